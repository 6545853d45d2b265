#include "geometry/body_projection.h"

#include "geometry/parallel.h"
#include "geometry/world_frame.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace vox {

namespace {

// Largest raster of an oblique grid's view (the pixel grows beyond it).
constexpr double kMaxRasterPixels = double(std::int64_t(1) << 24);

std::int64_t occupied(const std::vector<std::uint8_t>& cells) { return std::accumulate(cells.begin(), cells.end(), std::int64_t(0)); }

}  // namespace

BodyProjectionAccumulator::BodyProjectionAccumulator(const GridGeometry& g)
    : geometry_(g),
      axisAligned_(vox::axisAligned(g)),
      minWorldZ_(std::numeric_limits<double>::infinity()),
      maxWorldZ_(-std::numeric_limits<double>::infinity()) {
  const Index3& n = g.dims;
  if (axisAligned_) {
    columns_[0].assign(std::size_t(n[1] * n[2]), 0);
    columns_[1].assign(std::size_t(n[0] * n[2]), 0);
    columns_[2].assign(std::size_t(n[0] * n[1]), 0);
    for (int w = 0; w < 3; ++w) g.direction.row(w).cwiseAbs().maxCoeff(&gridAxisOfWorld_[w]);
    return;
  }
  // The world-frame box of the grid bounds every view's raster.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? g.boxMax().x() : g.boxMin().x(), (c & 2) ? g.boxMax().y() : g.boxMin().y(),
                                 (c & 4) ? g.boxMax().z() : g.boxMin().z());
    const Eigen::Vector3d w = gridToWorld(g, corner);
    lo = lo.cwiseMin(w);
    hi = hi.cwiseMax(w);
  }
  for (int view = 0; view < 3; ++view) {
    Raster& r = rasters_[view];
    r.u = view == 0 ? 1 : 0;
    r.v = view == 2 ? 1 : 2;
    const Eigen::Vector2d extent(hi[r.u] - lo[r.u], hi[r.v] - lo[r.v]);
    r.pixel = 0.25 * g.spacing.minCoeff();
    const double pixels = (extent.x() / r.pixel + 1.0) * (extent.y() / r.pixel + 1.0);
    if (pixels > kMaxRasterPixels) r.pixel *= std::sqrt(pixels / kMaxRasterPixels);
    r.lo = Eigen::Vector2d(lo[r.u], lo[r.v]);
    r.width = std::int64_t(std::ceil(extent.x() / r.pixel)) + 1;
    r.height = std::int64_t(std::ceil(extent.y() / r.pixel)) + 1;
    r.covered.assign(std::size_t(r.width * r.height), 0);
    std::array<Eigen::Vector2d, 3> half;
    for (int a = 0; a < 3; ++a) half[a] = 0.5 * g.spacing[a] * Eigen::Vector2d(g.direction(r.u, a), g.direction(r.v, a));
    r.halfBox.setZero();
    for (const Eigen::Vector2d& h : half) r.halfBox += h.cwiseAbs();
    // The hexagon's edges run along the projected half-axes; an axis along
    // the view projects to a point and contributes no edge.
    for (const Eigen::Vector2d& h : half) {
      if (h.norm() < 1e-9 * g.spacing.maxCoeff()) continue;
      const Eigen::Vector2d normal = Eigen::Vector2d(-h.y(), h.x()).normalized();
      double support = 0.0;
      for (const Eigen::Vector2d& k : half) support += std::abs(normal.dot(k));
      r.normals.push_back(normal);
      r.support.push_back(support);
    }
  }
}

void BodyProjectionAccumulator::splat(Raster& r, const Eigen::Vector3d& centre) const {
  const Eigen::Vector2d c(centre[r.u], centre[r.v]);
  const Eigen::Vector2d first = ((c - r.halfBox - r.lo) / r.pixel).array() - 0.5;
  const Eigen::Vector2d last = ((c + r.halfBox - r.lo) / r.pixel).array() - 0.5;
  const std::int64_t x0 = std::max<std::int64_t>(0, std::int64_t(std::ceil(first.x())));
  const std::int64_t y0 = std::max<std::int64_t>(0, std::int64_t(std::ceil(first.y())));
  const std::int64_t x1 = std::min<std::int64_t>(r.width - 1, std::int64_t(std::floor(last.x())));
  const std::int64_t y1 = std::min<std::int64_t>(r.height - 1, std::int64_t(std::floor(last.y())));
  for (std::int64_t y = y0; y <= y1; ++y)
    for (std::int64_t x = x0; x <= x1; ++x) {
      std::uint8_t& cell = r.covered[std::size_t(x + r.width * y)];
      if (cell) continue;
      const Eigen::Vector2d q = r.lo + r.pixel * Eigen::Vector2d(double(x) + 0.5, double(y) + 0.5) - c;
      bool inside = true;
      for (std::size_t e = 0; e < r.normals.size() && inside; ++e) inside = std::abs(r.normals[e].dot(q)) <= r.support[e];
      cell = inside;
    }
}

void BodyProjectionAccumulator::addSlices(std::int64_t k0, std::int64_t count, const Label* labels) {
  const GridGeometry& g = geometry_;
  const std::int64_t nx = g.dims[0], ny = g.dims[1];
  // World z of voxel centres is linear in (i, j, k).
  const Eigen::Vector3d zRate = g.direction.row(2).transpose().cwiseProduct(g.spacing);
  const double z0 = g.direction.row(2).dot(g.origin);
  std::vector<Eigen::Vector3d> centres;
  for (std::int64_t s = 0; s < count; ++s) {
    const std::int64_t k = k0 + s;
    const Label* slice = labels + s * nx * ny;
    for (std::int64_t j = 0; j < ny; ++j)
      for (std::int64_t i = 0; i < nx; ++i) {
        if (slice[i + nx * j] == 0) continue;
        ++foreground_;
        const double z = z0 + zRate.x() * double(i) + zRate.y() * double(j) + zRate.z() * double(k);
        minWorldZ_ = std::min(minWorldZ_, z);
        maxWorldZ_ = std::max(maxWorldZ_, z);
        if (axisAligned_) {
          columns_[0][std::size_t(j + ny * k)] = 1;
          columns_[1][std::size_t(i + nx * k)] = 1;
          columns_[2][std::size_t(i + nx * j)] = 1;
        } else {
          centres.push_back(gridToWorld(g, g.voxelCenter(i, j, k)));
        }
      }
  }
  if (centres.empty()) return;
  parallelFor(3, 3, [&](std::int64_t view) {
    for (const Eigen::Vector3d& c : centres) splat(rasters_[std::size_t(view)], c);
  });
}

BodyProjection BodyProjectionAccumulator::result() const {
  const GridGeometry& g = geometry_;
  BodyProjection p;
  p.foregroundVoxels = foreground_;
  if (foreground_ == 0) return p;
  p.heightMm = maxWorldZ_ - minWorldZ_ + g.direction.row(2).cwiseAbs().dot(g.spacing);
  std::array<double, 3> area{};
  if (axisAligned_) {
    for (int w = 0; w < 3; ++w) {
      const int a = gridAxisOfWorld_[w];
      area[w] = double(occupied(columns_[a])) * g.spacing.prod() / g.spacing[a];
    }
  } else {
    p.exact = false;
    for (int w = 0; w < 3; ++w) area[w] = double(occupied(rasters_[w].covered)) * rasters_[w].pixel * rasters_[w].pixel;
  }
  p.sideMm2 = area[0];
  p.frontMm2 = area[1];
  p.topMm2 = area[2];
  return p;
}

BodyProjection bodyProjection(const LabelGrid& grid) {
  BodyProjectionAccumulator accumulator(grid.geometry());
  accumulator.addSlices(0, grid.dims()[2], grid.data());
  return accumulator.result();
}

}  // namespace vox
