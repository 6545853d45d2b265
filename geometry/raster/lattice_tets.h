#pragma once
// Scan conversion of a tet mesh onto the points of a regular lattice: which
// lattice points lie in which tet, with one deterministic answer on shared
// faces, edges and vertices. Shared by the CPU rasterizer (rasterize.h), the
// field interpolation (field_interpolation.h) and the host side of their GPU
// kernels, which round these double-precision planes to float.
//
// Index space: lattice point (x,y,z) (integers) sits at
//   lattice.origin + lattice.spacing .* (x,y,z)
// in the grid frame; a lattice is a GridGeometry whose voxel centres are the
// points (an output grid, or the k-times finer lattice of its sub-samples).
//
// Watertight closed test. Every face plane is computed from the face's three
// vertices taken in a canonical order (ascending global vertex index) and is
// anchored at the lattice point nearest the first of them. The two tets that
// share a face therefore hold the same numbers with opposite signs, and their
// plane values at any point are exact negatives of each other: a point on a
// shared face passes the closed test (all four values >= 0) of both tets, a
// point near it passes exactly one, and the union of the tets' closed sets
// has no floating-point cracks. Ties are resolved by the lowest tet index (the
// thesis' "first tet that visits the voxel"). The GPU kernels round these
// planes to float and bound each scanline at the root of each plane value,
// which the two tets of a face also compute bitwise equal (shaders/shared/
// lattice_span.glsl): watertight too, and different from this exact test only
// for points within float rounding of a face.

#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace vox {

using LatticeIndex = std::array<std::int32_t, 3>;

// One tet of a mesh scan-converted onto a lattice.
struct LatticeTet {
  // Face k is the face opposite vertex k. Its inward plane value at lattice
  // point (x,y,z), evaluated exactly in this order:
  //   f_k = n.x * (x - a.x) + ((n.y * (y - a.y) + n.z * (z - a.z)) + d)
  // with n = normal[k], a = anchor[k], d = offset[k]; the integer differences
  // are exact. f_k = 6 |t| lambda_k (lambda_k the barycentric coordinate of
  // vertex k).
  std::array<Eigen::Vector3d, 4> normal;
  std::array<double, 4> offset{};
  std::array<LatticeIndex, 4> anchor{};
  // Lattice points that may pass the test: lo..hi per axis, clipped to the
  // lattice; empty (lo > hi on some axis) for a degenerate tet or one outside
  // the lattice.
  LatticeIndex lo{0, 0, 0};
  LatticeIndex hi{-1, -1, -1};

  bool empty() const { return lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]; }
  double planeValue(int k, std::int32_t x, std::int32_t y, std::int32_t z) const {
    const Eigen::Vector3d& n = normal[std::size_t(k)];
    const LatticeIndex& a = anchor[std::size_t(k)];
    const double rest = n.y() * double(y - a[1]) + n.z() * double(z - a[2]) + offset[std::size_t(k)];
    return n.x() * double(x - a[0]) + rest;
  }
  bool contains(std::int32_t x, std::int32_t y, std::int32_t z) const {
    for (int k = 0; k < 4; ++k)
      if (!(planeValue(k, x, y, z) >= 0.0)) return false;
    return true;
  }
  // Barycentric coordinates of vertices 0..3 at a lattice point.
  Eigen::Vector4d barycentric(std::int32_t x, std::int32_t y, std::int32_t z) const;
};

// A grid-frame position (mm) in the continuous index space of `lattice`.
inline Eigen::Vector3d latticeCoordinates(const GridGeometry& lattice, const Eigen::Vector3d& p) {
  return (p - lattice.origin).cwiseQuotient(lattice.spacing);
}

// Scan-converts every tet of (positions, tets) onto `lattice`.
//   positions  #V grid-frame positions (mm)
//   tets       #T tets indexing positions
// Returns #T lattice tets, in tet order. Tets of (near) zero volume get an
// empty box: they contain no point.
std::vector<LatticeTet> latticeTets(const GridGeometry& lattice, const std::vector<Eigen::Vector3d>& positions,
                                    const std::vector<Tet>& tets);

// The points of lattice row (y, z) inside tet t: x0..x1 (inclusive). Returns
// false when there are none. Exactly the points whose four plane values are
// >= 0 (each plane value is monotone in x, so the set is an interval).
bool rowSpan(const LatticeTet& t, std::int32_t y, std::int32_t z, std::int32_t& x0, std::int32_t& x1);

// The affine map, restricted to tet t, that sends a lattice point q to
//   value(q) = atAnchor + linear * (q - anchor)
// where value is the barycentric interpolation of per-vertex vectors
// (rest positions for the rasterizer, a scalar for field interpolation).
// `anchor` is the lattice point nearest the tet's centroid, so the GPU can
// evaluate it in float with a small (q - anchor).
template <int N>
struct TetAffineMap {
  LatticeIndex anchor{0, 0, 0};
  Eigen::Matrix<double, N, 3> linear = Eigen::Matrix<double, N, 3>::Zero();
  Eigen::Matrix<double, N, 1> atAnchor = Eigen::Matrix<double, N, 1>::Zero();
};
// values[k] = the value at vertex k of the tet (tet order).
template <int N>
TetAffineMap<N> tetAffineMap(const LatticeTet& t, const std::array<Eigen::Matrix<double, N, 1>, 4>& values);

// The tets of lattice slices [z0, z1) (a slab), binned per slice.
//   tets        global indices of the tets whose box meets the slab, ascending;
//               positions in this list are the slab's local tet indices
//   sliceStart  z1 - z0 + 1 offsets into `entries`
//   entries     per slice, the local indices of the tets meeting it, ascending
struct SlabTets {
  std::int32_t z0 = 0, z1 = 0;
  std::vector<std::int32_t> tets;
  std::vector<std::int64_t> sliceStart;
  std::vector<std::int32_t> entries;
};
SlabTets slabTets(const std::vector<LatticeTet>& tets, std::int32_t z0, std::int32_t z1);

// Point state of a located slab: the local index of the lowest-index tet
// containing the point, or kNoTet.
inline constexpr std::uint32_t kNoTet = 0xFFFFFFFFu;

// For every point of lattice slices [slab.z0, slab.z1): the local index of
// the lowest-index tet whose closed test it passes, else kNoTet. `state` holds
// the slab's points, x fastest (nx * ny * (z1 - z0) values).
void locateLatticePoints(const std::vector<LatticeTet>& tets, const SlabTets& slab, const GridGeometry& lattice,
                         std::uint32_t* state, int threads);

// Lattice points a located slab holds by default (64 MiB of point states).
inline constexpr std::int64_t kSlabPoints = std::int64_t(1) << 24;

// Slices per slab when a slab may hold `points` points and a slice has
// `pointsPerSlice` of them: at least one slice.
inline std::int64_t slabSlicesHolding(std::int64_t points, std::int64_t pointsPerSlice) {
  return std::max<std::int64_t>(1, points / std::max<std::int64_t>(1, pointsPerSlice));
}

// Every slice of `lattice`, in slabs of `slicesPerSlab` slices (at least 1),
// bottom to top: each slab is binned (slabTets), its points located
// (locateLatticePoints), then handed to body(slab, state).
template <class Body>
void forEachLocatedSlab(const std::vector<LatticeTet>& tets, const GridGeometry& lattice, std::int64_t slicesPerSlab,
                        int threads, Body&& body) {
  const std::int64_t nz = lattice.dims[2], step = slicesPerSlab > 1 ? slicesPerSlab : 1;
  std::vector<std::uint32_t> state;
  for (std::int64_t z0 = 0; z0 < nz; z0 += step) {
    const std::int64_t z1 = z0 + step < nz ? z0 + step : nz;
    const SlabTets slab = slabTets(tets, std::int32_t(z0), std::int32_t(z1));
    state.resize(std::size_t((z1 - z0) * lattice.sliceVoxels()));
    locateLatticePoints(tets, slab, lattice, state.data(), threads);
    body(slab, state.data());
  }
}

}  // namespace vox
