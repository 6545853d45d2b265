#include "geometry/raster/lattice_tets.h"

#include "geometry/parallel.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace vox {

namespace {

// Candidate boxes are widened by this much (lattice units) so that rounding
// of the vertex coordinates never drops a point that passes the plane test;
// the plane test alone decides.
constexpr double kBoxMargin = 1e-6;
// A tet whose volume is below this fraction of its longest edge cubed holds
// no lattice point.
constexpr double kDegenerateVolume = 1e-12;
// Lattice coordinates beyond this are not scan-converted (anchors are int32).
constexpr double kMaxCoordinate = 1e9;

std::int32_t nearestLatticePoint(double c) { return std::int32_t(std::floor(c + 0.5)); }

}  // namespace

Eigen::Vector4d LatticeTet::barycentric(std::int32_t x, std::int32_t y, std::int32_t z) const {
  Eigen::Vector4d f;
  for (int k = 0; k < 4; ++k) f[k] = planeValue(k, x, y, z);
  const double sum = f.sum();
  return sum != 0.0 ? Eigen::Vector4d(f / sum) : Eigen::Vector4d::Constant(0.25);
}

std::vector<LatticeTet> latticeTets(const GridGeometry& lattice, const std::vector<Eigen::Vector3d>& positions,
                                    const std::vector<Tet>& tets) {
  // Each tet's entry depends on its own vertices alone: on the parallel loop.
  std::vector<Eigen::Vector3d> q(positions.size());
  parallelRanges(std::int64_t(positions.size()), workerThreads(0), [&](std::int64_t i0, std::int64_t i1) {
    for (std::int64_t i = i0; i < i1; ++i) q[std::size_t(i)] = latticeCoordinates(lattice, positions[std::size_t(i)]);
  }, std::int64_t(1) << 14);

  std::vector<LatticeTet> out(tets.size());
  parallelRanges(std::int64_t(tets.size()), workerThreads(0), [&](std::int64_t t0, std::int64_t t1) {
    for (std::int64_t t = t0; t < t1; ++t) {
      const Tet& tet = tets[std::size_t(t)];
      LatticeTet& lt = out[std::size_t(t)];
      const Eigen::Vector3d& p0 = q[std::size_t(tet[0])];
      double longest = 0.0;
      Eigen::Vector3d lo = p0, hi = p0;
      for (int i = 0; i < 4; ++i) {
        const Eigen::Vector3d& pi = q[std::size_t(tet[i])];
        lo = lo.cwiseMin(pi);
        hi = hi.cwiseMax(pi);
        for (int j = i + 1; j < 4; ++j) longest = std::max(longest, (q[std::size_t(tet[j])] - pi).norm());
      }
      const double volume6 = (q[std::size_t(tet[1])] - p0).dot((q[std::size_t(tet[2])] - p0).cross(q[std::size_t(tet[3])] - p0));
      if (!(std::abs(volume6) > kDegenerateVolume * longest * longest * longest)) continue;
      if (!(lo.cwiseAbs().maxCoeff() < kMaxCoordinate && hi.cwiseAbs().maxCoeff() < kMaxCoordinate)) continue;

      for (int k = 0; k < 4; ++k) {
        std::array<std::int32_t, 3> face{};
        for (int i = 0, n = 0; i < 4; ++i)
          if (i != k) face[std::size_t(n++)] = tet[std::size_t(i)];
        std::sort(face.begin(), face.end());
        const Eigen::Vector3d& a = q[std::size_t(face[0])];
        const Eigen::Vector3d n = (q[std::size_t(face[1])] - a).cross(q[std::size_t(face[2])] - a);
        // The canonical normal points into this tet or out of it: the sign of
        // its value at the opposite vertex (+-6|t|, well away from zero here).
        const double sign = n.dot(q[std::size_t(tet[std::size_t(k)])] - a) > 0.0 ? 1.0 : -1.0;
        const LatticeIndex anchor{nearestLatticePoint(a.x()), nearestLatticePoint(a.y()), nearestLatticePoint(a.z())};
        const Eigen::Vector3d toAnchor(double(anchor[0]) - a.x(), double(anchor[1]) - a.y(), double(anchor[2]) - a.z());
        lt.normal[std::size_t(k)] = sign * n;
        lt.offset[std::size_t(k)] = sign * n.dot(toAnchor);
        lt.anchor[std::size_t(k)] = anchor;
      }
      for (int axis = 0; axis < 3; ++axis) {
        const double first = std::ceil(lo[axis] - kBoxMargin);
        const double last = std::floor(hi[axis] + kBoxMargin);
        lt.lo[std::size_t(axis)] = std::int32_t(std::max(first, 0.0));
        lt.hi[std::size_t(axis)] = std::int32_t(std::min(last, double(lattice.dims[std::size_t(axis)] - 1)));
      }
    }
  }, std::int64_t(1) << 12);
  return out;
}

bool rowSpan(const LatticeTet& t, std::int32_t y, std::int32_t z, std::int32_t& x0, std::int32_t& x1) {
  if (y < t.lo[1] || y > t.hi[1] || z < t.lo[2] || z > t.hi[2]) return false;
  std::int32_t lo = t.lo[0], hi = t.hi[0];
  for (int k = 0; k < 4 && lo <= hi; ++k) {
    const Eigen::Vector3d& n = t.normal[std::size_t(k)];
    const LatticeIndex& a = t.anchor[std::size_t(k)];
    const double rest = n.y() * double(y - a[1]) + n.z() * double(z - a[2]) + t.offset[std::size_t(k)];
    const auto passes = [&](std::int32_t x) { return n.x() * double(x - a[0]) + rest >= 0.0; };
    if (n.x() > 0.0) {
      // Passes from some x on: start from the real root, then step to the
      // exact first passing point (the evaluation is monotone in x).
      const double root = double(a[0]) - rest / n.x();
      std::int32_t c = root > double(lo) ? (root < double(hi) + 1.0 ? std::int32_t(std::ceil(root)) : hi + 1) : lo;
      while (c > lo && passes(c - 1)) --c;
      while (c <= hi && !passes(c)) ++c;
      lo = c;
    } else if (n.x() < 0.0) {
      const double root = double(a[0]) - rest / n.x();
      std::int32_t c = root < double(hi) ? (root > double(lo) - 1.0 ? std::int32_t(std::floor(root)) : lo - 1) : hi;
      while (c < hi && passes(c + 1)) ++c;
      while (c >= lo && !passes(c)) --c;
      hi = c;
    } else if (!passes(lo)) {
      return false;
    }
  }
  if (lo > hi) return false;
  x0 = lo;
  x1 = hi;
  return true;
}

template <int N>
TetAffineMap<N> tetAffineMap(const LatticeTet& t, const std::array<Eigen::Matrix<double, N, 1>, 4>& values) {
  TetAffineMap<N> m;
  if (t.empty()) return m;
  // Anchor: the lattice point nearest the centroid of the four face anchors,
  // which lie within half a lattice step of the tet's vertices.
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const LatticeIndex& a : t.anchor) c += Eigen::Vector3d(double(a[0]), double(a[1]), double(a[2]));
  c /= 4.0;
  m.anchor = {nearestLatticePoint(c.x()), nearestLatticePoint(c.y()), nearestLatticePoint(c.z())};
  // lambda_k(q) = f_k(q) / sum_j f_j, and sum_j f_j is constant (6|t|).
  Eigen::Vector4d f;
  for (int k = 0; k < 4; ++k) f[k] = t.planeValue(k, m.anchor[0], m.anchor[1], m.anchor[2]);
  const double sum = f.sum();
  for (int k = 0; k < 4; ++k) {
    m.linear += values[std::size_t(k)] * t.normal[std::size_t(k)].transpose() / sum;
    m.atAnchor += values[std::size_t(k)] * (f[k] / sum);
  }
  return m;
}

template TetAffineMap<1> tetAffineMap<1>(const LatticeTet&, const std::array<Eigen::Matrix<double, 1, 1>, 4>&);
template TetAffineMap<3> tetAffineMap<3>(const LatticeTet&, const std::array<Eigen::Matrix<double, 3, 1>, 4>&);

SlabTets slabTets(const std::vector<LatticeTet>& tets, std::int32_t z0, std::int32_t z1) {
  SlabTets slab;
  slab.z0 = z0;
  slab.z1 = z1;
  const std::size_t slices = std::size_t(std::max(z1 - z0, 0));
  slab.sliceStart.assign(slices + 1, 0);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    const LatticeTet& lt = tets[t];
    if (lt.empty() || lt.hi[2] < z0 || lt.lo[2] >= z1) continue;
    slab.tets.push_back(std::int32_t(t));
    for (std::int32_t z = std::max(lt.lo[2], z0); z <= std::min(lt.hi[2], z1 - 1); ++z) ++slab.sliceStart[std::size_t(z - z0) + 1];
  }
  for (std::size_t s = 0; s < slices; ++s) slab.sliceStart[s + 1] += slab.sliceStart[s];
  slab.entries.resize(std::size_t(slab.sliceStart[slices]));
  std::vector<std::int64_t> fill(slab.sliceStart.begin(), slab.sliceStart.end() - 1);
  for (std::size_t local = 0; local < slab.tets.size(); ++local) {
    const LatticeTet& lt = tets[std::size_t(slab.tets[local])];
    for (std::int32_t z = std::max(lt.lo[2], z0); z <= std::min(lt.hi[2], z1 - 1); ++z)
      slab.entries[std::size_t(fill[std::size_t(z - z0)]++)] = std::int32_t(local);
  }
  return slab;
}

void locateLatticePoints(const std::vector<LatticeTet>& tets, const SlabTets& slab, const GridGeometry& lattice,
                         std::uint32_t* state, int threads) {
  const std::int64_t nx = lattice.dims[0], sliceSize = lattice.dims[0] * lattice.dims[1];
  parallelFor(slab.z1 - slab.z0, threads, [&](std::int64_t s) {
    std::uint32_t* slice = state + s * sliceSize;
    std::fill(slice, slice + sliceSize, kNoTet);
    const std::int32_t z = slab.z0 + std::int32_t(s);
    // Tets in ascending order, each claiming only unclaimed points: the
    // lowest-index containing tet wins.
    for (std::int64_t e = slab.sliceStart[std::size_t(s)]; e < slab.sliceStart[std::size_t(s) + 1]; ++e) {
      const std::int32_t local = slab.entries[std::size_t(e)];
      const LatticeTet& lt = tets[std::size_t(slab.tets[std::size_t(local)])];
      for (std::int32_t y = lt.lo[1]; y <= lt.hi[1]; ++y) {
        std::int32_t x0, x1;
        if (!rowSpan(lt, y, z, x0, x1)) continue;
        std::uint32_t* row = slice + std::int64_t(y) * nx;
        for (std::int32_t x = x0; x <= x1; ++x)
          if (row[x] == kNoTet) row[x] = std::uint32_t(local);
      }
    }
  });
}

}  // namespace vox
