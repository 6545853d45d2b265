#include "geometry/deform/transfer_mesh.h"

#include "geometry/cancellation.h"
#include "geometry/distance_transform.h"
#include "geometry/deform/cage/restricted_delaunay.h"
#include "geometry/error.h"
#include "geometry/parallel.h"
#include "geometry/progress.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <unordered_map>

namespace vox {

ScalarGrid defaultSizingField(const GridGeometry& geometry, double fraction) {
  return ScalarGrid(geometry, float(fraction * geometry.diagonal()));
}

namespace {

// Label of the domain at p: outside when the interpolated distance to the
// foreground's voxel centres exceeds the offset; otherwise the group whose
// trilinear weights over the 8 surrounding voxel centres sum highest (ties
// to the smaller group), so group interfaces pass between voxel centres.
// The distance is interpolated exactly as ScalarGrid::sample does (same
// weights, same order), so the domain is the sampled field's to the bit.
//
// The mesher asks this at every bisection step of its surface points, at
// scattered places of a grid larger than the caches, so each query pays for
// the cache lines of its 8 corners in two fields. A table of the cells
// (the cube between 8 voxel centres, named by its lowest corner) answers
// most queries from one line: a cell whose corner distances all lie beyond
// the offset by 1e-6 of the largest magnitude among them and the offset is
// outside wherever sampled (the interpolation and its rounding to float
// move the value by far less), one whose corners all lie that far within it
// and share a group (under 255, the byte's marker of the rest) is that
// group; only the other cells are interpolated.
class TransferMeshDomain {
public:
  TransferMeshDomain(const ScalarGrid& distance, const LabelGrid& nearestGroup, double offsetMm)
      : distance_(distance), groups_(nearestGroup), offset_(offsetMm) {}

  // (Re)builds the table's cells whose lowest corner lies in [lo, hi]
  // (voxel indices, clamped to the cells) from the distance field as it is
  // now; the first call builds the whole table.
  void classifyCells(Index3 lo, Index3 hi) {
    const GridGeometry& g = groups_.geometry();
    if (cells_.empty()) {
      cells_.assign(std::size_t(g.voxelCount()), kMixed);
      lo = {0, 0, 0};
      hi = {g.dims[0], g.dims[1], g.dims[2]};
    }
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max<std::int64_t>(lo[a], 0);
      hi[a] = std::min<std::int64_t>(hi[a], g.dims[a] - 2);
    }
    if (lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]) return;
    const Label* groups = groups_.data();
    const std::array<std::int64_t, 8> offsets = cornerOffsets(g);
    parallelRanges(hi[2] - lo[2] + 1, workerThreads(0), [&](std::int64_t k0, std::int64_t k1) {
      for (std::int64_t k = lo[2] + k0; k < lo[2] + k1; ++k) {
        throwIfCancelled();
        for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
          for (std::int64_t i = lo[0]; i <= hi[0]; ++i) {
            const std::int64_t base = g.index(i, j, k);
            double low = std::numeric_limits<double>::infinity(), high = -low;
            bool oneGroup = true;
            for (const std::int64_t o : offsets) {
              const double d = distance_.values[std::size_t(base + o)];
              low = std::min(low, d);
              high = std::max(high, d);
              oneGroup = oneGroup && groups[base + o] == groups[base];
            }
            const double margin = 1e-6 * std::max({std::abs(low), std::abs(high), std::abs(offset_)});
            std::uint8_t cell = kMixed;
            if (low > offset_ + margin) cell = 0;
            else if (high < offset_ - margin && oneGroup && groups[base] < kMixed) cell = std::uint8_t(groups[base]);
            cells_[std::size_t(base)] = cell;
          }
      }
    }, 8);
  }

  int operator()(const Eigen::Vector3d& p) const {
    const GridGeometry& g = groups_.geometry();
    const Eigen::Vector3d c = g.continuousIndex(p);
    std::int64_t i0[3];
    double f[3];
    for (int a = 0; a < 3; ++a) {
      const double x = std::clamp(c[a], 0.0, double(g.dims[a] - 1));
      i0[a] = std::min<std::int64_t>(std::int64_t(x), g.dims[a] - 2);  // x >= 0: truncation is the floor
      f[a] = x - double(i0[a]);
    }
    const std::int64_t base = g.index(i0[0], i0[1], i0[2]);
    const std::uint8_t cell = cells_[std::size_t(base)];
    if (cell != kMixed) return int(cell);
    const std::array<std::int64_t, 8> offsets = cornerOffsets(g);
    double weights[8];
    double d = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
      const int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
      weights[corner] = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
      d += weights[corner] * double(distance_.values[std::size_t(base + offsets[corner])]);
    }
    if (double(float(d)) > offset_) return 0;
    const Label* groups = groups_.data() + base;
    Label labels[8];
    double sums[8];
    int n = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const Label l = groups[offsets[corner]];
      int slot = 0;
      while (slot < n && labels[slot] != l) ++slot;
      if (slot == n) labels[n] = l, sums[n++] = 0.0;
      sums[slot] += weights[corner];
    }
    int best = 0;
    for (int s = 1; s < n; ++s)
      if (sums[s] > sums[best] || (sums[s] == sums[best] && labels[s] < labels[best])) best = s;
    return int(labels[best]);
  }

private:
  static constexpr std::uint8_t kMixed = 255;

  // Linear offsets of a cell's corners from its lowest one, x fastest.
  static std::array<std::int64_t, 8> cornerOffsets(const GridGeometry& g) {
    const std::int64_t y = g.dims[0], z = g.sliceVoxels();
    return {0, 1, y, y + 1, z, z + 1, z + y, z + y + 1};
  }

  const ScalarGrid& distance_;
  const LabelGrid& groups_;
  double offset_;
  std::vector<std::uint8_t> cells_;
};

// Marks covered[v] for the voxels of z in [k0, k1) whose centres lie in a
// tet of `mesh`.
void markCoveredVoxels(const TetMesh& mesh, const GridGeometry& g, std::int64_t k0, std::int64_t k1, std::vector<std::uint8_t>& covered) {
  std::size_t visited = 0;
  for (const Tet& t : mesh.tets) {
    if ((++visited & 0xfff) == 0) throwIfCancelled();
    const Eigen::Vector3d& a = mesh.positions[t[0]];
    Eigen::Vector3d lo = a, hi = a;
    for (int k = 1; k < 4; ++k) {
      lo = lo.cwiseMin(mesh.positions[t[k]]);
      hi = hi.cwiseMax(mesh.positions[t[k]]);
    }
    const Eigen::Vector3d clo = g.continuousIndex(lo), chi = g.continuousIndex(hi);
    std::int64_t i0[3], i1[3];
    for (int d = 0; d < 3; ++d) {
      i0[d] = std::max<std::int64_t>(0, std::int64_t(std::ceil(clo[d])));
      i1[d] = std::min<std::int64_t>(g.dims[d] - 1, std::int64_t(std::floor(chi[d])));
    }
    i0[2] = std::max(i0[2], k0);
    i1[2] = std::min(i1[2], k1 - 1);
    if (i0[2] > i1[2]) continue;
    Eigen::Matrix3d m;
    m << mesh.positions[t[1]] - a, mesh.positions[t[2]] - a, mesh.positions[t[3]] - a;
    const Eigen::Matrix3d inv = m.inverse();
    if (!inv.allFinite()) continue;
    // Barycentric inclusion with a tolerance: a centre on a shared face
    // counts for both tets.
    constexpr double kTolerance = 1e-9;
    for (std::int64_t k = i0[2]; k <= i1[2]; ++k)
      for (std::int64_t j = i0[1]; j <= i1[1]; ++j)
        for (std::int64_t i = i0[0]; i <= i1[0]; ++i) {
          const Eigen::Vector3d l = inv * (g.voxelCenter(i, j, k) - a);
          if (l.minCoeff() >= -kTolerance && l.sum() <= 1.0 + kTolerance) covered[std::size_t(g.index(i, j, k))] = 1;
        }
  }
}

// Foreground voxels of `grid` (linear indices) whose centres lie in no tet.
// On the parallel loop by slabs of z: each slab's voxels are marked by the
// tets that reach it, so no two threads write one voxel.
std::vector<std::int64_t> uncoveredVoxels(const TetMesh& mesh, const LabelGrid& grid) {
  const GridGeometry& g = grid.geometry();
  std::vector<std::uint8_t> covered(std::size_t(g.voxelCount()), 0);
  parallelRanges(g.dims[2], workerThreads(0), [&](std::int64_t k0, std::int64_t k1) { markCoveredVoxels(mesh, g, k0, k1, covered); }, 8);
  std::vector<std::int64_t> uncovered;
  for (std::size_t v = 0; v < covered.size(); ++v)
    if (grid.labels()[v] != 0 && !covered[v]) uncovered.push_back(std::int64_t(v));
  return uncovered;
}

// Coverage caps: a foreground voxel centre that the mesh leaves out lies
// just outside its boundary, where a Delaunay facet's chord cuts inside the
// domain at a convex feature. A tet on that facet whose apex lies beyond
// the centre (a cap) covers it where the cap meets no other part of the
// mesh: a few tets instead of meshing the whole domain again.
class CoverageCaps {
public:
  CoverageCaps(TetMesh& mesh, double reachMm) : mesh_(mesh), reach_(reachMm), cell_(4.0 * reachMm) {
    const std::vector<std::array<std::int32_t, 4>> neighbours = faceNeighbors(mesh, "transfer mesh");
    for (std::size_t t = 0; t < mesh.tets.size(); ++t)
      for (int k = 0; k < 4; ++k)
        if (neighbours[t][std::size_t(k)] < 0) addFacet(tetFace(mesh.tets[t], k), mesh.labels[t]);
  }

  // Covers the point c (outside the mesh; of `group`) by a cap on the
  // nearest boundary facet it lies above, of its group's tets first, the
  // best shaped cap that meets no other boundary facet; false when no such
  // cap exists within reach.
  bool cover(const Eigen::Vector3d& c, std::int32_t group) {
    for (const std::size_t t : caps_)
      if (contains(mesh_.tets[t], c)) return true;
    struct Candidate {
      bool otherGroup;
      double height;
      std::int32_t facet;
    };
    std::vector<Candidate> candidates;
    forFacetsNear(c - Eigen::Vector3d::Constant(reach_), c + Eigen::Vector3d::Constant(reach_), [&](std::int32_t f) {
      const Tri& v = facets_[std::size_t(f)].vertices;
      const Eigen::Vector3d &a = mesh_.positions[std::size_t(v[0])], &b = mesh_.positions[std::size_t(v[1])], &e = mesh_.positions[std::size_t(v[2])];
      const Eigen::Vector3d n = (b - a).cross(e - a).normalized();
      const double d = n.dot(c - a);
      if (!(d > 0.0 && d <= reach_)) return;
      const Eigen::Vector3d beta = barycentric(a, b, e, c - d * n);
      if (beta.minCoeff() < 0.0) return;
      candidates.push_back({facets_[std::size_t(f)].label != group, d, f});
    });
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
      return std::tie(x.otherGroup, x.height, x.facet) < std::tie(y.otherGroup, y.height, y.facet);
    });
    for (const Candidate& candidate : candidates)
      if (capOn(candidate.facet, candidate.height, c)) return true;
    return false;
  }

private:
  struct Facet {
    Tri vertices;
    std::int32_t label;
    bool open;  // still on the boundary
  };

  static Eigen::Vector3d barycentric(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& e, const Eigen::Vector3d& p) {
    const Eigen::Vector3d u = b - a, w = e - a, r = p - a;
    const double uu = u.dot(u), uw = u.dot(w), ww = w.dot(w), ru = r.dot(u), rw = r.dot(w);
    const double det = uu * ww - uw * uw;
    const double y = (ww * ru - uw * rw) / det, z = (uu * rw - uw * ru) / det;
    return {1.0 - y - z, y, z};
  }

  // p inside the tet (a margin within its faces, where markCoveredVoxels
  // counts a margin beyond them).
  static bool contains(const std::array<Eigen::Vector3d, 4>& t, const Eigen::Vector3d& p) {
    Eigen::Matrix3d m;
    m << t[1] - t[0], t[2] - t[0], t[3] - t[0];
    const Eigen::Vector3d l = m.inverse() * (p - t[0]);
    constexpr double kMargin = 1e-7;
    return l.allFinite() && l.minCoeff() >= kMargin && l.sum() <= 1.0 - kMargin;
  }
  bool contains(const Tet& t, const Eigen::Vector3d& p) const {
    return contains({mesh_.positions[std::size_t(t[0])], mesh_.positions[std::size_t(t[1])], mesh_.positions[std::size_t(t[2])],
                     mesh_.positions[std::size_t(t[3])]},
                    p);
  }

  // Mean ratio of a tet (1 for the regular tet, 0 for a flat one).
  static double shape(const std::array<Eigen::Vector3d, 4>& p) {
    const double v = std::abs(signedVolume(p[0], p[1], p[2], p[3]));
    double squares = 0.0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) squares += (p[std::size_t(i)] - p[std::size_t(j)]).squaredNorm();
    return 12.0 * std::pow(3.0 * v, 2.0 / 3.0) / squares;
  }

  // Separating axes of a triangle and a tet (both convex): true when no
  // axis separates them.
  static bool overlaps(const std::array<Eigen::Vector3d, 3>& tri, const std::array<Eigen::Vector3d, 4>& tet) {
    std::array<Eigen::Vector3d, 6> tetEdges;
    std::size_t n = 0;
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = i + 1; j < 4; ++j) tetEdges[n++] = tet[j] - tet[i];
    const std::array<Eigen::Vector3d, 3> triEdges{tri[1] - tri[0], tri[2] - tri[1], tri[0] - tri[2]};
    const auto separates = [&](const Eigen::Vector3d& axis) {
      if (axis.squaredNorm() < 1e-24) return false;
      double lo0 = std::numeric_limits<double>::infinity(), hi0 = -lo0, lo1 = lo0, hi1 = hi0;
      for (const Eigen::Vector3d& p : tri) lo0 = std::min(lo0, axis.dot(p)), hi0 = std::max(hi0, axis.dot(p));
      for (const Eigen::Vector3d& p : tet) lo1 = std::min(lo1, axis.dot(p)), hi1 = std::max(hi1, axis.dot(p));
      return hi0 <= lo1 || hi1 <= lo0;
    };
    if (separates(triEdges[0].cross(triEdges[1]))) return false;
    for (std::size_t f = 0; f < 4; ++f) {
      const Eigen::Vector3d& a = tet[(f + 1) % 4];
      if (separates((tet[(f + 2) % 4] - a).cross(tet[(f + 3) % 4] - a))) return false;
    }
    for (const Eigen::Vector3d& e : tetEdges)
      for (const Eigen::Vector3d& t : triEdges)
        if (separates(e.cross(t))) return false;
    return true;
  }

  // Caps facet f towards c (height d above it): of a few apexes above the
  // facet's centroid, above c's foot and between, at heights from a regular
  // tet's down to just beyond c, the best shaped cap that holds c inside and
  // meets no open facet but f. Adds it and returns true, or false.
  bool capOn(std::int32_t f, double d, const Eigen::Vector3d& c) {
    const Tri v = facets_[std::size_t(f)].vertices;
    const std::array<Eigen::Vector3d, 3> base{mesh_.positions[std::size_t(v[0])], mesh_.positions[std::size_t(v[1])],
                                               mesh_.positions[std::size_t(v[2])]};
    const Eigen::Vector3d n = (base[1] - base[0]).cross(base[2] - base[0]).normalized();
    const Eigen::Vector3d centroid = (base[0] + base[1] + base[2]) / 3.0, foot = c - d * n;
    const double edge = ((base[1] - base[0]).norm() + (base[2] - base[1]).norm() + (base[0] - base[2]).norm()) / 3.0;
    struct Apex {
      double shape;
      Eigen::Vector3d p;
    };
    std::vector<Apex> apexes;
    for (const Eigen::Vector3d& under : {centroid, Eigen::Vector3d(0.5 * (centroid + foot)), foot})
      for (const double h : {0.8165 * edge, 0.5 * edge, 0.3 * edge, 2.0 * d, 1.25 * d}) {
        if (!(h > 1.01 * d)) continue;
        const std::array<Eigen::Vector3d, 4> tet{base[0], base[1], base[2], under + h * n};
        if (signedVolume(tet[0], tet[1], tet[2], tet[3]) > 0.0 && contains(tet, c)) apexes.push_back({shape(tet), tet[3]});
      }
    std::stable_sort(apexes.begin(), apexes.end(), [](const Apex& x, const Apex& y) { return x.shape > y.shape; });
    for (const Apex& apex : apexes) {
      // The cap shrunk a little about its centroid, so the facets that share
      // its base's edges and corners touch it nowhere.
      std::array<Eigen::Vector3d, 4> tet{base[0], base[1], base[2], apex.p};
      const Eigen::Vector3d middle = (tet[0] + tet[1] + tet[2] + tet[3]) / 4.0;
      Eigen::Vector3d lo = middle, hi = middle;
      for (Eigen::Vector3d& p : tet) {
        p = middle + (1.0 - 1e-4) * (p - middle);
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      bool meets = false;
      forFacetsNear(lo, hi, [&](std::int32_t other) {
        if (meets || other == f) return;
        const Tri& o = facets_[std::size_t(other)].vertices;
        meets = overlaps({mesh_.positions[std::size_t(o[0])], mesh_.positions[std::size_t(o[1])], mesh_.positions[std::size_t(o[2])]}, tet);
      });
      if (meets) continue;
      const std::int32_t apexIndex = std::int32_t(mesh_.positions.size());
      mesh_.positions.push_back(apex.p);
      const Tet cap{v[0], v[1], v[2], apexIndex};
      caps_.push_back(mesh_.tets.size());
      mesh_.tets.push_back(cap);
      mesh_.labels.push_back(facets_[std::size_t(f)].label);
      facets_[std::size_t(f)].open = false;
      for (int k = 0; k < 3; ++k) addFacet(tetFace(cap, k), facets_[std::size_t(f)].label);
      return true;
    }
    return false;
  }

  std::int64_t cellKey(const Eigen::Vector3d& p) const {
    constexpr std::int64_t kBias = std::int64_t(1) << 20;
    std::int64_t key = 0;
    for (int a = 0; a < 3; ++a) key = (key << 21) | (std::int64_t(std::floor(p[a] / cell_)) + kBias);
    return key;
  }

  template <class Visit>
  void forCells(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, Visit&& visit) const {
    const Eigen::Vector3d l = (lo / cell_).array().floor(), h = (hi / cell_).array().floor();
    for (double z = l.z(); z <= h.z(); ++z)
      for (double y = l.y(); y <= h.y(); ++y)
        for (double x = l.x(); x <= h.x(); ++x) visit(cellKey(Eigen::Vector3d((x + 0.5) * cell_, (y + 0.5) * cell_, (z + 0.5) * cell_)));
  }

  // Calls visit(f) once for each open facet whose cells meet the box.
  template <class Visit>
  void forFacetsNear(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, Visit&& visit) {
    ++stamp_;
    forCells(lo, hi, [&](std::int64_t key) {
      const auto found = cells_.find(key);
      if (found == cells_.end()) return;
      for (const std::int32_t f : found->second)
        if (facets_[std::size_t(f)].open && seen_[std::size_t(f)] != stamp_) {
          seen_[std::size_t(f)] = stamp_;
          visit(f);
        }
    });
  }

  void addFacet(const Tri& t, std::int32_t label) {
    const std::int32_t f = std::int32_t(facets_.size());
    facets_.push_back({t, label, true});
    seen_.push_back(0);
    Eigen::Vector3d lo = mesh_.positions[std::size_t(t[0])], hi = lo;
    for (int k = 1; k < 3; ++k) {
      lo = lo.cwiseMin(mesh_.positions[std::size_t(t[std::size_t(k)])]);
      hi = hi.cwiseMax(mesh_.positions[std::size_t(t[std::size_t(k)])]);
    }
    forCells(lo, hi, [&](std::int64_t key) { cells_[key].push_back(f); });
  }

  TetMesh& mesh_;
  double reach_, cell_;
  std::vector<Facet> facets_;
  std::vector<std::uint32_t> seen_;
  std::uint32_t stamp_ = 0;
  std::unordered_map<std::int64_t, std::vector<std::int32_t>> cells_;
  std::vector<std::size_t> caps_;
};

// Coverage repair: at most this many extra meshing passes, each pushing the
// boundary out by half the offset around the voxels still uncovered (that
// no cap covers, with TransferMeshOptions::coverageCaps), within
// a radius of four of the coarsest voxel spacing (chords of Delaunay facets
// cut inside at sharp convex features: finger tips, a body cut flat by the
// grid's border).
constexpr int kCoveragePasses = 3;

}  // namespace

TetMesh buildTransferMesh(const LabelGrid& groups, const ScalarGrid& sizing, const TransferMeshOptions& options,
                          const TransferMeshRelabel& relabel, std::int64_t* uncoveredVoxels) {
  if (sizing.values.empty() || *std::min_element(sizing.values.begin(), sizing.values.end()) <= 0.0f)
    throw InputError("sizing field", "must be positive everywhere");
  reportProgress("transfer mesh", 0.0);
  const GridGeometry& g = groups.geometry();
  const double offset = options.boundaryOffsetVoxels * g.spacing.minCoeff();
  const double maxOffset = offset * (1.0 + 0.5 * kCoveragePasses);
  // Pad by the largest offset plus two voxels: the domain ends inside the grid.
  const GridGeometry padded = padGeometry(g, padForDistance(g, maxOffset, 2));
  const LabelGrid labels = padLabels(groups, padded);
  std::vector<std::uint8_t> foreground(labels.labels().size());
  std::transform(labels.labels().begin(), labels.labels().end(), foreground.begin(), [](Label l) { return std::uint8_t(l != 0); });
  if (std::find(foreground.begin(), foreground.end(), 1) == foreground.end())
    throw InputError("grid", "has no foreground voxels to mesh");

  // Distance to the foreground, and each voxel's nearest group: the groups
  // extended into the background so the offset boundary has labels.
  DistanceTransform dt = euclideanDistanceTransform(padded, foreground, true);
  LabelGrid nearestGroup(padded, 0);
  parallelRanges(std::int64_t(foreground.size()), workerThreads(0), [&](std::int64_t v0, std::int64_t v1) {
    for (std::int64_t v = v0; v < v1; ++v) nearestGroup.labels()[std::size_t(v)] = labels.labels()[std::size_t(dt.nearest[std::size_t(v)])];
  }, std::int64_t(1) << 16);
  TransferMeshDomain domainLabel(dt.distance, nearestGroup, offset);
  const auto label = [&](const Eigen::Vector3d& p) {
    const int l = domainLabel(p);
    return l > 0 && relabel ? relabel(p, l) : l;
  };
  LabelGrid atCentres(padded, 0);
  SampledDomain domain;
  domain.labels = &atCentres;
  domain.labelAt = label;
  VolumeCriteria criteria;
  criteria.facetAngleDeg = options.facetAngleDeg;
  criteria.facetDistanceMm = options.facetDistanceVoxels * g.spacing.minCoeff();
  criteria.radiusEdgeRatio = options.radiusEdgeRatio;
  criteria.sizing = &sizing;

  const double radius = 4.0 * g.spacing.maxCoeff();
  // The voxels whose distance the last pass lowered (all of them at first):
  // a cell's label reads its 8 corners, a voxel centre's the cell it falls
  // in (its own or, rounded down, the one below), so the cells and centres
  // within two voxels of them are labelled again, the rest keep theirs.
  Index3 changedLo{0, 0, 0}, changedHi{padded.dims[0] - 1, padded.dims[1] - 1, padded.dims[2] - 1};
  for (int pass = 0;; ++pass) {
    Index3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max<std::int64_t>(0, changedLo[a] - 2);
      hi[a] = std::min<std::int64_t>(padded.dims[a] - 1, changedHi[a] + 2);
    }
    domainLabel.classifyCells(lo, hi);
    parallelRanges(hi[2] - lo[2] + 1, workerThreads(0), [&](std::int64_t k0, std::int64_t k1) {
      for (std::int64_t k = lo[2] + k0; k < lo[2] + k1; ++k) {
        throwIfCancelled();
        for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
          for (std::int64_t i = lo[0]; i <= hi[0]; ++i) atCentres.at(i, j, k) = Label(label(padded.voxelCenter(i, j, k)));
      }
    }, 8);
    reportProgress("transfer mesh", 0.1);
    TetMesh mesh = restrictedDelaunayVolume(domain, criteria);
    orientPositively(mesh);
    std::vector<std::int64_t> uncovered = vox::uncoveredVoxels(mesh, groups);
    if (!uncovered.empty() && options.coverageCaps) uncovered = capUncoveredVoxels(mesh, groups, uncovered);
    if (uncovered.empty() || pass == kCoveragePasses) {
      if (uncoveredVoxels) *uncoveredVoxels = std::int64_t(uncovered.size());
      reportProgress("transfer mesh", 1.0);
      return mesh;
    }
    // Lower the distance field by a bump of height offset/2 around each
    // uncovered centre (the largest bump where they overlap).
    ScalarGrid bump(padded, 0.0f);
    const Index3 reach = padForDistance(padded, radius, 0);
    changedLo = {padded.dims[0], padded.dims[1], padded.dims[2]};
    changedHi = {-1, -1, -1};
    for (const std::int64_t u : uncovered) {
      const Index3 c = g.ijk(u);
      const Eigen::Vector3d centre = g.voxelCenter(c[0], c[1], c[2]);
      Index3 pc;
      padded.voxelAt(centre, pc);
      for (int a = 0; a < 3; ++a) {
        changedLo[a] = std::min(changedLo[a], std::max<std::int64_t>(0, pc[a] - reach[a]));
        changedHi[a] = std::max(changedHi[a], std::min(padded.dims[a] - 1, pc[a] + reach[a]));
      }
      for (std::int64_t k = std::max<std::int64_t>(0, pc[2] - reach[2]); k <= std::min(padded.dims[2] - 1, pc[2] + reach[2]); ++k)
        for (std::int64_t j = std::max<std::int64_t>(0, pc[1] - reach[1]); j <= std::min(padded.dims[1] - 1, pc[1] + reach[1]); ++j)
          for (std::int64_t i = std::max<std::int64_t>(0, pc[0] - reach[0]); i <= std::min(padded.dims[0] - 1, pc[0] + reach[0]); ++i) {
            const double d = (padded.voxelCenter(i, j, k) - centre).norm();
            if (d < radius) bump.at(i, j, k) = std::max(bump.at(i, j, k), float(0.5 * offset * (1.0 - d / radius)));
          }
    }
    for (std::size_t v = 0; v < bump.values.size(); ++v) dt.distance.values[v] -= bump.values[v];
  }
}

std::vector<std::int64_t> capUncoveredVoxels(TetMesh& mesh, const LabelGrid& grid, std::span<const std::int64_t> uncovered) {
  const GridGeometry& g = grid.geometry();
  CoverageCaps caps(mesh, 2.5 * g.spacing.maxCoeff());
  std::vector<std::int64_t> left;
  for (const std::int64_t u : uncovered) {
    throwIfCancelled();
    const Index3 c = g.ijk(u);
    if (!caps.cover(g.voxelCenter(c[0], c[1], c[2]), std::int32_t(grid.labels()[std::size_t(u)]))) left.push_back(u);
  }
  return left;
}

std::int64_t countUncoveredVoxels(const TetMesh& mesh, const LabelGrid& grid) {
  return std::int64_t(uncoveredVoxels(mesh, grid).size());
}

CutReport cutTransferMesh(TetMesh& mesh, std::int32_t groupA, std::int32_t groupB, const std::optional<Eigen::AlignedBox3d>& region) {
  CutSides sides;
  sides.sideA = [groupA](std::int32_t label) { return label == groupA; };
  sides.sideB = [groupB](std::int32_t label) { return label == groupB; };
  if (region) sides.inRegion = [box = *region](const Eigen::Vector3d& p) { return box.contains(p); };
  return cutTransferMesh(mesh, sides);
}

CutReport cutTransferMesh(TetMesh& mesh, const CutSides& sides) {
  CutReport report;
  const auto neighbors = faceNeighbors(mesh, "transfer mesh");
  const std::size_t nt = mesh.tetCount();
  const auto isA = [&](std::int32_t t) { return sides.sideA(mesh.labels[std::size_t(t)]); };
  const auto isB = [&](std::int32_t t) { return sides.sideB(mesh.labels[std::size_t(t)]); };
  const auto inRegion = [&](const Eigen::Vector3d& p) { return !sides.inRegion || sides.inRegion(p); };

  // Cut faces: sideB tet against sideA tet, centroid in the region.
  std::vector<std::uint8_t> tetHasCutFace(nt, 0);
  std::vector<std::uint8_t> vertexOnCut(mesh.vertexCount(), 0);
  for (std::size_t t = 0; t < nt; ++t) {
    if (!isB(std::int32_t(t))) continue;
    for (int k = 0; k < 4; ++k) {
      const std::int32_t n = neighbors[t][k];
      if (n < 0 || !isA(n)) continue;
      const Tri f = tetFace(mesh.tets[t], k);
      const Eigen::Vector3d centroid = (mesh.positions[f[0]] + mesh.positions[f[1]] + mesh.positions[f[2]]) / 3.0;
      if (!inRegion(centroid)) continue;
      ++report.cutFaces;
      tetHasCutFace[t] = 1;
      for (const std::int32_t v : f) vertexOnCut[v] = 1;
    }
  }

  const VertexTets around = vertexTets(mesh.tets, mesh.vertexCount());

  // Contacts: vertices in the region where sideA and sideB tets meet
  // without a cut face (through an edge or the vertex alone). Left shared,
  // such a vertex ties the two groups together: moving one pulls a sliver
  // of tets across the gap. Every sideB fan there gets its own copy.
  std::vector<std::uint8_t> contact(mesh.vertexCount(), 0);
  for (std::int32_t v = 0; v < std::int32_t(mesh.vertexCount()); ++v) {
    if (vertexOnCut[v] || !inRegion(mesh.positions[v])) continue;
    bool a = false, b = false;
    for (const std::int32_t t : around.of(v)) {
      a = a || isA(t);
      b = b || isB(t);
    }
    if (a && b) {
      contact[v] = 1;
      vertexOnCut[v] = 1;
      ++report.contactVertices;
    }
  }
  if (report.cutFaces == 0 && report.contactVertices == 0) return report;

  const std::vector<Tet> original = mesh.tets;
  std::vector<std::int32_t> fanOf;
  // local[t]: t's index among v's sideB tets, -1 elsewhere; reset through
  // those tets after each vertex (a map cleared per vertex would cost its
  // bucket count, the largest valence seen, every time).
  std::vector<std::int32_t> local(nt, -1);
  const auto originalVertices = std::int32_t(vertexOnCut.size());
  for (std::int32_t v = 0; v < originalVertices; ++v) {
    if (!vertexOnCut[v]) continue;
    // Fans of sideB tets around v: joined through sideB-sideB faces
    // containing v (the faces opposite the tets' other vertices).
    std::vector<std::int32_t> btets;
    for (const std::int32_t t : around.of(v))
      if (isB(t)) {
        local[t] = std::int32_t(btets.size());
        btets.push_back(t);
      }
    fanOf.assign(btets.size(), -1);
    std::vector<std::int32_t> stack;
    for (std::size_t seed = 0; seed < btets.size(); ++seed) {
      if (fanOf[seed] >= 0) continue;
      fanOf[seed] = std::int32_t(seed);
      stack.assign(1, std::int32_t(seed));
      bool touchesCut = contact[v] != 0;
      std::vector<std::int32_t> members;
      while (!stack.empty()) {
        const std::int32_t b = stack.back();
        stack.pop_back();
        members.push_back(b);
        const std::int32_t t = btets[b];
        // Faces of t containing v: grow the fan through sideB neighbours,
        // and note whether one of them is a cut face.
        for (int k = 0; k < 4; ++k) {
          if (original[t][k] == v) continue;
          const std::int32_t n = neighbors[t][k];
          if (n < 0) continue;
          if (isB(n)) {
            const std::int32_t ln = local[std::size_t(n)];
            if (ln >= 0 && fanOf[std::size_t(ln)] < 0) {
              fanOf[std::size_t(ln)] = std::int32_t(seed);
              stack.push_back(ln);
            }
          } else if (isA(n) && tetHasCutFace[t]) {
            const Tri f = tetFace(original[t], k);
            const Eigen::Vector3d centroid = (mesh.positions[f[0]] + mesh.positions[f[1]] + mesh.positions[f[2]]) / 3.0;
            if (inRegion(centroid)) touchesCut = true;
          }
        }
      }
      if (!touchesCut) continue;
      const std::int32_t copy = std::int32_t(mesh.positions.size());
      mesh.positions.push_back(mesh.positions[v]);
      ++report.duplicatedVertices;
      report.splitVertices.push_back(v);
      report.splitVertices.push_back(copy);
      for (const std::int32_t b : members)
        for (std::int32_t& x : mesh.tets[btets[b]])
          if (x == v) x = copy;
    }
    for (const std::int32_t t : btets) local[std::size_t(t)] = -1;
  }

  std::sort(report.splitVertices.begin(), report.splitVertices.end());
  report.splitVertices.erase(std::unique(report.splitVertices.begin(), report.splitVertices.end()), report.splitVertices.end());

  // Faces opened besides the cut faces: originally shared, now not.
  std::size_t opened = 0;
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) {
      const std::int32_t n = neighbors[t][k];
      if (n < std::int32_t(t)) continue;
      Tri a = tetFace(mesh.tets[t], k);
      std::sort(a.begin(), a.end());
      bool shared = false;
      for (int m = 0; m < 4 && !shared; ++m) {
        Tri b = tetFace(mesh.tets[n], m);
        std::sort(b.begin(), b.end());
        shared = a == b;
      }
      opened += !shared;
    }
  report.openedRimFaces = opened - report.cutFaces;
  return report;
}

}  // namespace vox
