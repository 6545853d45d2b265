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

// Distances from the voxels where at(v) holds to the nearest voxel where
// seed(v) holds, as (linear index, mm) in grid order. The transform runs on
// the box around the `at` voxels grown by `reachMm` and a voxel, which holds
// every seed closer than `reachMm` to them: the distances under `reachMm`
// are the whole grid's, the others at least `reachMm` (the whole grid when
// the reach is negative or not finite).
template <class At, class Seed>
std::vector<std::pair<std::int64_t, float>> distancesWithin(const GridGeometry& g, const At& at, const Seed& seed, double reachMm) {
  Index3 lo{g.dims[0], g.dims[1], g.dims[2]}, hi{-1, -1, -1};
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i)
        if (at(g.index(i, j, k), i, j, k)) {
          const Index3 c{i, j, k};
          for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
        }
  if (hi[0] < 0) return {};
  GridGeometry box = g;
  for (int a = 0; a < 3; ++a) {
    const double steps = std::ceil(reachMm / g.spacing[a]) + 1.0;
    const std::int64_t reach = reachMm >= 0.0 && steps < double(g.dims[a]) ? std::int64_t(steps) : g.dims[a];
    lo[a] = std::max<std::int64_t>(0, lo[a] - reach);
    hi[a] = std::min(g.dims[a] - 1, hi[a] + reach);
    box.dims[a] = hi[a] - lo[a] + 1;
  }
  box.origin = g.voxelCenter(lo[0], lo[1], lo[2]);
  std::vector<std::uint8_t> seeds(std::size_t(box.voxelCount()));
  for (std::int64_t k = 0; k < box.dims[2]; ++k)
    for (std::int64_t j = 0; j < box.dims[1]; ++j)
      for (std::int64_t i = 0; i < box.dims[0]; ++i)
        seeds[std::size_t(box.index(i, j, k))] = std::uint8_t(seed(g.index(lo[0] + i, lo[1] + j, lo[2] + k)));
  const ScalarGrid distance = euclideanDistanceTransform(box, seeds).distance;
  std::vector<std::pair<std::int64_t, float>> out;
  for (std::int64_t k = 0; k < box.dims[2]; ++k)
    for (std::int64_t j = 0; j < box.dims[1]; ++j)
      for (std::int64_t i = 0; i < box.dims[0]; ++i) {
        const std::int64_t v = g.index(lo[0] + i, lo[1] + j, lo[2] + k);
        if (at(v, lo[0] + i, lo[1] + j, lo[2] + k)) out.emplace_back(v, distance.at(i, j, k));
      }
  return out;
}

// Whether voxel (i, j, k) of g lies in the separation's region.
bool inRegion(const GridGeometry& g, const std::optional<Eigen::AlignedBox3d>& region, std::int64_t i, std::int64_t j,
              std::int64_t k) {
  return !region || region->contains(g.voxelCenter(i, j, k));
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
    // Each side: the voxels of one group within erosionMm (centre to
    // centre) of the other, inside the region (thesis 4.2.1).
    std::vector<std::vector<std::pair<std::int64_t, float>>> sides(2 * options.separations.size());
    parallelFor(std::int64_t(sides.size()), 0, [&](std::int64_t task) {
      const LimbSeparation& s = options.separations[std::size_t(task / 2)];
      const Label from = task % 2 == 0 ? s.groupA : s.groupB, other = task % 2 == 0 ? s.groupB : s.groupA;
      const Label* l = labels.data();
      sides[std::size_t(task)] = distancesWithin(
          padded, [&](std::int64_t v, std::int64_t i, std::int64_t j, std::int64_t k) { return l[v] == from && inRegion(padded, s.region, i, j, k); },
          [&](std::int64_t v) { return l[v] == other; }, options.erosionMm);
    });
    for (const auto& side : sides)
      for (const auto& [v, d] : side)
        if (!(d > options.erosionMm) && !eroded[std::size_t(v)]) {
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
  // The distances to the other group (within the reach where the slope
  // bounds the radius) and to the whole core are independent: they are
  // computed at once on the parallel loop.
  ScalarGrid radius(padded, float(options.dilationMm));
  const double slopeReach = options.dilationMm / options.separationSlope;
  DistanceTransform toCore;
  std::vector<std::vector<std::pair<std::int64_t, float>>> toOther(2 * options.separations.size());
  parallelFor(std::int64_t(toOther.size()) + 1, 0, [&](std::int64_t task) {
    if (task == std::int64_t(toOther.size())) {
      toCore = euclideanDistanceTransform(padded, core, !options.separations.empty());
      return;
    }
    const LimbSeparation& s = options.separations[std::size_t(task / 2)];
    const Label self = task % 2 == 0 ? s.groupA : s.groupB, other = task % 2 == 0 ? s.groupB : s.groupA;
    const Label* l = labels.data();
    toOther[std::size_t(task)] = distancesWithin(
        padded,
        [&](std::int64_t v, std::int64_t i, std::int64_t j, std::int64_t k) { return l[v] == self && core[std::size_t(v)] && inRegion(padded, s.region, i, j, k); },
        [&](std::int64_t v) { return l[v] == other && core[std::size_t(v)]; }, slopeReach);
  });
  for (const auto& side : toOther)
    for (const auto& [v, d] : side)
      radius.values[std::size_t(v)] = std::min(radius.values[std::size_t(v)], float(options.separationSlope * double(d)));
  toOther.clear();
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
