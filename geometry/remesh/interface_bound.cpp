#include "geometry/remesh/interface_bound.h"

#include "geometry/error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace vox::remesh {

namespace {

std::uint64_t pairKey(std::int32_t x, std::int32_t y) {
  if (x > y) std::swap(x, y);
  return (std::uint64_t(std::uint32_t(x)) << 32) | std::uint32_t(y);
}

// The seven samples of a facet: corners, edge mid-points, centroid.
std::array<Eigen::Vector3d, 7> facetSamples(const std::array<Eigen::Vector3d, 3>& c) {
  return {c[0], c[1], c[2], 0.5 * (c[0] + c[1]), 0.5 * (c[1] + c[2]), 0.5 * (c[2] + c[0]), (c[0] + c[1] + c[2]) / 3.0};
}

double distance2ToFacets(const Eigen::Vector3d& p, const std::vector<InterfaceFacet>& facets, std::int32_t pair,
                         double enough2) {
  double best = std::numeric_limits<double>::infinity();
  for (const InterfaceFacet& f : facets) {
    if (f.pair != pair) continue;
    best = std::min(best, pointTriangleDistance2(p, f.corners[0], f.corners[1], f.corners[2]));
    if (best <= enough2) break;
  }
  return best;
}

}  // namespace

double pointTriangleDistance2(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.squaredNorm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return (ap - v * ab).squaredNorm();
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return (ap - w * ac).squaredNorm();
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (bp - w * (c - b)).squaredNorm();
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return (ap - ab * v - ac * w).squaredNorm();
}

InterfaceBound::InterfaceBound(const RemeshComplex& complex, double bound) : bound_(bound) {
  if (!(bound > 0.0) || !std::isfinite(bound)) throw InputError("remesh", "the interface bound must be positive");
  // The input's interface facets, each once (from its domain tet of the
  // smaller label when both sides are domain tets).
  struct Facet {
    std::uint64_t key;
    Tri v;
  };
  std::vector<Facet> facets;
  for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
    if (!complex.tetAlive(t) || complex.label(t) <= 0) continue;
    const std::int32_t lt = complex.label(t);
    for (int k = 0; k < 4; ++k) {
      const std::int32_t ln = std::max(complex.label(complex.neighbor(t, k)), 0);
      if (ln == lt || (ln > 0 && ln < lt)) continue;
      facets.push_back({pairKey(lt, ln), tetFace(complex.tet(t), k)});
    }
  }
  for (const Facet& f : facets) pairKeys_.push_back(f.key);
  std::sort(pairKeys_.begin(), pairKeys_.end());
  pairKeys_.erase(std::unique(pairKeys_.begin(), pairKeys_.end()), pairKeys_.end());
  auto indexOf = [&](std::uint64_t key) {
    return std::int32_t(std::lower_bound(pairKeys_.begin(), pairKeys_.end(), key) - pairKeys_.begin());
  };

  // Samples, each once per pair: vertices, edge mid-points, centroids.
  std::vector<std::tuple<std::int32_t, std::int32_t, std::int32_t>> points;  // pair, a, b (a == b: vertex)
  triangles_.reserve(facets.size());
  for (const Facet& f : facets) {
    const std::int32_t pair = indexOf(f.key);
    Triangle tri;
    tri.pair = pair;
    for (int i = 0; i < 3; ++i) {
      tri.corners[std::size_t(i)] = complex.position(f.v[std::size_t(i)]).cast<float>();
      const std::int32_t a = f.v[std::size_t(i)], b = f.v[std::size_t((i + 1) % 3)];
      points.emplace_back(pair, a, a);
      points.emplace_back(pair, std::min(a, b), std::max(a, b));
    }
    triangles_.push_back(tri);
  }
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  samples_.reserve(points.size() + triangles_.size());
  for (const auto& [pair, a, b] : points)
    samples_.push_back({(0.5 * (complex.position(a) + complex.position(b))).cast<float>(), pair});
  for (const Triangle& t : triangles_) samples_.push_back({(t.corners[0] + t.corners[1] + t.corners[2]) / 3.0f, t.pair});

  // One grid for both, cells of the bound (a query visits at most 27),
  // coarser where that would make too many cells.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Triangle& t : triangles_)
    for (const Eigen::Vector3f& c : t.corners) {
      lo = lo.cwiseMin(c.cast<double>());
      hi = hi.cwiseMax(c.cast<double>());
    }
  if (triangles_.empty()) lo = hi = Eigen::Vector3d::Zero();
  origin_ = lo - Eigen::Vector3d::Constant(bound_);
  cell_ = bound_;
  const double maxCells = double(std::int64_t(1) << 24);
  for (;;) {
    for (int i = 0; i < 3; ++i) dims_[std::size_t(i)] = std::int64_t(std::floor((hi[i] + bound_ - origin_[i]) / cell_)) + 1;
    if (double(dims_[0]) * double(dims_[1]) * double(dims_[2]) <= maxCells) break;
    cell_ *= 2.0;
  }
  buildCells(
      triangles_.size(), [&](std::size_t i) { return triangles_[i].pair; },
      [&](std::size_t i) {
        const auto& c = triangles_[i].corners;
        return std::make_pair(Eigen::Vector3d(c[0].cwiseMin(c[1]).cwiseMin(c[2]).cast<double>()),
                              Eigen::Vector3d(c[0].cwiseMax(c[1]).cwiseMax(c[2]).cast<double>()));
      },
      triangleCells_);
  buildCells(
      samples_.size(), [&](std::size_t i) { return samples_[i].pair; },
      [&](std::size_t i) {
        const Eigen::Vector3d p = samples_[i].p.cast<double>();
        return std::make_pair(p, p);
      },
      sampleCells_);
}

std::int32_t InterfaceBound::pairIndex(std::int32_t x, std::int32_t y) const {
  const std::uint64_t key = pairKey(x, y);
  const auto it = std::lower_bound(pairKeys_.begin(), pairKeys_.end(), key);
  return it != pairKeys_.end() && *it == key ? std::int32_t(it - pairKeys_.begin()) : -1;
}

std::array<std::int64_t, 3> InterfaceBound::cellOf(const Eigen::Vector3d& p) const {
  std::array<std::int64_t, 3> c{};
  for (int i = 0; i < 3; ++i) {
    const double x = std::floor((p[i] - origin_[i]) / cell_);
    c[std::size_t(i)] = std::int64_t(std::clamp(x, 0.0, double(dims_[std::size_t(i)] - 1)));
  }
  return c;
}

template <typename Pair, typename Box>
void InterfaceBound::buildCells(std::size_t count, const Pair& pairOf, const Box& boxOf, Cells& out) const {
  const std::int64_t cells = dims_[0] * dims_[1] * dims_[2];
  out.start.assign(std::size_t(cells + 1), 0);
  auto forCells = [&](std::size_t item, const auto& f) {
    const auto [lo, hi] = boxOf(item);
    const auto a = cellOf(lo), b = cellOf(hi);
    for (std::int64_t k = a[2]; k <= b[2]; ++k)
      for (std::int64_t j = a[1]; j <= b[1]; ++j)
        for (std::int64_t i = a[0]; i <= b[0]; ++i) f(cellIndex(i, j, k));
  };
  for (std::size_t n = 0; n < count; ++n) forCells(n, [&](std::int64_t c) { ++out.start[std::size_t(c + 1)]; });
  for (std::int64_t c = 0; c < cells; ++c) out.start[std::size_t(c + 1)] += out.start[std::size_t(c)];
  out.items.resize(std::size_t(out.start.back()));
  std::vector<std::int64_t> fill(out.start.begin(), out.start.end() - 1);
  for (std::size_t n = 0; n < count; ++n)
    forCells(n, [&](std::int64_t c) { out.items[std::size_t(fill[std::size_t(c)]++)] = std::int32_t(n); });
  for (std::int64_t c = 0; c < cells; ++c)
    std::stable_sort(out.items.begin() + out.start[std::size_t(c)], out.items.begin() + out.start[std::size_t(c + 1)],
                     [&](std::int32_t x, std::int32_t y) { return pairOf(std::size_t(x)) < pairOf(std::size_t(y)); });
}

template <typename Visit>
bool InterfaceBound::visitCells(const Cells& cells, std::int32_t pair, const Eigen::Vector3d& lo,
                                const Eigen::Vector3d& hi, const Visit& visit) const {
  const auto a = cellOf(lo), b = cellOf(hi);
  for (std::int64_t k = a[2]; k <= b[2]; ++k)
    for (std::int64_t j = a[1]; j <= b[1]; ++j)
      for (std::int64_t i = a[0]; i <= b[0]; ++i) {
        const std::int64_t c = cellIndex(i, j, k);
        auto first = cells.items.begin() + cells.start[std::size_t(c)];
        auto last = cells.items.begin() + cells.start[std::size_t(c + 1)];
        if (first == last) continue;
        // Items sorted by pair within the cell.
        first = std::partition_point(first, last, [&](std::int32_t x) { return visit.pairOf(x) < pair; });
        for (; first != last && visit.pairOf(*first) == pair; ++first)
          if (visit(*first)) return true;
      }
  return false;
}

bool InterfaceBound::within(std::int32_t pair, const Eigen::Vector3d& p, double r) const {
  if (pair < 0) return false;
  const double r2 = r * r;
  const Eigen::Vector3d d = Eigen::Vector3d::Constant(r);
  struct Visit {
    const InterfaceBound& self;
    const Eigen::Vector3d& p;
    double r2;
    std::int32_t pairOf(std::int32_t x) const { return self.triangles_[std::size_t(x)].pair; }
    bool operator()(std::int32_t x) const {
      const auto& c = self.triangles_[std::size_t(x)].corners;
      return pointTriangleDistance2(p, c[0].cast<double>(), c[1].cast<double>(), c[2].cast<double>()) <= r2;
    }
  };
  return visitCells(triangleCells_, pair, p - d, p + d, Visit{*this, p, r2});
}

bool InterfaceBound::keeps(const std::vector<InterfaceFacet>& before, const std::vector<InterfaceFacet>& after) const {
  const double r2 = bound_ * bound_;
  // The new facets, to the input.
  for (const InterfaceFacet& f : after) {
    if (!f.changed) continue;
    for (const Eigen::Vector3d& s : facetSamples(f.corners))
      if (!within(f.pair, s, bound_)) return false;
  }
  // The input, to the new facets: the samples the replaced facets covered.
  thread_local std::vector<std::int32_t> pairs;
  pairs.clear();
  for (const InterfaceFacet& f : before) pairs.push_back(f.pair);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  for (std::int32_t pair : pairs) {
    if (pair < 0) continue;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const InterfaceFacet& f : before)
      if (f.pair == pair)
        for (const Eigen::Vector3d& c : f.corners) {
          lo = lo.cwiseMin(c);
          hi = hi.cwiseMax(c);
        }
    const Eigen::Vector3d d = Eigen::Vector3d::Constant(bound_);
    struct Visit {
      const InterfaceBound& self;
      const std::vector<InterfaceFacet>& before;
      const std::vector<InterfaceFacet>& after;
      std::int32_t pair;
      double r2;
      std::int32_t pairOf(std::int32_t x) const { return self.samples_[std::size_t(x)].pair; }
      // True (stop) at a sample the replaced facets covered and the new ones do not.
      bool operator()(std::int32_t x) const {
        const Eigen::Vector3d s = self.samples_[std::size_t(x)].p.cast<double>();
        if (distance2ToFacets(s, before, pair, r2) > r2) return false;
        return distance2ToFacets(s, after, pair, r2) > r2;
      }
    };
    if (visitCells(sampleCells_, pair, lo - d, hi + d, Visit{*this, before, after, pair, r2})) return false;
  }
  return true;
}

bool InterfaceBound::keepsMove(const RemeshComplex& complex, std::int32_t v, const std::vector<std::int32_t>& tets,
                               const Eigen::Vector3d& p) const {
  // The interface facets through v, each from its side of the larger label.
  thread_local std::vector<InterfaceFacet> before, after;
  before.clear();
  after.clear();
  for (std::int32_t q : tets) {
    const std::int32_t lq = complex.label(q);
    if (lq <= 0) continue;
    const Tet& t = complex.tet(q);
    for (int f = 0; f < 4; ++f) {
      if (t[std::size_t(f)] == v) continue;  // the facet opposite v
      const std::int32_t ln = std::max(complex.label(complex.neighbor(q, f)), 0);
      if (ln >= lq) continue;
      InterfaceFacet facet;
      facet.pair = pairIndex(lq, ln);
      const Tri w = tetFace(t, f);
      for (int i = 0; i < 3; ++i) facet.corners[std::size_t(i)] = complex.position(w[std::size_t(i)]);
      before.push_back(facet);
      for (int i = 0; i < 3; ++i)
        if (w[std::size_t(i)] == v) facet.corners[std::size_t(i)] = p;
      after.push_back(facet);
    }
  }
  return before.empty() || keeps(before, after);
}

}  // namespace vox::remesh
