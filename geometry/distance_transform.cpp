#include "geometry/distance_transform.h"

#include "geometry/cancellation.h"
#include "geometry/parallel.h"

#include <cmath>
#include <limits>

namespace vox {

GridGeometry padGeometry(const GridGeometry& geometry, const Index3& pad) {
  GridGeometry g = geometry;
  for (int a = 0; a < 3; ++a) {
    g.dims[a] = geometry.dims[a] + 2 * pad[a];
    g.origin[a] = geometry.origin[a] - double(pad[a]) * geometry.spacing[a];
  }
  return g;
}

Index3 padForDistance(const GridGeometry& geometry, double distanceMm, std::int64_t margin) {
  Index3 pad{};
  for (int a = 0; a < 3; ++a) pad[a] = std::int64_t(std::ceil(std::max(0.0, distanceMm) / geometry.spacing[a])) + margin;
  return pad;
}

LabelGrid padLabels(const LabelGrid& grid, const GridGeometry& padded) {
  LabelGrid out(padded, 0);
  const GridGeometry& g = grid.geometry();
  Index3 offset{};
  for (int a = 0; a < 3; ++a) offset[a] = std::int64_t(std::llround((g.origin[a] - padded.origin[a]) / g.spacing[a]));
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j) {
      const Label* src = grid.data() + g.index(0, j, k);
      Label* dst = out.data() + padded.index(offset[0], j + offset[1], k + offset[2]);
      std::copy(src, src + g.dims[0], dst);
    }
  return out;
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// One pass of the separable transform along a line of n samples spaced h
// apart: out[p] = min_q f[q] + (h (p - q))^2, and the argmin's feature.
// v, z and the outputs are scratch buffers of size n (z: n + 1).
struct LinePass {
  std::vector<double> f, out;
  std::vector<std::int64_t> featureIn, featureOut;
  std::vector<std::int64_t> v;
  std::vector<double> z;

  explicit LinePass(std::int64_t n)
      : f(std::size_t(n)), out(std::size_t(n)), featureIn(std::size_t(n)), featureOut(std::size_t(n)),
        v(std::size_t(n)), z(std::size_t(n) + 1) {}

  void run(std::int64_t n, double h, bool withNearest) {
    const double h2 = h * h;
    std::int64_t k = -1;
    for (std::int64_t q = 0; q < n; ++q) {
      if (f[q] == kInf) continue;
      double s = -kInf;
      while (k >= 0) {
        const std::int64_t r = v[k];
        // Abscissa (in samples) where the parabolas rooted at r and q meet.
        s = ((f[q] + h2 * double(q) * double(q)) - (f[r] + h2 * double(r) * double(r))) / (2.0 * h2 * double(q - r));
        if (s <= z[k]) --k;
        else break;
      }
      ++k;
      v[k] = q;
      z[k] = k == 0 ? -kInf : s;
      z[k + 1] = kInf;
    }
    if (k < 0) {
      std::fill(out.begin(), out.begin() + n, kInf);
      if (withNearest) std::fill(featureOut.begin(), featureOut.begin() + n, -1);
      return;
    }
    k = 0;
    for (std::int64_t p = 0; p < n; ++p) {
      while (z[k + 1] < double(p)) ++k;
      const double d = double(p - v[k]) * h;
      out[p] = f[v[k]] + d * d;
      if (withNearest) featureOut[p] = featureIn[v[k]];
    }
  }
};

}  // namespace

DistanceTransform euclideanDistanceTransform(const GridGeometry& geometry, const std::vector<std::uint8_t>& seeds,
                                             bool withNearest) {
  const std::int64_t n = geometry.voxelCount();
  // Squared distances between passes, in double: float would lose whole
  // mm^2 on grids a metre wide.
  std::vector<double> sq(static_cast<std::size_t>(n));
  std::vector<std::int64_t> nearest;
  for (std::int64_t i = 0; i < n; ++i) sq[i] = seeds[i] ? 0.0 : kInf;
  if (withNearest) {
    nearest.resize(std::size_t(n));
    for (std::int64_t i = 0; i < n; ++i) nearest[i] = seeds[i] ? i : -1;
  }

  const std::int64_t dims[3] = {geometry.dims[0], geometry.dims[1], geometry.dims[2]};
  const std::int64_t stride[3] = {1, dims[0], dims[0] * dims[1]};
  for (int axis = 0; axis < 3; ++axis) {
    const std::int64_t len = dims[axis];
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    // The lines of a pass are independent: planes of them on the parallel
    // loop, each line computed as on one thread.
    parallelRanges(dims[a2], workerThreads(0), [&](std::int64_t begin, std::int64_t end) {
      LinePass pass(len);
      for (std::int64_t u = begin; u < end; ++u) {
        throwIfCancelled();
        for (std::int64_t t = 0; t < dims[a1]; ++t) {
          const std::int64_t base = t * stride[a1] + u * stride[a2];
          for (std::int64_t p = 0; p < len; ++p) {
            pass.f[p] = sq[base + p * stride[axis]];
            if (withNearest) pass.featureIn[p] = nearest[base + p * stride[axis]];
          }
          pass.run(len, geometry.spacing[axis], withNearest);
          for (std::int64_t p = 0; p < len; ++p) {
            sq[base + p * stride[axis]] = pass.out[p];
            if (withNearest) nearest[base + p * stride[axis]] = pass.featureOut[p];
          }
        }
      }
    }, 1);
  }

  DistanceTransform result;
  result.distance.geometry = geometry;
  result.distance.values.resize(std::size_t(n));
  for (std::int64_t i = 0; i < n; ++i) result.distance.values[i] = float(std::sqrt(sq[i]));
  result.nearest = std::move(nearest);
  return result;
}

}  // namespace vox
