#include "geometry/remesh/interface_bound.h"

#include "geometry/cancellation.h"
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

// Squared distance from p to the box [lo, hi] (0 inside): a lower bound of
// the distance to anything in it, cheaper than a triangle's.
template <typename V>
double boxDistance2(const Eigen::Vector3d& p, const V& lo, const V& hi) {
  double d2 = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double d = std::max({double(lo[i]) - p[i], 0.0, p[i] - double(hi[i])});
    d2 += d * d;
  }
  return d2;
}

struct FacetBox {
  Eigen::Vector3d lo, hi;
};

void facetBoxes(const std::vector<InterfaceFacet>& facets, std::vector<FacetBox>& out) {
  out.clear();
  for (const InterfaceFacet& f : facets) {
    const auto& c = f.corners;
    out.push_back({c[0].cwiseMin(c[1]).cwiseMin(c[2]), c[0].cwiseMax(c[1]).cwiseMax(c[2])});
  }
}

// Whether p lies within sqrt(r2) of a facet of `pair` among `facets`,
// trying first the facet `hint` (the one that held the sample before: the
// samples come cell by cell), and leaving there the one that holds p.
bool nearFacets(const Eigen::Vector3d& p, const std::vector<InterfaceFacet>& facets,
                const std::vector<FacetBox>& boxes, std::int32_t pair, double r2, std::size_t& hint) {
  const std::size_t n = facets.size();
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = (hint + k) % n;
    const InterfaceFacet& f = facets[i];
    if (f.pair != pair || boxDistance2(p, boxes[i].lo, boxes[i].hi) > r2) continue;
    if (pointTriangleDistance2(p, f.corners[0], f.corners[1], f.corners[2]) <= r2) {
      hint = i;
      return true;
    }
  }
  return false;
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
  // larger label when both sides are domain tets).
  struct Facet {
    std::uint64_t key;
    Tri v;
  };
  std::vector<Facet> facets;
  // Seconds on a grid of millions of voxels: the loops poll the
  // cancellation (the process's Ctrl-C, the Python module's interrupt).
  for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (!complex.tetAlive(t) || complex.label(t) <= 0) continue;
    const std::int32_t lt = complex.label(t);
    for (int k = 0; k < 4; ++k) {
      const std::int32_t ln = std::max(complex.label(complex.neighbor(t, k)), 0);
      if (ln >= lt) continue;
      facets.push_back({pairKey(lt, ln), tetFace(complex.tet(t), k)});
    }
  }
  for (const Facet& f : facets) pairKeys_.push_back(f.key);
  sortCancellable(pairKeys_.begin(), pairKeys_.end());
  throwIfCancelled();
  pairKeys_.erase(std::unique(pairKeys_.begin(), pairKeys_.end()), pairKeys_.end());
  auto indexOf = [&](std::uint64_t key) {
    return std::int32_t(std::lower_bound(pairKeys_.begin(), pairKeys_.end(), key) - pairKeys_.begin());
  };

  // Samples, each once per pair: vertices, edge mid-points (a, b, a != b), centroids.
  std::vector<std::tuple<std::int32_t, std::int32_t, std::int32_t>> points;  // pair, a, b (a == b: vertex)
  triangles_.reserve(facets.size());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t n = 0; n < facets.size(); ++n) {
    if (n % 65536 == 0) throwIfCancelled();
    const Facet& f = facets[n];
    const std::int32_t pair = indexOf(f.key);
    Triangle tri;
    tri.pair = pair;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d& x = complex.position(f.v[std::size_t(i)]);
      tri.corners[std::size_t(i)] = x.cast<float>();
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
      const std::int32_t a = f.v[std::size_t(i)], b = f.v[std::size_t((i + 1) % 3)];
      points.emplace_back(pair, a, a);
      points.emplace_back(pair, std::min(a, b), std::max(a, b));
    }
    triangles_.push_back(tri);
  }
  if (triangles_.empty()) lo = hi = Eigen::Vector3d::Zero();
  sortCancellable(points.begin(), points.end());
  throwIfCancelled();
  points.erase(std::unique(points.begin(), points.end()), points.end());
  std::vector<std::pair<Eigen::Vector3f, std::int32_t>> samples;
  samples.reserve(points.size() + triangles_.size());
  for (const auto& [pair, a, b] : points)
    samples.emplace_back((0.5 * (complex.position(a) + complex.position(b))).cast<float>(), pair);
  for (const Triangle& t : triangles_) samples.emplace_back((t.corners[0] + t.corners[1] + t.corners[2]) / 3.0f, t.pair);

  // Triangles in cells of the bound (a query visits at most 27), each in
  // every cell its box meets, sorted by pair within a cell.
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(bound_);
  Cells& tc = triangleCells_;
  tc.cover(lo - margin, hi + margin, bound_);
  tc.start.assign(std::size_t(tc.count() + 1), 0);
  auto forCells = [&](const Triangle& t, const auto& f) {
    const auto a = tc.cellOf(t.corners[0].cwiseMin(t.corners[1]).cwiseMin(t.corners[2]).cast<double>());
    const auto b = tc.cellOf(t.corners[0].cwiseMax(t.corners[1]).cwiseMax(t.corners[2]).cast<double>());
    for (std::int64_t k = a[2]; k <= b[2]; ++k)
      for (std::int64_t j = a[1]; j <= b[1]; ++j)
        for (std::int64_t i = a[0]; i <= b[0]; ++i) f(tc.index(i, j, k));
  };
  throwIfCancelled();
  for (const Triangle& t : triangles_) forCells(t, [&](std::int64_t c) { ++tc.start[std::size_t(c + 1)]; });
  for (std::int64_t c = 0; c < tc.count(); ++c) tc.start[std::size_t(c + 1)] += tc.start[std::size_t(c)];
  tc.items.resize(std::size_t(tc.start.back()));
  {
    std::vector<std::int64_t> fill(tc.start.begin(), tc.start.end() - 1);
    for (std::size_t n = 0; n < triangles_.size(); ++n)
      forCells(triangles_[n], [&](std::int64_t c) { tc.items[std::size_t(fill[std::size_t(c)]++)] = std::int32_t(n); });
  }
  throwIfCancelled();
  for (std::int64_t c = 0; c < tc.count(); ++c, c % 65536 == 0 ? throwIfCancelled() : void())
    std::stable_sort(tc.items.begin() + tc.start[std::size_t(c)], tc.items.begin() + tc.start[std::size_t(c + 1)],
                     [&](std::int32_t x, std::int32_t y) { return triangles_[std::size_t(x)].pair < triangles_[std::size_t(y)].pair; });

  // Samples sorted by cell (half the bound: a run's box is small enough to
  // lie within the bound of one facet as a whole), then by pair; one run per
  // cell and pair.
  Cells& sc = sampleCells_;
  sc.cover(lo - margin, hi + margin, 0.5 * bound_);
  std::vector<std::int64_t> cellOfSample(samples.size());
  std::vector<std::int32_t> order(samples.size());
  for (std::size_t n = 0; n < samples.size(); ++n) {
    const auto c = sc.cellOf(samples[n].first.cast<double>());
    cellOfSample[n] = sc.index(c[0], c[1], c[2]);
    order[n] = std::int32_t(n);
  }
  sortCancellable(order.begin(), order.end(), [&](std::int32_t x, std::int32_t y) {
    return std::tie(cellOfSample[std::size_t(x)], samples[std::size_t(x)].second, x) <
           std::tie(cellOfSample[std::size_t(y)], samples[std::size_t(y)].second, y);
  });
  throwIfCancelled();
  samples_.reserve(samples.size());
  sc.start.assign(std::size_t(sc.count() + 1), 0);
  for (std::size_t n = 0, runs = 0; n < order.size(); ++runs) {
    if (runs % 65536 == 0) throwIfCancelled();
    const std::int64_t cell = cellOfSample[std::size_t(order[n])];
    const std::int32_t pair = samples[std::size_t(order[n])].second;
    SampleRun run{pair, std::int32_t(samples_.size()), 0, samples[std::size_t(order[n])].first,
                  samples[std::size_t(order[n])].first};
    for (; n < order.size() && cellOfSample[std::size_t(order[n])] == cell && samples[std::size_t(order[n])].second == pair; ++n) {
      const Eigen::Vector3f& p = samples[std::size_t(order[n])].first;
      samples_.push_back(p);
      run.lo = run.lo.cwiseMin(p);
      run.hi = run.hi.cwiseMax(p);
    }
    run.last = std::int32_t(samples_.size());
    sc.items.push_back(std::int32_t(runs_.size()));
    runs_.push_back(run);
    ++sc.start[std::size_t(cell + 1)];
  }
  for (std::int64_t c = 0; c < sc.count(); ++c) sc.start[std::size_t(c + 1)] += sc.start[std::size_t(c)];
}

void InterfaceBound::Cells::cover(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double cellSize) {
  origin = lo;
  size = cellSize;
  const double maxCells = double(std::int64_t(1) << 24);
  for (;;) {
    for (int i = 0; i < 3; ++i) dims[std::size_t(i)] = std::int64_t(std::floor((hi[i] - lo[i]) / size)) + 1;
    if (double(dims[0]) * double(dims[1]) * double(dims[2]) <= maxCells) break;
    size *= 2.0;
  }
}

std::array<std::int64_t, 3> InterfaceBound::Cells::cellOf(const Eigen::Vector3d& p) const {
  std::array<std::int64_t, 3> c{};
  for (int i = 0; i < 3; ++i) {
    const double x = std::floor((p[i] - origin[i]) / size);
    c[std::size_t(i)] = std::int64_t(std::clamp(x, 0.0, double(dims[std::size_t(i)] - 1)));
  }
  return c;
}

std::int32_t InterfaceBound::pairIndex(std::int32_t x, std::int32_t y) const {
  const std::uint64_t key = pairKey(x, y);
  const auto it = std::lower_bound(pairKeys_.begin(), pairKeys_.end(), key);
  return it != pairKeys_.end() && *it == key ? std::int32_t(it - pairKeys_.begin()) : -1;
}

template <typename PairOf, typename Visit>
bool InterfaceBound::visitCells(const Cells& cells, std::int32_t pair, const Eigen::Vector3d& lo,
                                const Eigen::Vector3d& hi, const PairOf& pairOf, const Visit& visit) {
  const auto a = cells.cellOf(lo), b = cells.cellOf(hi);
  for (std::int64_t k = a[2]; k <= b[2]; ++k)
    for (std::int64_t j = a[1]; j <= b[1]; ++j)
      for (std::int64_t i = a[0]; i <= b[0]; ++i) {
        const std::int64_t c = cells.index(i, j, k);
        auto first = cells.items.begin() + cells.start[std::size_t(c)];
        const auto last = cells.items.begin() + cells.start[std::size_t(c + 1)];
        if (first == last) continue;
        first = std::partition_point(first, last, [&](std::int32_t x) { return pairOf(x) < pair; });
        for (; first != last && pairOf(*first) == pair; ++first)
          if (visit(*first)) return true;
      }
  return false;
}

bool InterfaceBound::within(std::int32_t pair, const Eigen::Vector3d& p, double r) const {
  if (pair < 0) return false;
  const double r2 = r * r;
  const Eigen::Vector3d d = Eigen::Vector3d::Constant(r);
  auto pairOf = [&](std::int32_t x) { return triangles_[std::size_t(x)].pair; };
  auto visit = [&](std::int32_t x) {
    const auto& c = triangles_[std::size_t(x)].corners;
    const Eigen::Vector3f lo = c[0].cwiseMin(c[1]).cwiseMin(c[2]), hi = c[0].cwiseMax(c[1]).cwiseMax(c[2]);
    if (boxDistance2(p, lo, hi) > r2) return false;
    return pointTriangleDistance2(p, c[0].cast<double>(), c[1].cast<double>(), c[2].cast<double>()) <= r2;
  };
  // p's own cell first: most samples lie next to the input.
  return visitCells(triangleCells_, pair, p, p, pairOf, visit) ||
         visitCells(triangleCells_, pair, p - d, p + d, pairOf, visit);
}

bool InterfaceBound::keeps(const std::vector<InterfaceFacet>& before, const std::vector<InterfaceFacet>& after) const {
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
  for (std::int32_t pair : pairs)
    if (pair >= 0 && !coveredSamples(pair, before, after)) return false;
  return true;
}

bool InterfaceBound::coveredSamples(std::int32_t pair, const std::vector<InterfaceFacet>& before,
                                    const std::vector<InterfaceFacet>& after) const {
  const double r2 = bound_ * bound_;
  thread_local std::vector<FacetBox> beforeBoxes, afterBoxes;
  thread_local std::vector<InterfaceFacet> b, a;
  b.clear();
  a.clear();
  for (const InterfaceFacet& f : before)
    if (f.pair == pair) b.push_back(f);
  for (const InterfaceFacet& f : after)
    if (f.pair == pair) a.push_back(f);
  facetBoxes(b, beforeBoxes);
  facetBoxes(a, afterBoxes);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const FacetBox& box : beforeBoxes) {
    lo = lo.cwiseMin(box.lo);
    hi = hi.cwiseMax(box.hi);
  }
  const Eigen::Vector3d d = Eigen::Vector3d::Constant(bound_);
  std::size_t beforeHint = 0, afterHint = 0;
  auto pairOf = [&](std::int32_t x) { return runs_[std::size_t(x)].pair; };
  // True (stop) at a run with a sample the replaced facets covered and the new ones do not.
  auto visit = [&](std::int32_t x) {
    const SampleRun& run = runs_[std::size_t(x)];
    const Eigen::Vector3d rlo = run.lo.cast<double>(), rhi = run.hi.cast<double>();
    // No replaced facet near the run's box: none of its samples was covered.
    bool near = false;
    for (const FacetBox& box : beforeBoxes) {
      Eigen::Vector3d gap = (box.lo - rhi).cwiseMax(rlo - box.hi).cwiseMax(0.0);
      if (gap.squaredNorm() <= r2) {
        near = true;
        break;
      }
    }
    if (!near) return false;
    // The distance to a triangle is convex: a box whose corners all lie
    // within the bound of one new facet lies within it as a whole.
    for (const InterfaceFacet& f : a) {
      bool all = true;
      for (int corner = 0; corner < 8 && all; ++corner) {
        const Eigen::Vector3d x((corner & 1) ? rhi[0] : rlo[0], (corner & 2) ? rhi[1] : rlo[1], (corner & 4) ? rhi[2] : rlo[2]);
        all = pointTriangleDistance2(x, f.corners[0], f.corners[1], f.corners[2]) <= r2;
      }
      if (all) return false;
    }
    for (std::int32_t n = run.first; n < run.last; ++n) {
      const Eigen::Vector3d s = samples_[std::size_t(n)].cast<double>();
      if (nearFacets(s, b, beforeBoxes, pair, r2, beforeHint) && !nearFacets(s, a, afterBoxes, pair, r2, afterHint))
        return true;
    }
    return false;
  };
  return !visitCells(sampleCells_, pair, lo - d, hi + d, pairOf, visit);
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
