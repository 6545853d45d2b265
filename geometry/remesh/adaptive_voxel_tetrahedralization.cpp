#include "geometry/remesh/adaptive_voxel_tetrahedralization.h"

#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/progress.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace vox::remesh {

namespace {

// Lattice points (voxel corners of the padded grid), packed 21 bits per axis.
using Point = std::uint64_t;
constexpr int kBits = 21;
constexpr std::uint64_t kMask = (std::uint64_t(1) << kBits) - 1;
Point pack(std::int64_t x, std::int64_t y, std::int64_t z) {
  return std::uint64_t(x) | (std::uint64_t(y) << kBits) | (std::uint64_t(z) << (2 * kBits));
}
std::array<std::int64_t, 3> unpack(Point p) {
  return {std::int64_t(p & kMask), std::int64_t((p >> kBits) & kMask), std::int64_t(p >> (2 * kBits))};
}
Point midpoint(Point a, Point b) {
  const auto x = unpack(a), y = unpack(b);
  return pack((x[0] + y[0]) / 2, (x[1] + y[1]) / 2, (x[2] + y[2]) / 2);
}

// A simplex of the bisection: Maubach's ordered vertices and tag k, its
// refinement edge being (v[0], v[k]).
constexpr std::uint16_t kMixed = 0xFFFF;
constexpr std::int32_t kUnknown = -1;

struct Simplex {
  std::array<Point, 4> v;
  std::uint8_t tag = 3;
  std::uint8_t depth = 0;
  std::int32_t label = kUnknown;  // kMixed, or the label of every voxel it covers
};

// Virtual descent below this many generations is exact; above it a simplex
// is judged by its cube only.
constexpr int kExactDescent = 9;

class KuhnBisection {
public:
  KuhnBisection(const LabelGrid& grid, const AdaptiveTetrahedralizationOptions& options) : grid_(grid) {
    levels_ = std::max(0, options.coarsestLevel);
    const Index3 d = grid.dims();
    std::int64_t lo[3] = {d[0], d[1], d[2]}, hi[3] = {-1, -1, -1};
    for (std::int64_t k = 0; k < d[2]; ++k, throwIfCancelled())
      for (std::int64_t j = 0; j < d[1]; ++j)
        for (std::int64_t i = 0; i < d[0]; ++i)
          if (grid.at(i, j, k) != 0) {
            const std::int64_t c[3] = {i, j, k};
            for (int a = 0; a < 3; ++a) {
              lo[a] = std::min(lo[a], c[a]);
              hi[a] = std::max(hi[a], c[a]);
            }
          }
    if (hi[0] < 0) throw InputError("grid", "has no labelled voxel to mesh");
    if (grid.maxLabel() == kMixed) throw InputError("grid", "uses label 65535, which the mesher reserves");
    const std::int64_t s = std::int64_t(1) << levels_;
    const int margin = std::max(0, options.margin);
    for (int a = 0; a < 3; ++a) {
      offset_[a] = lo[a] - margin;
      dims_[a] = (hi[a] - lo[a] + 1 + 2 * margin + s - 1) / s * s;
      if (dims_[a] + 1 >= std::int64_t(kMask)) throw InputError("grid", "is too large for the adaptive decomposition");
    }
    corners_[0] = dims_[0] + 1;
    corners_[1] = dims_[1] + 1;
    corners_[2] = dims_[2] + 1;
    if (corners_[0] * corners_[1] * corners_[2] >= std::numeric_limits<std::int32_t>::max())
      throw InputError("grid", "has too many voxels to mesh in one piece");
    buildPyramid();
    selectCubes(options.shell, margin);
  }

  TetMesh run(bool includeBackground) {
    exists_.assign(std::size_t(corners_[0] * corners_[1] * corners_[2]), 0);
    std::vector<Simplex> pending, next, done;
    seed(pending);
    const int finest = 3 * levels_;
    for (int round = 0; !pending.empty(); ++round) {
      if (round > 16 * (finest + 2)) throw RuntimeFailure("adaptive tetrahedralization: conforming closure did not end");
      next.clear();
      bool bisected = false;
      std::size_t visited = 0;
      for (Simplex& t : pending) {
        if (++visited % 65536 == 0) throwIfCancelled();
        if (t.depth == finest) {
          done.push_back(t);
          continue;
        }
        if (!mixed(t) && !hanging(t)) {
          next.push_back(t);
          continue;
        }
        bisect(t, next);
        bisected = true;
      }
      pending.swap(next);
      reportProgress("voxel decomposition", std::min(0.99, double(round + 1) / double(finest + 4)));
      if (!bisected) {
        appendCancellable(done, pending.begin(), pending.end());
        break;
      }
    }
    TetMesh mesh = toMesh(done, includeBackground);
    reportProgress("voxel decomposition", 1.0);
    return mesh;
  }

private:
  std::int64_t cubeSize(int depth) const { return std::int64_t(1) << (levels_ - depth / 3); }

  std::int64_t coarseCount(int a) const { return dims_[a] >> levels_; }
  std::size_t coarseIndex(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return std::size_t(i + coarseCount(0) * (j + coarseCount(1) * k));
  }

  // Which coarsest cubes are meshed: all of them, or (shell) those within
  // `margin` voxels of a labelled voxel, counted in whole cubes along each
  // axis, then grown until their union is well composed (no two cubes meet
  // only along an edge or at a corner, nor two gaps), so that the hull of
  // the imaginary layer is a closed manifold surface of axis-aligned faces.
  void selectCubes(bool shell, int margin) {
    const std::int64_t n[3] = {coarseCount(0), coarseCount(1), coarseCount(2)};
    const auto& coarse = pyramid_[0];
    keep_.assign(coarse.size(), shell ? 0 : 1);
    if (!shell) return;
    for (std::size_t c = 0; c < coarse.size(); ++c) keep_[c] = coarse[c] != 0;
    const std::int64_t r = (std::int64_t(margin) + (std::int64_t(1) << levels_) - 1) >> levels_;
    std::vector<std::uint8_t> pass;
    for (int a = 0; a < 3; ++a) {  // separable box dilation by r cubes
      pass = keep_;
      const std::int64_t step = a == 0 ? 1 : a == 1 ? n[0] : n[0] * n[1];
      for (std::int64_t k = 0; k < n[2]; ++k)
        for (std::int64_t j = 0; j < n[1]; ++j)
          for (std::int64_t i = 0; i < n[0]; ++i) {
            const std::int64_t at[3] = {i, j, k};
            const std::size_t c = coarseIndex(i, j, k);
            if (!pass[c]) continue;
            for (std::int64_t d = std::max<std::int64_t>(-r, -at[a]); d <= r && at[a] + d < n[a]; ++d)
              keep_[std::size_t(std::int64_t(c) + d * step)] = 1;
          }
    }
    // Well-composedness: in every 2 x 2 square of cubes (three orientations)
    // a diagonal pair, and in every 2 x 2 x 2 block an antipodal pair of kept
    // cubes or of gaps, is filled in, until there is none.
    for (bool changed = true; changed;) {
      changed = false;
      for (std::int64_t k = 0; k + 1 < std::max<std::int64_t>(n[2], 2); ++k)
        for (std::int64_t j = 0; j + 1 < std::max<std::int64_t>(n[1], 2); ++j)
          for (std::int64_t i = 0; i + 1 < std::max<std::int64_t>(n[0], 2); ++i) {
            std::size_t cell[8];
            std::uint8_t bits = 0;
            for (int c = 0; c < 8; ++c) {
              const std::int64_t x = i + (c & 1), y = j + ((c >> 1) & 1), z = k + (c >> 2);
              cell[c] = x < n[0] && y < n[1] && z < n[2] ? coarseIndex(x, y, z) : SIZE_MAX;
              if (cell[c] != SIZE_MAX && keep_[cell[c]]) bits |= std::uint8_t(1u << c);
            }
            if (!pinched(bits)) continue;
            for (int c = 0; c < 8; ++c)
              if (cell[c] != SIZE_MAX && !keep_[cell[c]]) keep_[cell[c]] = 1, changed = true;
          }
    }
  }

  // Whether a 2 x 2 x 2 block (bit c: cube (c & 1, c >> 1 & 1, c >> 2)
  // kept; cubes beyond the grid are gaps) is not well composed: a square
  // with exactly a diagonal pair kept, or a block whose only kept cubes, or
  // only gaps, are an antipodal pair. (Such pairs never involve a cube
  // beyond the grid, which lies on one side of the block.)
  static bool pinched(std::uint8_t bits) {
    static constexpr int kSquares[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
    for (const auto& q : kSquares) {
      const bool b0 = bits >> q[0] & 1, b1 = bits >> q[1] & 1, b2 = bits >> q[2] & 1, b3 = bits >> q[3] & 1;
      if (b0 == b2 && b1 == b3 && b0 != b1) return true;
    }
    for (int c = 0; c < 4; ++c) {
      const std::uint8_t pair = std::uint8_t(1u << c | 1u << (7 - c));
      if (bits == pair || std::uint8_t(~bits) == pair) return true;
    }
    return false;
  }

  void buildPyramid() {
    pyramid_.resize(std::size_t(levels_) + 1);
    auto& fine = pyramid_[std::size_t(levels_)];
    fine.resize(std::size_t(dims_[0] * dims_[1] * dims_[2]));
    for (std::int64_t k = 0; k < dims_[2]; ++k, throwIfCancelled())
      for (std::int64_t j = 0; j < dims_[1]; ++j)
        for (std::int64_t i = 0; i < dims_[0]; ++i)
          fine[std::size_t(i + dims_[0] * (j + dims_[1] * k))] =
              grid_.atOr(i + offset_[0], j + offset_[1], k + offset_[2], 0);
    for (int m = levels_ - 1; m >= 0; --m) {
      const std::int64_t n0 = dims_[0] >> (levels_ - m), n1 = dims_[1] >> (levels_ - m), n2 = dims_[2] >> (levels_ - m);
      const auto& child = pyramid_[std::size_t(m) + 1];
      auto& level = pyramid_[std::size_t(m)];
      level.assign(std::size_t(n0 * n1 * n2), 0);
      for (std::int64_t k = 0; k < n2; ++k)
        for (std::int64_t j = 0; j < n1; ++j)
          for (std::int64_t i = 0; i < n0; ++i) {
            std::uint16_t label = child[std::size_t(2 * i + 2 * n0 * (2 * j + 2 * n1 * 2 * k))];
            for (int c = 0; c < 8 && label != kMixed; ++c) {
              const std::uint16_t l =
                  child[std::size_t((2 * i + (c & 1)) + 2 * n0 * ((2 * j + ((c >> 1) & 1)) + 2 * n1 * (2 * k + (c >> 2))))];
              if (l != label) label = kMixed;
            }
            level[std::size_t(i + n0 * (j + n1 * k))] = label;
          }
    }
  }

  // Label of the cube (at the simplex's level) holding simplex t; for a
  // simplex of the finest generation, of its voxel.
  std::uint16_t cubeLabel(const Simplex& t) const {
    const int m = t.depth / 3;
    const std::int64_t s = cubeSize(t.depth);
    std::int64_t sum[3] = {0, 0, 0};
    for (Point p : t.v) {
      const auto c = unpack(p);
      for (int a = 0; a < 3; ++a) sum[a] += c[a];
    }
    std::int64_t cube[3];
    for (int a = 0; a < 3; ++a) cube[a] = sum[a] / (4 * s);
    for (Point p : t.v) {
      const auto c = unpack(p);
      for (int a = 0; a < 3; ++a)
        if (c[a] < cube[a] * s || c[a] > (cube[a] + 1) * s)
          throw RuntimeFailure("adaptive tetrahedralization: a simplex left its cube");
    }
    const std::int64_t n0 = dims_[0] >> (levels_ - m), n1 = dims_[1] >> (levels_ - m);
    return pyramid_[std::size_t(m)][std::size_t(cube[0] + n0 * (cube[1] + n1 * cube[2]))];
  }

  // The label every voxel under t carries, or kMixed: from t's cube when
  // that is uniform, else by bisecting t virtually down to the voxels.
  std::uint16_t regionLabel(const Simplex& t) const {
    const std::uint16_t cube = cubeLabel(t);
    if (cube != kMixed || t.depth == 3 * levels_ || 3 * levels_ - t.depth > kExactDescent) return cube;
    thread_local std::vector<Simplex> children;
    const std::size_t base = children.size();
    bisectInto(t, children);
    const Simplex a = children[base], b = children[base + 1];
    children.resize(base);
    const std::uint16_t la = regionLabel(a);
    if (la == kMixed) return kMixed;
    return regionLabel(b) == la ? la : kMixed;
  }

  bool mixed(Simplex& t) const {
    if (t.label == kUnknown) t.label = regionLabel(t);
    return t.label == kMixed;
  }

  std::size_t index(Point p) const {
    const auto c = unpack(p);
    return std::size_t(c[0] + corners_[0] * (c[1] + corners_[1] * c[2]));
  }

  // An edge of t whose midpoint is already a vertex: t must be bisected for
  // the mesh to be conforming.
  bool hanging(const Simplex& t) const {
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const auto a = unpack(t.v[std::size_t(i)]), b = unpack(t.v[std::size_t(j)]);
        if (((a[0] + b[0]) | (a[1] + b[1]) | (a[2] + b[2])) & 1) continue;
        if (exists_[index(midpoint(t.v[std::size_t(i)], t.v[std::size_t(j)]))]) return true;
      }
    return false;
  }

  void bisect(const Simplex& t, std::vector<Simplex>& out) {
    exists_[index(midpoint(t.v[0], t.v[std::size_t(t.tag)]))] = 1;
    bisectInto(t, out);
  }

  static void bisectInto(const Simplex& t, std::vector<Simplex>& out) {
    const int k = t.tag;
    const Point z = midpoint(t.v[0], t.v[std::size_t(k)]);
    Simplex a, b;
    a.tag = b.tag = std::uint8_t(k > 1 ? k - 1 : 3);
    a.depth = b.depth = std::uint8_t(t.depth + 1);
    // Maubach: (x0..x_{k-1}, z, x_{k+1}..x3) and (x1..x_k, z, x_{k+1}..x3).
    for (int i = 0; i < k; ++i) a.v[std::size_t(i)] = t.v[std::size_t(i)];
    for (int i = 0; i < k; ++i) b.v[std::size_t(i)] = t.v[std::size_t(i + 1)];
    a.v[std::size_t(k)] = b.v[std::size_t(k)] = z;
    for (int i = k + 1; i < 4; ++i) a.v[std::size_t(i)] = b.v[std::size_t(i)] = t.v[std::size_t(i)];
    out.push_back(a);
    out.push_back(b);
  }

  // Six Kuhn tets per coarse cube, mirrored along each axis in odd cubes.
  void seed(std::vector<Simplex>& out) {
    static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    const std::int64_t s = std::int64_t(1) << levels_;
    for (std::int64_t c = 0; c < dims_[2] / s; ++c)
      for (std::int64_t b = 0; b < dims_[1] / s; ++b)
        for (std::int64_t a = 0; a < dims_[0] / s; ++a) {
          if (!keep_[coarseIndex(a, b, c)]) continue;
          const std::int64_t cube[3] = {a, b, c};
          std::int64_t origin[3], step[3];
          for (int x = 0; x < 3; ++x) {
            const bool odd = cube[x] & 1;
            origin[x] = (cube[x] + (odd ? 1 : 0)) * s;
            step[x] = odd ? -s : s;
          }
          for (const auto& perm : kPerm) {
            Simplex t;
            std::int64_t p[3] = {origin[0], origin[1], origin[2]};
            t.v[0] = pack(p[0], p[1], p[2]);
            for (int i = 0; i < 3; ++i) {
              p[perm[i]] += step[perm[i]];
              t.v[std::size_t(i) + 1] = pack(p[0], p[1], p[2]);
            }
            for (Point v : t.v) exists_[index(v)] = 1;
            out.push_back(t);
          }
        }
  }

  TetMesh toMesh(const std::vector<Simplex>& simplices, bool includeBackground) const {
    TetMesh mesh;
    std::vector<std::int32_t> remap = filledCancellable(exists_.size(), std::int32_t(-1));
    std::vector<std::int32_t> labels;  // every simplex's, in the polled loop below
    labels.reserve(simplices.size());
    for (std::size_t i = 0; i < simplices.size(); ++i) {
      if (i % 65536 == 0) throwIfCancelled();
      const Simplex& t = simplices[i];
      const std::int32_t label = regionLabel(t);
      if (label == kMixed) throw RuntimeFailure("adaptive tetrahedralization: a final tet covers several labels");
      labels.push_back(label);
      if (label == 0 && !includeBackground) continue;
      for (Point p : t.v) remap[index(p)] = 0;
    }
    std::int32_t next = 0;
    const GridGeometry& g = grid_.geometry();
    for (std::int64_t z = 0; z < corners_[2]; ++z, throwIfCancelled())
      for (std::int64_t y = 0; y < corners_[1]; ++y)
        for (std::int64_t x = 0; x < corners_[0]; ++x) {
          auto& r = remap[std::size_t(x + corners_[0] * (y + corners_[1] * z))];
          if (r < 0) continue;
          r = next++;
          mesh.positions.push_back(g.origin + g.spacing.cwiseProduct(Eigen::Vector3d(double(x + offset_[0]) - 0.5,
                                                                                     double(y + offset_[1]) - 0.5,
                                                                                     double(z + offset_[2]) - 0.5)));
        }
    for (std::size_t i = 0; i < simplices.size(); ++i) {
      if (i % 65536 == 0) throwIfCancelled();
      if (labels[i] == 0 && !includeBackground) continue;
      const Simplex& t = simplices[i];
      std::array<std::array<std::int64_t, 3>, 4> c;
      Tet q;
      for (int k = 0; k < 4; ++k) {
        c[std::size_t(k)] = unpack(t.v[std::size_t(k)]);
        q[std::size_t(k)] = remap[index(t.v[std::size_t(k)])];
      }
      // Exact orientation in lattice coordinates.
      std::int64_t e[3][3];
      for (int r = 0; r < 3; ++r)
        for (int a = 0; a < 3; ++a) e[r][a] = c[std::size_t(r) + 1][std::size_t(a)] - c[0][std::size_t(a)];
      const std::int64_t det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                               e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                               e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
      if (det < 0) std::swap(q[2], q[3]);
      mesh.tets.push_back(q);
      mesh.labels.push_back(labels[i]);
    }
    return mesh;
  }

  const LabelGrid& grid_;
  int levels_ = 0;
  std::int64_t offset_[3]{}, dims_[3]{}, corners_[3]{};
  std::vector<std::vector<std::uint16_t>> pyramid_;
  std::vector<std::uint8_t> exists_;
  std::vector<std::uint8_t> keep_;  // per coarsest cube: meshed
};

}  // namespace

AdaptiveTetrahedralizationOptions adaptiveOptionsForTarget(const GridGeometry& geometry, double targetLength) {
  AdaptiveTetrahedralizationOptions o;
  o.coarsestLevel = 0;
  // Along the finest axis the coarsest cubes span at most 2 l; the splits of
  // the first iteration refine longer axes of anisotropic voxels.
  while (o.coarsestLevel < 6 &&
         double(std::int64_t(2) << o.coarsestLevel) * geometry.spacing.minCoeff() <= 2.0 * targetLength * (1.0 + 1e-9))
    ++o.coarsestLevel;
  o.margin = std::max(2, int(std::ceil(targetLength / geometry.spacing.minCoeff())));
  return o;
}

AdaptiveTetrahedralizationOptions adaptiveOptionsForSizing(const GridGeometry& geometry, double shortest, double longest) {
  AdaptiveTetrahedralizationOptions o = adaptiveOptionsForTarget(geometry, shortest);
  o.coarsestLevel = adaptiveOptionsForTarget(geometry, longest).coarsestLevel;
  return o;
}

TetMesh tetrahedralizeVoxelsAdaptive(const LabelGrid& grid, const AdaptiveTetrahedralizationOptions& options) {
  KuhnBisection bisection(grid, options);
  return bisection.run(options.includeBackground);
}

}  // namespace vox::remesh
