#include "geometry/remesh/sizing_field.h"

#include "geometry/distance_transform.h"
#include "geometry/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <tuple>
#include <utility>
#include <vector>

namespace vox::remesh {

SizingField::SizingField(ScalarGrid lengths, const Eigen::Matrix3d& meshToGrid)
    : lengths_(std::move(lengths)), meshToGrid_(meshToGrid) {
  checkSizingGrid(lengths_, "sizing field");
  const auto [lo, hi] = std::minmax_element(lengths_.values.begin(), lengths_.values.end());
  minimum_ = double(*lo);
  maximum_ = double(*hi);
}

void checkSizingGrid(const ScalarGrid& lengths, const std::string& source) {
  if (lengths.values.empty()) throw InputError(source, "the sizing grid is empty");
  for (std::size_t v = 0; v < lengths.values.size(); ++v) {
    const float l = lengths.values[v];
    if (std::isfinite(l) && l > 0.0f) continue;
    const Index3 ijk = lengths.geometry.ijk(std::int64_t(v));
    char text[160];
    std::snprintf(text, sizeof text, "voxel %zu (%lld, %lld, %lld) holds %g: sizes must be finite and positive (mm)", v,
                  (long long)ijk[0], (long long)ijk[1], (long long)ijk[2], double(l));
    throw InputError(source, text);
  }
}

namespace {

// d / largest, clamped to [0, 1]; 0 everywhere when there is no distance to
// scale by (every domain voxel on an interface).
void normalize(ScalarGrid& d, float largest) {
  for (float& x : d.values) x = largest > 0.0f && std::isfinite(largest) ? std::min(1.0f, x / largest) : 0.0f;
}

}  // namespace

ScalarGrid normalizedInterfaceDistance(const LabelGrid& grid) {
  const GridGeometry& g = grid.geometry();
  std::vector<std::uint8_t> seeds(std::size_t(g.voxelCount()), 0);
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const Label l = grid.at(i, j, k);
        const bool interface = grid.atOr(i - 1, j, k) != l || grid.atOr(i + 1, j, k) != l || grid.atOr(i, j - 1, k) != l ||
                               grid.atOr(i, j + 1, k) != l || grid.atOr(i, j, k - 1) != l || grid.atOr(i, j, k + 1) != l;
        if (interface) seeds[std::size_t(g.index(i, j, k))] = 1;
      }
  ScalarGrid d = euclideanDistanceTransform(g, seeds).distance;
  // Normalized over the labelled voxels (the domain), as the thesis
  // normalizes over the meshed region: the background far from the body
  // does not set the scale.
  float largest = 0.0f;
  for (std::size_t v = 0; v < d.values.size(); ++v)
    if (grid.labels()[v] > 0) largest = std::max(largest, d.values[v]);
  normalize(d, largest);
  return d;
}

namespace {

void checkLengths(double boundaryLength, double interiorLength) {
  if (!(boundaryLength > 0.0) || !std::isfinite(boundaryLength))
    throw InputError("sizing field", "the boundary length l_B must be positive");
  if (!(interiorLength >= boundaryLength) || !std::isfinite(interiorLength))
    throw InputError("sizing field", "the interior length l_I must be at least the boundary length l_B");
}

// Eq. 2.2 applied to D in place.
SizingField lengthsFromDistance(ScalarGrid d, double boundaryLength, double interiorLength,
                                const Eigen::Matrix3d& meshToGrid = Eigen::Matrix3d::Identity()) {
  for (float& x : d.values) x = float((interiorLength - boundaryLength) * double(x) + boundaryLength);
  return SizingField(std::move(d), meshToGrid);
}

}  // namespace

SizingField interfaceSizingField(const LabelGrid& grid, double boundaryLength, double interiorLength) {
  checkLengths(boundaryLength, interiorLength);
  return lengthsFromDistance(normalizedInterfaceDistance(grid), boundaryLength, interiorLength);
}

SizingField interfaceSizingField(const TetMesh& mesh, double boundaryLength, double interiorLength) {
  checkLengths(boundaryLength, interiorLength);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t)
    if (mesh.labels[t] > 0)
      for (std::int32_t v : mesh.tets[t]) {
        lo = lo.cwiseMin(mesh.positions[std::size_t(v)]);
        hi = hi.cwiseMax(mesh.positions[std::size_t(v)]);
      }
  if (!(lo.array() <= hi.array()).all()) throw InputError("sizing field", "the mesh has no domain tet (label > 0)");
  // Voxels of l_B / 2, one more around the box, fewer if there would be too many.
  double h = 0.5 * boundaryLength;
  const Eigen::Vector3d extent = hi - lo;
  auto voxels = [&](double step) {
    double n = 1.0;
    for (int a = 0; a < 3; ++a) n *= std::floor(extent[a] / step) + 3.0;
    return n;
  };
  while (voxels(h) > double(kMaxSizingVoxels)) h *= 1.25;
  GridGeometry g;
  for (int a = 0; a < 3; ++a) g.dims[a] = std::int64_t(std::floor(extent[a] / h)) + 3;
  g.spacing = Eigen::Vector3d::Constant(h);
  g.origin = lo - Eigen::Vector3d::Constant(h);

  // Interface facets: sorted vertex triples with the label on each side.
  struct Facet {
    std::array<std::int32_t, 3> v;
    std::int32_t label;
  };
  std::vector<Facet> facets;
  facets.reserve(4 * mesh.tets.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      const Tri f = tetFace(mesh.tets[t], k);
      std::array<std::int32_t, 3> v{f[0], f[1], f[2]};
      std::sort(v.begin(), v.end());
      facets.push_back({v, std::max(mesh.labels[t], 0)});
    }
  std::sort(facets.begin(), facets.end(), [](const Facet& x, const Facet& y) { return std::tie(x.v, x.label) < std::tie(y.v, y.label); });
  std::vector<std::uint8_t> seeds(std::size_t(g.voxelCount()), 0);
  auto seed = [&](const Eigen::Vector3d& p) {
    Index3 ijk;
    if (g.voxelAt(p, ijk)) seeds[std::size_t(g.index(ijk[0], ijk[1], ijk[2]))] = 1;
  };
  for (std::size_t i = 0; i < facets.size();) {
    std::size_t j = i + 1;
    while (j < facets.size() && facets[j].v == facets[i].v) ++j;
    const std::int32_t other = j - i > 1 ? facets[i + 1].label : 0;
    if (facets[i].label != other) {
      // Points at most half a voxel apart on the facet.
      const Eigen::Vector3d& a = mesh.positions[std::size_t(facets[i].v[0])];
      const Eigen::Vector3d& b = mesh.positions[std::size_t(facets[i].v[1])];
      const Eigen::Vector3d& c = mesh.positions[std::size_t(facets[i].v[2])];
      const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
      const int n = std::max(1, int(std::ceil(2.0 * longest / h)));
      for (int x = 0; x <= n; ++x)
        for (int y = 0; x + y <= n; ++y)
          seed(a + (double(x) / n) * (b - a) + (double(y) / n) * (c - a));
    }
    i = j;
  }
  ScalarGrid d = euclideanDistanceTransform(g, seeds).distance;
  float largest = 0.0f;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t)
    if (mesh.labels[t] > 0)
      for (std::int32_t v : mesh.tets[t]) largest = std::max(largest, d.sample(mesh.positions[std::size_t(v)]));
  normalize(d, largest);
  return lengthsFromDistance(std::move(d), boundaryLength, interiorLength);
}

}  // namespace vox::remesh
