#include "geometry/deform/cage/cage_builder.h"

#include "geometry/distance_transform.h"
#include "geometry/deform/cage/restricted_delaunay.h"
#include "geometry/error.h"
#include "geometry/parallel.h"
#include "geometry/progress.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace vox {

namespace {

std::vector<std::uint8_t> maskOf(const LabelGrid& labels, Label value) {
  std::vector<std::uint8_t> mask(labels.labels().size());
  std::transform(labels.labels().begin(), labels.labels().end(), mask.begin(), [value](Label l) { return std::uint8_t(l == value); });
  return mask;
}

// Marks the voxels of group `from` within `depth` mm (centre to centre) of
// the other group, given as the distance to it, inside `region`: one side
// of a limb interface (thesis 4.2.1). Returns how many were newly marked.
std::int64_t markInterface(const LabelGrid& labels, Label from, const ScalarGrid& distanceToOther, double depth,
                           const std::optional<Eigen::AlignedBox3d>& region, std::vector<std::uint8_t>& eroded) {
  const GridGeometry& g = labels.geometry();
  std::int64_t count = 0;
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const std::int64_t v = g.index(i, j, k);
        if (labels.labels()[v] != from || eroded[v] || distanceToOther.values[v] > depth) continue;
        if (region && !region->contains(g.voxelCenter(i, j, k))) continue;
        eroded[v] = 1;
        ++count;
      }
  return count;
}

// Distance to the seeds of each mask, the transforms run at once on the
// parallel loop (each is sequential, so the values are the same on any
// thread count).
std::vector<ScalarGrid> distancesTo(const GridGeometry& geometry, const std::vector<std::vector<std::uint8_t>>& masks) {
  std::vector<ScalarGrid> to(masks.size());
  parallelFor(std::int64_t(masks.size()), 0, [&](std::int64_t i) {
    to[std::size_t(i)] = euclideanDistanceTransform(geometry, masks[std::size_t(i)]).distance;
  });
  return to;
}

}  // namespace

CageResult buildCage(const LabelGrid& groups, const CageOptions& options) {
  if (options.targetVertices < 4) throw InputError("cage", "target vertex count must be at least 4");
  if (!(options.dilationMm >= 0.0)) throw InputError("cage", "dilation must be a non-negative distance in mm");
  CageResult result;
  reportProgress("cage", 0.0);

  const GridGeometry padded = padGeometry(groups.geometry(), padForDistance(groups.geometry(), options.dilationMm, 2));
  const LabelGrid labels = padLabels(groups, padded);
  std::vector<std::uint8_t> core(labels.labels().size());
  std::transform(labels.labels().begin(), labels.labels().end(), core.begin(), [](Label l) { return std::uint8_t(l != 0); });
  if (std::find(core.begin(), core.end(), 1) == core.end()) throw InputError("grid", "has no foreground voxels to build a cage around");

  // Limb separation, first step: erode both sides of each interface.
  std::vector<std::uint8_t> eroded(core.size(), 0);
  {
    std::vector<std::vector<std::uint8_t>> masks;  // groupA, groupB of each separation
    for (const LimbSeparation& s : options.separations)
      for (const Label group : {s.groupA, s.groupB}) {
        masks.push_back(maskOf(labels, group));
        if (std::find(masks.back().begin(), masks.back().end(), 1) == masks.back().end())
          throw InputError("grid", "limb separation: label group " + std::to_string(group) + " has no voxels");
      }
    const std::vector<ScalarGrid> to = distancesTo(padded, masks);
    for (std::size_t i = 0; i < options.separations.size(); ++i) {
      const LimbSeparation& s = options.separations[i];
      result.report.erodedVoxels += markInterface(labels, s.groupA, to[2 * i + 1], options.erosionMm, s.region, eroded);
      result.report.erodedVoxels += markInterface(labels, s.groupB, to[2 * i], options.erosionMm, s.region, eroded);
    }
  }
  for (std::size_t v = 0; v < core.size(); ++v) core[v] &= std::uint8_t(!eroded[v]);
  if (std::find(core.begin(), core.end(), 1) == core.end())
    throw InputError("cage", "limb separation erodes the whole foreground (erosion " + std::to_string(options.erosionMm) + " mm)");
  reportProgress("cage", 0.1);

  // Dilation radius of each kept voxel: dilationMm, except that inside a
  // separation region a voxel of one group grows by at most
  // separationSlope times its distance to the other group's kept voxels.
  // With a slope under 1/2 two such balls from opposite groups never meet,
  // so the dilated groups stay apart.
  // The distances to each kept group and to the whole core are independent:
  // they are computed at once on the parallel loop.
  ScalarGrid radius(padded, float(options.dilationMm));
  std::vector<std::vector<std::uint8_t>> kept;  // groupA, groupB of each separation, kept voxels
  for (const LimbSeparation& s : options.separations)
    for (const Label group : {s.groupA, s.groupB}) {
      kept.push_back(maskOf(labels, group));
      for (std::size_t v = 0; v < core.size(); ++v) kept.back()[v] &= core[v];
    }
  DistanceTransform toCore;
  std::vector<ScalarGrid> toKept(kept.size());
  parallelFor(std::int64_t(kept.size()) + 1, 0, [&](std::int64_t task) {
    if (task == std::int64_t(kept.size())) toCore = euclideanDistanceTransform(padded, core, !options.separations.empty());
    else toKept[std::size_t(task)] = euclideanDistanceTransform(padded, kept[std::size_t(task)]).distance;
  });
  for (std::size_t i = 0; i < options.separations.size(); ++i) {
    const LimbSeparation& s = options.separations[i];
    for (const auto& [self, other] : {std::pair{2 * i, 2 * i + 1}, std::pair{2 * i + 1, 2 * i}}) {
      const std::vector<std::uint8_t>& mask = kept[self];
      const ScalarGrid& toOther = toKept[other];
      for (std::int64_t k = 0; k < padded.dims[2]; ++k)
        for (std::int64_t j = 0; j < padded.dims[1]; ++j)
          for (std::int64_t i = 0; i < padded.dims[0]; ++i) {
            const std::int64_t v = padded.index(i, j, k);
            if (!mask[v] || (s.region && !s.region->contains(padded.voxelCenter(i, j, k)))) continue;
            radius.values[v] = std::min(radius.values[v], float(options.separationSlope * double(toOther.values[v])));
          }
    }
  }
  kept.clear();
  toKept.clear();
  reportProgress("cage", 0.2);

  // Cage field, negative inside: the union of the balls, approximated
  // through each voxel's nearest kept voxel (distance to it minus its
  // radius; exact where the radius is constant).
  ScalarGrid field = toCore.distance;
  for (std::size_t v = 0; v < field.values.size(); ++v)
    field.values[v] -= toCore.nearest.empty() ? float(options.dilationMm) : radius.values[std::size_t(toCore.nearest[v])];
  reportProgress("cage", 0.3);

  LabelGrid inside(padded, 0);
  for (std::size_t v = 0; v < field.values.size(); ++v) inside.labels()[v] = Label(field.values[v] < 0.0f);
  SampledDomain domain;
  domain.labels = &inside;
  domain.labelAt = [&field](const Eigen::Vector3d& p) { return int(field.sample(p) < 0.0f); };
  const TriMesh dense = restrictedDelaunaySurface(domain, {30.0, options.facetSizeMm, options.facetDistanceMm});
  result.report.meshedVertices = dense.vertexCount();
  reportProgress("cage", 0.7);

  result.cage = simplifyQem(dense, options.targetVertices);
  reportProgress("cage", 0.8);
  result.report.check = checkSurface(result.cage);
  result.report.foregroundOutside = countForegroundOutside(result.cage, groups);
  reportProgress("cage", 1.0);
  return result;
}

}  // namespace vox
