#include "geometry/remesh/flip_edges.h"

#include "geometry/cancellation.h"
#include "geometry/mesh_quality.h"
#include "geometry/remesh/label_set.h"
#include "geometry/remesh/parallel_ranges.h"
#include "geometry/remesh/tet_shape.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <tuple>

namespace vox::remesh {

namespace {
double cosDegrees(double deg) { return std::cos(deg * M_PI / 180.0); }
// Worst dihedral angles under 30 degrees are worth a flip of their own.
constexpr double kPoorAngleCosine = 0.8660254037844387;
}  // namespace

EdgeFlipper::EdgeFlipper(RemeshComplex& complex, const FlipOptions& options) : complex_(complex), options_(options) {}

void EdgeFlipper::fanTowards(std::size_t apex) {
  fan_.clear();
  fanLabels_.clear();
  const std::size_t n = ring_.size();
  const std::int32_t top = ring_.ring[apex];
  for (std::size_t j = 0; j < n; ++j) {
    if (ring_.ring[j] == top || ring_.ring[(j + 1) % n] == top) continue;
    const std::int32_t q = ring_.tets[j];
    Tet withoutA = complex_.tet(q), withoutB = complex_.tet(q);
    withoutA[std::size_t(complex_.localIndex(q, ring_.a))] = top;
    withoutB[std::size_t(complex_.localIndex(q, ring_.b))] = top;
    fan_.push_back(withoutA);
    fan_.push_back(withoutB);
    fanLabels_.push_back(complex_.label(q));
    fanLabels_.push_back(complex_.label(q));
  }
}

double EdgeFlipper::fanWorstCosine(double bound) const {
  const auto& P = complex_.positions();
  double worst = -1.0;
  for (const Tet& q : fan_) {
    const Eigen::Vector3d& a = P[std::size_t(q[0])];
    const Eigen::Vector3d& b = P[std::size_t(q[1])];
    const Eigen::Vector3d& c = P[std::size_t(q[2])];
    const Eigen::Vector3d& d = P[std::size_t(q[3])];
    if (!(signedVolume(a, b, c, d) > 0.0) || !(volumeLengthQuality(a, b, c, d) > kQualityFloor))
      return std::numeric_limits<double>::infinity();
    worst = std::max(worst, minDihedralCosine(a, b, c, d));
    if (worst >= bound) return worst;  // cannot win any more
  }
  return worst;
}

bool EdgeFlipper::fanCreatesExistingEdge(std::size_t apex) {
  const std::size_t n = ring_.size();
  const std::int32_t top = ring_.ring[apex];
  walker_.incidentTets(complex_, top, star_);
  if (n == 3) {
    // 3-2: the new facet must not exist yet.
    const std::int32_t x = ring_.ring[(apex + 1) % n], y = ring_.ring[(apex + 2) % n];
    for (std::int32_t q : star_)
      if (complex_.localIndex(q, x) >= 0 && complex_.localIndex(q, y) >= 0) return true;
    return false;
  }
  for (std::int32_t q : star_)
    for (std::int32_t w : complex_.tet(q))
      for (std::size_t j = 0; j < n; ++j) {
        if (j == apex || j == (apex + 1) % n || j == (apex + n - 1) % n) continue;
        if (ring_.ring[j] == w) return true;
      }
  return false;
}

double EdgeFlipper::tetWorstCosine(std::int32_t q) const {
  return worst_ ? (*worst_)[std::size_t(q)] : complex_.minDihedralCosineOf(q);
}

bool EdgeFlipper::ringNearPinch() const {
  // A flip joins ring vertices: none may be a copy of a pinched vertex
  // (see RemeshComplex::pinchOf).
  if (!complex_.hasPinches()) return false;
  for (std::int32_t w : ring_.ring)
    if (complex_.pinchOf(w) >= 0) return true;
  return false;
}

bool EdgeFlipper::tryFlipInnerEdge(std::int32_t a, std::int32_t b, bool apply, std::uint8_t* apex) {
  if (a == complex_.dummyVertex() || b == complex_.dummyVertex()) return false;
  if (complex_.features().lineOf(a, b) >= 0) return false;
  if (!complex_.vertexAlive(a) || !complex_.vertexAlive(b)) return false;
  const std::int32_t t = walker_.findEdgeTet(complex_, a, b);
  if (t < 0) return false;
  complex_.edgeRing(a, b, t, ring_);
  const std::size_t n = ring_.size();
  if (n > std::size_t(options_.maxRing)) return false;
  if (ringNearPinch()) return false;
  const std::int32_t label = complex_.label(ring_.tets[0]);
  for (std::int32_t q : ring_.tets)
    if (complex_.label(q) != label || complex_.isDummyTet(q)) return false;
  double current = -1.0;
  for (std::int32_t q : ring_.tets) current = std::max(current, tetWorstCosine(q));
  // Candidate fans, best worst-angle first.
  thread_local std::vector<std::pair<double, std::size_t>> choices;
  choices.clear();
  const std::size_t configurations = n == 3 ? 1 : n == 4 ? 2 : n;
  for (std::size_t k = 0; k < configurations; ++k) {
    fanTowards(k);
    const double worst = fanWorstCosine(current - 1e-9);
    if (worst < current - 1e-9) choices.push_back({worst, k});
  }
  std::sort(choices.begin(), choices.end());
  for (const auto& [worst, k] : choices) {
    if (fanCreatesExistingEdge(k)) continue;
    if (apex) *apex = std::uint8_t(k);
    if (!apply) return true;
    fanTowards(k);
    complex_.replaceTets(ring_.tets, fan_, fanLabels_, scratch_);
    return true;
  }
  return false;
}

std::pair<int, int> EdgeFlipper::boundaryValence(std::int32_t v, std::int32_t x, std::int32_t y) {
  // Edges of v on the x|y interface: sides of the boundary facets around v.
  walker_.incidentTets(complex_, v, star_);
  thread_local std::vector<std::int32_t> others;
  others.clear();
  LabelSet labels;
  for (std::int32_t q : star_) {
    const std::int32_t l = complex_.label(q);
    labels.insert(l);
    if (l != x) continue;
    for (int k = 0; k < 4; ++k) {
      const std::int32_t w = complex_.tet(q)[std::size_t(k)];
      if (w == v || complex_.label(complex_.neighbor(q, k)) != y) continue;
      for (std::int32_t u : complex_.tet(q))
        if (u != v && u != w) others.push_back(u);
    }
  }
  std::sort(others.begin(), others.end());
  return {int(std::unique(others.begin(), others.end()) - others.begin()), labels.size()};
}

bool EdgeFlipper::tryFlipSurfaceEdge(std::int32_t a, std::int32_t b, bool apply, std::uint8_t* apex) {
  if (a == complex_.dummyVertex() || b == complex_.dummyVertex()) return false;
  if (complex_.features().lineOf(a, b) >= 0) return false;
  if (!complex_.vertexAlive(a) || !complex_.vertexAlive(b)) return false;
  const std::int32_t t = walker_.findEdgeTet(complex_, a, b);
  if (t < 0) return false;
  complex_.edgeRing(a, b, t, ring_);
  const std::size_t n = ring_.size();
  if (n < 4 || n > std::size_t(options_.maxRing)) return false;
  if (ringNearPinch()) return false;
  // Exactly two label changes around the edge: the boundary facets (a,b,c)
  // and (a,b,d), each arc at least two tets so (c, d) is not a ring edge.
  std::size_t change[2], changes = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (complex_.isDummyTet(ring_.tets[i])) return false;
    if (complex_.label(ring_.tets[(i + n - 1) % n]) != complex_.label(ring_.tets[i])) {
      if (changes == 2) return false;
      change[changes++] = i;
    }
  }
  if (changes != 2) return false;
  const std::size_t arc = change[1] - change[0];
  if (arc < 2 || n - arc < 2) return false;
  const std::int32_t x = complex_.label(ring_.tets[change[0]]), y = complex_.label(ring_.tets[change[1]]);
  const std::int32_t c = ring_.ring[change[0]], d = ring_.ring[change[1]];

  // The interface must be nearly flat across the edge, before and after.
  const auto& P = complex_.positions();
  auto facetNormal = [&](std::int32_t p, std::int32_t q, std::int32_t r, std::int32_t xSide) {
    Eigen::Vector3d nrm = (P[std::size_t(q)] - P[std::size_t(p)]).cross(P[std::size_t(r)] - P[std::size_t(p)]);
    if (nrm.dot(P[std::size_t(xSide)] - P[std::size_t(p)]) > 0.0) nrm = -nrm;
    return nrm.normalized();
  };
  const Eigen::Vector3d n1 = facetNormal(a, b, c, ring_.ring[(change[0] + 1) % n]);
  const Eigen::Vector3d n2 = facetNormal(a, b, d, ring_.ring[(change[1] + n - 1) % n]);
  const double bend = cosDegrees(options_.surfaceFlipMaxBend);
  if (!(n1.dot(n2) >= bend)) return false;
  const Eigen::Vector3d mean = (n1 + n2).normalized();
  for (std::int32_t e : {a, b}) {
    Eigen::Vector3d m = (P[std::size_t(c)] - P[std::size_t(e)]).cross(P[std::size_t(d)] - P[std::size_t(e)]).normalized();
    if (m.dot(mean) < 0.0) m = -m;
    if (!(m.dot(mean) >= bend)) return false;
  }

  double current = -1.0;
  for (std::int32_t q : ring_.tets) current = std::max(current, tetWorstCosine(q));
  // The better of the (one or two) fans towards the boundary facets' apexes.
  double best = std::numeric_limits<double>::infinity();
  std::size_t bestApex = n;
  for (std::size_t apex : {change[0], change[1]}) {
    if (n == 4 && apex == change[1]) break;  // the same fan
    fanTowards(apex);
    const double worst = fanWorstCosine(best);
    if (worst < best) {
      best = worst;
      bestApex = apex;
    }
  }
  if (bestApex == n) return false;

  // Flip when it evens the valences of this interface (against 6 for
  // surface vertices, 4 for feature vertices) without making the worst
  // angle worse than 20 degrees, or when it lifts a worst angle under 30.
  const bool removesSliver = current > kPoorAngleCosine && best < current - 1e-3;
  if (!removesSliver) {
    if (best > std::max(current, cosDegrees(20.0))) return false;
    const std::int32_t vertices[4] = {a, b, c, d};
    const int delta[4] = {-1, -1, +1, +1};
    int before = 0, after = 0;
    for (int i = 0; i < 4; ++i) {
      const auto [valence, labels] = boundaryValence(vertices[i], x, y);
      const int target = labels == 2 ? 6 : 4;
      before += (valence - target) * (valence - target);
      after += (valence + delta[i] - target) * (valence + delta[i] - target);
    }
    if (after >= before) return false;
  }
  if (fanCreatesExistingEdge(bestApex)) return false;
  if (bestApex == n) return false;
  if (options_.interfaces && !removesSliver) {
    // The facets (a, b, c), (a, b, d) become (c, d, a), (c, d, b): a flip
    // for the valences keeps the bound; one that removes a sliver may cross it.
    const std::int32_t pair = options_.interfaces->pairIndex(x, y);
    auto facet = [&](std::int32_t p, std::int32_t q, std::int32_t r) {
      return InterfaceFacet{pair, {P[std::size_t(p)], P[std::size_t(q)], P[std::size_t(r)]}};
    };
    if (!options_.interfaces->keeps({facet(a, b, c), facet(a, b, d)}, {facet(c, d, a), facet(c, d, b)})) return false;
  }
  if (apex) *apex = std::uint8_t(bestApex);
  if (!apply) return true;
  fanTowards(bestApex);
  complex_.replaceTets(ring_.tets, fan_, fanLabels_, scratch_);
  return true;
}

bool EdgeFlipper::applyEdgePlan(std::int32_t a, std::int32_t b, std::uint8_t apex, const std::vector<char>& touched) {
  if (touched[std::size_t(a)] || touched[std::size_t(b)] || !complex_.vertexAlive(a) || !complex_.vertexAlive(b))
    return false;
  // Stars of a and b unchanged: the same ring, in the same order.
  complex_.edgeRing(a, b, walker_.findEdgeTet(complex_, a, b), ring_);
  for (std::int32_t w : ring_.ring)
    if (touched[std::size_t(w)]) return false;
  fanTowards(apex);
  complex_.replaceTets(ring_.tets, fan_, fanLabels_, scratch_);
  return true;
}

bool EdgeFlipper::tryFlipFace(std::int32_t t, int k, bool apply) {
  // 2-3 flip: the two tets on either side of a facet that is no interface
  // become three around the edge joining their apexes.
  if (!complex_.tetAlive(t) || complex_.isDummyTet(t)) return false;
  const std::int32_t n = complex_.neighbor(t, k);
  if (complex_.isDummyTet(n) || complex_.label(n) != complex_.label(t)) return false;
  const std::int32_t apexT = complex_.tet(t)[std::size_t(k)];
  const std::int32_t apexN = complex_.tet(n)[std::size_t(complex_.neighborFace(t, k))];
  if (complex_.pinchOf(apexT) >= 0 || complex_.pinchOf(apexN) >= 0) return false;  // see RemeshComplex::pinchOf
  const double current = std::max(tetWorstCosine(t), tetWorstCosine(n));
  fan_.clear();
  fanLabels_.clear();
  for (int i = 0; i < 4; ++i) {
    if (i == k) continue;
    Tet q = complex_.tet(t);
    q[std::size_t(i)] = apexN;  // t with one facet vertex replaced by the other apex
    fan_.push_back(q);
    fanLabels_.push_back(complex_.label(t));
  }
  if (!(fanWorstCosine(current - 1e-3) < current - 1e-3)) return false;
  walker_.incidentTets(complex_, apexT, star_);
  for (std::int32_t q : star_)
    if (complex_.localIndex(q, apexN) >= 0) return false;  // the new edge exists already
  if (apply) complex_.replaceTets({t, n}, fan_, fanLabels_, scratch_);
  return true;
}

namespace {
// Worst dihedral cosine of every geometric tet (2 elsewhere), in parallel.
void worstCosines(const RemeshComplex& complex, int threads, std::vector<double>& out) {
  out.assign(std::size_t(complex.tetSlots()), 2.0);
  parallelRanges(complex.tetSlots(), threads, [&](std::int64_t b, std::int64_t e) {
    for (std::int32_t t = std::int32_t(b); t < std::int32_t(e); ++t) {
      if (t % 65536 == 0) throwIfCancelled();
      if (complex.tetAlive(t) && !complex.isDummyTet(t)) out[std::size_t(t)] = complex.minDihedralCosineOf(t);
    }
  });
}
}  // namespace

// Finds on all threads (read-only) which candidate edges a flip would take
// on the complex as it is now (`worst`: its tets' worst dihedral cosines),
// and towards which apex. Then applies them in
// order: as screened (the apex found then) while no
// flip has touched the edge's end points or ring, re-checked otherwise, so
// the result is that of checking every flip in turn. Returns the flips.
template <typename Try>
std::size_t screenAndFlip(RemeshComplex& complex, const FlipOptions& options, EdgeFlipper& flipper,
                          std::vector<std::pair<std::int32_t, std::int32_t>>& edges, const std::vector<double>& worst,
                          const Try& tryFlip) {
  constexpr std::uint8_t kNone = 0xFF;
  std::vector<std::uint8_t> apex(edges.size(), kNone);
  parallelRanges(std::int64_t(edges.size()), options.threads, [&](std::int64_t b, std::int64_t e) {
    EdgeFlipper f(complex, options);
    f.useWorstCosines(&worst);
    for (std::int64_t i = b; i < e; ++i) {
      throwIfCancelled();
      tryFlip(f, edges[std::size_t(i)].first, edges[std::size_t(i)].second, false, &apex[std::size_t(i)]);
    }
  });
  std::vector<char> touched(std::size_t(complex.vertexSlots()), 0);
  std::size_t flips = 0;
  for (std::size_t i = 0; i < edges.size(); ++i) {
    throwIfCancelled();
    if (apex[i] == kNone) continue;
    const auto [a, b] = edges[i];
    if (!flipper.applyEdgePlan(a, b, apex[i], touched) && !tryFlip(flipper, a, b, true, nullptr)) continue;
    ++flips;
    touched[std::size_t(a)] = touched[std::size_t(b)] = 1;
    for (std::int32_t w : flipper.lastRing().ring) touched[std::size_t(w)] = 1;
  }
  return flips;
}

FlipCounts flipEdges(RemeshComplex& complex, const FlipOptions& options) {
  FlipCounts counts;
  EdgeFlipper flipper(complex, options);
  std::vector<double> worst;

  // Surface edges: sides of boundary facets between two geometric tets.
  std::vector<std::pair<std::int32_t, std::int32_t>> edges;
  std::mutex gather;
  parallelRanges(complex.tetSlots(), options.threads, [&](std::int64_t begin, std::int64_t end) {
    std::vector<std::pair<std::int32_t, std::int32_t>> found;
    for (std::int32_t t = std::int32_t(begin); t < std::int32_t(end); ++t) {
      if (t % 65536 == 0) throwIfCancelled();
      if (!complex.tetAlive(t) || complex.isDummyTet(t)) continue;
      for (int k = 0; k < 4; ++k) {
        const std::int32_t n = complex.neighbor(t, k);
        if (n < t || complex.label(n) == complex.label(t) || complex.isDummyTet(n)) continue;
        const Tri f = tetFace(complex.tet(t), k);
        for (int e = 0; e < 3; ++e)
          found.push_back({std::min(f[std::size_t(e)], f[std::size_t((e + 1) % 3)]),
                           std::max(f[std::size_t(e)], f[std::size_t((e + 1) % 3)])});
      }
    }
    std::lock_guard lock(gather);
    edges.insert(edges.end(), found.begin(), found.end());
  });
  sortCancellable(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  worstCosines(complex, options.threads, worst);
  counts.surface = screenAndFlip(complex, options, flipper, edges, worst,
                                 [](EdgeFlipper& f, std::int32_t a, std::int32_t b, bool apply, std::uint8_t* apex) {
                                   return f.tryFlipSurfaceEdge(a, b, apply, apex);
                                 });

  // Inner edges of poor tets, worst tets first.
  const double threshold = cosDegrees(options.innerFlipAngle);
  // The imaginary layer is not output: its tets are candidates only where
  // they touch the domain (their shape limits how its boundary can move).
  std::vector<char> nearDomain(std::size_t(complex.vertexSlots()), 0);
  for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (complex.tetAlive(t) && complex.label(t) > 0)
      for (std::int32_t v : complex.tet(t)) nearDomain[std::size_t(v)] = 1;
  }
  auto candidate = [&](std::int32_t t) {
    if (complex.label(t) > 0) return true;
    for (std::int32_t v : complex.tet(t))
      if (nearDomain[std::size_t(v)]) return true;
    return false;
  };
  using Candidate = std::tuple<double, std::int32_t, std::int32_t>;
  std::vector<Candidate> candidates;
  worstCosines(complex, options.threads, worst);
  // Gathered on all threads in any order: the sorts below order them fully.
  parallelRanges(complex.tetSlots(), options.threads, [&](std::int64_t begin, std::int64_t end) {
    std::vector<Candidate> found;
    const auto& P = complex.positions();
    for (std::int32_t t = std::int32_t(begin); t < std::int32_t(end); ++t) {
      if (t % 65536 == 0) throwIfCancelled();
      const double w = worst[std::size_t(t)];
      if (w <= threshold || w > 1.5 || !candidate(t)) continue;
      // The edges at its largest dihedral angles: removing either one
      // takes a sliver apart (thesis 2.3.6); caps are left to face flips.
      const Tet& q = complex.tet(t);
      const auto angles =
          dihedralAngles(P[std::size_t(q[0])], P[std::size_t(q[1])], P[std::size_t(q[2])], P[std::size_t(q[3])]);
      static constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
      int order[6] = {0, 1, 2, 3, 4, 5};
      std::sort(order, order + 6, [&](int x, int y) {
        return angles[std::size_t(x)] > angles[std::size_t(y)] || (angles[std::size_t(x)] == angles[std::size_t(y)] && x < y);
      });
      for (int k = 0; k < options.edgesPerPoorTet; ++k) {
        const std::int32_t a = q[std::size_t(kEdge[order[k]][0])], b = q[std::size_t(kEdge[order[k]][1])];
        found.push_back({-w, std::min(a, b), std::max(a, b)});
      }
    }
    std::lock_guard lock(gather);
    candidates.insert(candidates.end(), found.begin(), found.end());
  });
  // Each edge once, at its worst tet's key; worst first.
  sortCancellable(candidates.begin(), candidates.end(), [](const auto& x, const auto& y) {
    return std::tie(std::get<1>(x), std::get<2>(x), std::get<0>(x)) < std::tie(std::get<1>(y), std::get<2>(y), std::get<0>(y));
  });
  candidates.erase(std::unique(candidates.begin(), candidates.end(),
                               [](const auto& x, const auto& y) {
                                 return std::get<1>(x) == std::get<1>(y) && std::get<2>(x) == std::get<2>(y);
                               }),
                   candidates.end());
  sortCancellable(candidates.begin(), candidates.end());
  edges.clear();
  for (const auto& [w, a, b] : candidates) edges.push_back({a, b});
  counts.inner = screenAndFlip(complex, options, flipper, edges, worst,
                               [](EdgeFlipper& f, std::int32_t a, std::int32_t b, bool apply, std::uint8_t* apex) {
                                 return f.tryFlipInnerEdge(a, b, apply, apex);
                               });

  // Face flips for the slivers and caps that are left.
  std::vector<std::pair<double, std::int32_t>> poor;
  worstCosines(complex, options.threads, worst);
  for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (worst[std::size_t(t)] > threshold && worst[std::size_t(t)] < 1.5 && candidate(t)) poor.push_back({-worst[std::size_t(t)], t});
  }
  sortCancellable(poor.begin(), poor.end());
  {
    std::vector<char> any(poor.size(), 0);
    parallelRanges(std::int64_t(poor.size()), options.threads, [&](std::int64_t b, std::int64_t e) {
      EdgeFlipper f(complex, options);
      f.useWorstCosines(&worst);
      for (std::int64_t i = b; i < e; ++i) {
        throwIfCancelled();
        for (int k = 0; k < 4 && !any[std::size_t(i)]; ++k) any[std::size_t(i)] = f.tryFlipFace(poor[std::size_t(i)].second, k, false);
      }
    });
    std::size_t kept = 0;
    for (std::size_t i = 0; i < poor.size(); ++i)
      if (any[i]) poor[kept++] = poor[i];
    poor.resize(kept);
  }
  for (const auto& [w, t] : poor) {
    throwIfCancelled();
    for (int k = 0; k < 4; ++k)
      if (flipper.tryFlipFace(t, k)) {
        ++counts.face;
        break;
      }
  }
  return counts;
}

}  // namespace vox::remesh
