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

// The voxels of group `from` within `depth` mm (centre to centre) of group
// `other`, inside `region`: one side of a limb interface (thesis 4.2.1),
// as linear indices in grid order. The distance transform runs on the box
// around those voxels grown by `depth` and a voxel, which holds every voxel
// of `other` within reach of them, so the distances that decide are those
// of the whole grid.
std::vector<std::int64_t> interfaceVoxels(const LabelGrid& labels, Label from, Label other, double depth,
                                          const std::optional<Eigen::AlignedBox3d>& region) {
  const GridGeometry& g = labels.geometry();
  const auto side = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return labels.at(i, j, k) == from && (!region || region->contains(g.voxelCenter(i, j, k)));
  };
  Index3 lo{g.dims[0], g.dims[1], g.dims[2]}, hi{-1, -1, -1};
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i)
        if (side(i, j, k)) {
          const Index3 c{i, j, k};
          for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
        }
  if (hi[0] < 0) return {};
  const Index3 reach = padForDistance(g, depth, 1);
  GridGeometry box = g;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max<std::int64_t>(0, lo[a] - reach[a]);
    hi[a] = std::min(g.dims[a] - 1, hi[a] + reach[a]);
    box.dims[a] = hi[a] - lo[a] + 1;
  }
  box.origin = g.voxelCenter(lo[0], lo[1], lo[2]);
  std::vector<std::uint8_t> seeds(std::size_t(box.voxelCount()));
  for (std::int64_t k = 0; k < box.dims[2]; ++k)
    for (std::int64_t j = 0; j < box.dims[1]; ++j)
      for (std::int64_t i = 0; i < box.dims[0]; ++i)
        seeds[std::size_t(box.index(i, j, k))] = labels.at(lo[0] + i, lo[1] + j, lo[2] + k) == other;
  const ScalarGrid toOther = euclideanDistanceTransform(box, seeds).distance;
  std::vector<std::int64_t> within;
  for (std::int64_t k = 0; k < box.dims[2]; ++k)
    for (std::int64_t j = 0; j < box.dims[1]; ++j)
      for (std::int64_t i = 0; i < box.dims[0]; ++i)
        if (side(lo[0] + i, lo[1] + j, lo[2] + k) && !(toOther.at(i, j, k) > depth))
          within.push_back(g.index(lo[0] + i, lo[1] + j, lo[2] + k));
  return within;
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

  // Limb separation, first step: erode both sides of each interface (the
  // sides of all separations at once on the parallel loop).
  std::vector<std::uint8_t> eroded(core.size(), 0);
  {
    for (const LimbSeparation& s : options.separations)
      for (const Label group : {s.groupA, s.groupB})
        if (std::find(labels.labels().begin(), labels.labels().end(), group) == labels.labels().end())
          throw InputError("grid", "limb separation: label group " + std::to_string(group) + " has no voxels");
    std::vector<std::vector<std::int64_t>> sides(2 * options.separations.size());
    parallelFor(std::int64_t(sides.size()), 0, [&](std::int64_t task) {
      const LimbSeparation& s = options.separations[std::size_t(task / 2)];
      const bool fromA = task % 2 == 0;
      sides[std::size_t(task)] =
          interfaceVoxels(labels, fromA ? s.groupA : s.groupB, fromA ? s.groupB : s.groupA, options.erosionMm, s.region);
    });
    for (const std::vector<std::int64_t>& side : sides)
      for (const std::int64_t v : side)
        if (!eroded[std::size_t(v)]) {
          eroded[std::size_t(v)] = 1;
          ++result.report.erodedVoxels;
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
