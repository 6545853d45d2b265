#include "geometry/remesh/collapse_short_edges.h"

#include "geometry/cancellation.h"
#include "geometry/remesh/mesh_edges.h"
#include "geometry/remesh/parallel_ranges.h"
#include "geometry/remesh/tet_shape.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace vox::remesh {

namespace {
const double kGuardCosine = std::cos(kCollapseMinDihedral * M_PI / 180.0);
const double kGuardQuality = 2.0 * std::sin(kCollapseMinDihedral * M_PI / 180.0);
constexpr double kUnknownCosine = 3.0;
}  // namespace

EdgeCollapser::EdgeCollapser(RemeshComplex& complex, const EdgeLengthBounds& bounds, const HullConstraint& hull,
                             const InterfaceBound* interfaces)
    : complex_(complex), bounds_(bounds), hull_(hull), interfaces_(interfaces) {}

const LabelSet& EdgeCollapser::edgeLabels(const VertexNeighborhood& n, std::int32_t w) const {
  return n.edgeLabels[std::size_t(n.find(w))];
}

std::int32_t EdgeCollapser::tryCollapse(std::int32_t u, std::int32_t v, bool apply, CollapseMove* move) {
  if (move) *move = CollapseMove::None;
  const std::int32_t dummy = complex_.dummyVertex();
  if (u == v || u == dummy || v == dummy || !complex_.vertexAlive(u) || !complex_.vertexAlive(v)) return -1;
  // The first tet of u's star (in the walk's order) holding v: the edge
  // ring starts where StarWalker::findEdgeTet would start it.
  starOf(u, nu_.tets);
  std::int32_t t = -1;
  for (std::int32_t q : nu_.tets)
    if (complex_.localIndex(q, v) >= 0) {
      t = q;
      break;
    }
  if (t < 0) return -1;
  complex_.edgeRing(u, v, t, ring_);
  LabelSet suv;
  for (std::int32_t q : ring_.tets) suv.insert(complex_.label(q));
  starOf(v, nv_.tets);
  auto labelsOf = [&](const std::vector<std::int32_t>& tets) {
    LabelSet s;
    for (std::int32_t q : tets) s.insert(complex_.label(q));
    return s;
  };
  if (suv.overflow() || (!(labelsOf(nu_.tets) == suv) && !(labelsOf(nv_.tets) == suv))) return -1;
  if (!anyPositionKeepsEdgesShort()) return -1;
  if (classifiedU_ != u || classifiedAfter_ != collapses_) {
    classifyNeighborhood(complex_, u, nu_);
    classifiedU_ = u;
    classifiedAfter_ = collapses_;
  }
  classifyNeighborhood(complex_, v, nv_);
  const EdgeRule rule = edgeRule(nu_, nv_, suv, dummy);
  if (rule.condition == EdgeCondition::Exclusion) return -1;
  if (complex_.hasPinches() && nearPinch()) return -1;
  if (!topologyTests(suv) || !linkCondition()) return -1;
  if (mergesTaggedEdges(u, v)) return -1;

  worstBefore_[0] = worstBefore_[1] = kUnknownCosine;

  const Eigen::Vector3d pu = complex_.position(u), pv = complex_.position(v);
  struct Option {
    const VertexNeighborhood* removed;
    const VertexNeighborhood* kept;
    Eigen::Vector3d p;
    CollapseMove move;
  };
  Option options[3];
  int count = 0;
  if (rule.condition == EdgeCondition::Similarity) {
    options[count++] = {&nu_, &nv_, 0.5 * (pu + pv), CollapseMove::ToMidpoint};
    options[count++] = {&nu_, &nv_, pv, CollapseMove::UOntoV};
    options[count++] = {&nv_, &nu_, pu, CollapseMove::VOntoU};
  } else if (rule.moving == u) {
    options[count++] = {&nu_, &nv_, pv, CollapseMove::UOntoV};
  } else {
    options[count++] = {&nv_, &nu_, pu, CollapseMove::VOntoU};
  }
  const HullConstraint::Planes planes[2] = {hull_.planes(complex_, nu_), hull_.planes(complex_, nv_)};
  for (int i = 0; i < count; ++i) {
    const Option& o = options[i];
    const VertexNeighborhood& r = *o.removed;
    const VertexNeighborhood& k = *o.kept;
    const bool keptMoves = o.p != complex_.position(k.vertex);
    if (r.onHull() && !hull_.allows(planes[&r == &nu_ ? 0 : 1], o.p)) continue;
    if (keptMoves && k.onHull() && !hull_.allows(planes[&k == &nu_ ? 0 : 1], o.p)) continue;
    if (!test2NoLongEdges(r, k, o.p) || !test1PositiveVolumes(r, k, o.p)) continue;
    if (!keepsTaggedLine(r, k, o.p)) continue;
    if (!keepsInterfaces(r, k, o.p)) continue;
    if (move) *move = o.move;
    if (apply) collapse(r, k, o.p);
    return k.vertex;
  }
  return -1;
}

bool EdgeCollapser::keepsTaggedLine(const VertexNeighborhood& r, const VertexNeighborhood& k,
                                    const Eigen::Vector3d& p) const {
  if (r.featureLine < 0 || !r.taggedEdgeTo(k.vertex)) return true;
  // The line's new edges at p: to r's other neighbour on the line, and to
  // k's when k moves. They must pass within a sixteenth of e_min (l / 20)
  // of the input line's points nearest to the vertices they replace, so
  // that the line coarsened towards l stays within 0.1 l of the input.
  auto pos = [&](std::int32_t w) { return complex_.position(w); };
  const std::int32_t wr = r.tagged[0] == k.vertex ? r.tagged[1] : r.tagged[0];
  FeatureSegment edges[2] = {{pos(wr), p}, {p, p}};
  const bool kMoves = p != pos(k.vertex);
  if (kMoves && k.featureLine >= 0) edges[1][1] = pos(k.tagged[0] == r.vertex ? k.tagged[1] : k.tagged[0]);
  const double tolerance = std::sqrt(bounds_.emin2(pos(r.vertex), pos(k.vertex))) / 16.0;
  auto near = [&](const Eigen::Vector3d& x) {
    for (const FeatureSegment& e : edges) {
      const Eigen::Vector3d d = e[1] - e[0];
      const double t = d.squaredNorm() > 0.0 ? std::clamp((x - e[0]).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      if ((e[0] + t * d - x).norm() <= tolerance) return true;
    }
    return false;
  };
  const FeatureEdges& features = complex_.features();
  return near(features.projectOnLine(r.featureLine, pos(r.vertex))) &&
         (!kMoves || near(k.featureLine >= 0 ? features.projectOnLine(k.featureLine, pos(k.vertex)) : pos(k.vertex)));
}

bool EdgeCollapser::keepsInterfaces(const VertexNeighborhood& r, const VertexNeighborhood& k,
                                    const Eigen::Vector3d& p) const {
  if (!interfaces_) return true;
  const bool keptMoves = p != complex_.position(k.vertex);
  auto onInterface = [](const VertexNeighborhood& nb) {
    int labels = 0;
    for (std::int32_t l : nb.labels) labels += l >= 0;
    return labels >= 2;
  };
  if (!onInterface(r) && !onInterface(k)) return true;
  // The interface facets through r and k before the collapse, and through
  // k after it (r's tets joined to k at p, the ring's tets gone: a facet
  // that faced a ring tet faces the tet beyond it), each taken from its side
  // of the larger label. An interface facet after it that was there before
  // (same vertices, same labels) is unchanged.
  struct Facet {
    std::array<std::int32_t, 3> ids;  // sorted, r renamed k
    InterfaceFacet facet;
  };
  thread_local std::vector<Facet> before, after;
  before.clear();
  after.clear();
  const std::int32_t rv = r.vertex, kv = k.vertex;
  auto gather = [&](const VertexNeighborhood& nb, bool collapsed, std::vector<Facet>& out) {
    const std::int32_t x = nb.vertex;
    for (std::int32_t q : nb.tets) {
      const std::int32_t lq = complex_.label(q);
      if (lq <= 0) continue;
      if (collapsed && complex_.localIndex(q, rv) >= 0 && complex_.localIndex(q, kv) >= 0) continue;  // a ring tet
      const Tet& t = complex_.tet(q);
      for (int f = 0; f < 4; ++f) {
        if (t[std::size_t(f)] == x) continue;  // the facet opposite x
        std::int32_t n = complex_.neighbor(q, f);
        if (collapsed && complex_.localIndex(n, rv) >= 0 && complex_.localIndex(n, kv) >= 0)
          n = complex_.neighbor(n, complex_.localIndex(n, x));
        const std::int32_t ln = std::max(complex_.label(n), 0);
        if (ln >= lq) continue;
        Facet out1;
        const Tri v = tetFace(t, f);
        for (int i = 0; i < 3; ++i) {
          const std::int32_t w = v[std::size_t(i)];
          const bool moved = collapsed && (w == rv || w == kv);
          out1.ids[std::size_t(i)] = collapsed && w == rv ? kv : w;
          out1.facet.corners[std::size_t(i)] = moved ? p : complex_.position(w);
        }
        std::sort(out1.ids.begin(), out1.ids.end());
        out1.facet.pair = interfaces_->pairIndex(lq, ln);
        out.push_back(out1);
      }
    }
  };
  gather(r, false, before);
  gather(k, false, before);
  gather(r, true, after);
  gather(k, true, after);
  thread_local std::vector<InterfaceFacet> replaced, replacing;
  replaced.clear();
  replacing.clear();
  for (const Facet& f : before) replaced.push_back(f.facet);
  for (Facet& f : after) {
    if (!keptMoves)
      for (const Facet& b : before)
        if (b.ids == f.ids && b.facet.pair == f.facet.pair) f.facet.changed = false;
    replacing.push_back(f.facet);
  }
  return interfaces_->keeps(replaced, replacing);
}

bool EdgeCollapser::mergesTaggedEdges(std::int32_t u, std::int32_t v) const {
  // A common neighbour w with (u, w) and (v, w) both tagged: the collapse
  // would fold a tagged line onto itself (the Figure 2.16 case of a line).
  const FeatureEdges& features = complex_.features();
  if (features.degree(u) == 0 || features.degree(v) == 0) return false;
  for (std::int32_t w : ring_.ring)
    if (features.lineOf(u, w) >= 0 && features.lineOf(v, w) >= 0) return true;
  return false;
}

bool EdgeCollapser::nearPinch() const {
  // The kept vertex gets the removed one's neighbours: next to a copy of a
  // pinched vertex that could join two copies (see RemeshComplex::pinchOf).
  for (const VertexNeighborhood* n : {&nu_, &nv_}) {
    if (complex_.pinchOf(n->vertex) >= 0) return true;
    for (std::int32_t w : n->neighbors)
      if (complex_.pinchOf(w) >= 0) return true;
  }
  return false;
}

bool EdgeCollapser::anyPositionKeepsEdgesShort() const {
  // Test 2 for the three positions a collapse may take (either end point or
  // the mid-point), from the two stars alone: most short edges that cannot
  // be collapsed fail here, before any classification.
  const std::int32_t u = ring_.a, v = ring_.b, dummy = complex_.dummyVertex();
  const Eigen::Vector3d pu = complex_.position(u), pv = complex_.position(v), mid = 0.5 * (pu + pv);
  bool toV = true, toU = true, toMid = true;
  auto holds = [&](const std::vector<std::int32_t>& tets, std::int32_t w) {
    for (std::int32_t q : tets)
      if (complex_.localIndex(q, w) >= 0) return true;
    return false;
  };
  auto scan = [&](const std::vector<std::int32_t>& tets, const std::vector<std::int32_t>& otherTets, std::int32_t self,
                  std::int32_t other, bool& toOther) {
    for (std::int32_t q : tets) {
      if (!toMid && !toOther) return;  // nothing left for this star to decide
      for (std::int32_t w : complex_.tet(q)) {
        if (w == self || w == other || w == dummy) continue;
        const Eigen::Vector3d& pw = complex_.position(w);
        if (toMid && bounds_.reachesEmax(pw, mid, (pw - mid).squaredNorm())) toMid = false;
        // Moving `self` onto `other` creates (other, w) unless it exists.
        const Eigen::Vector3d& po = complex_.position(other);
        if (toOther && bounds_.reachesEmax(pw, po, (pw - po).squaredNorm()) && !holds(otherTets, w)) toOther = false;
      }
    }
  };
  scan(nu_.tets, nv_.tets, u, v, toV);
  scan(nv_.tets, nu_.tets, v, u, toU);
  return toV || toU || toMid;
}

bool EdgeCollapser::topologyTests(const LabelSet& suv) const {
  // Tests 3 and 4 (Figure 2.16), on the facets (u, v, c) around the edge.
  const bool boundaryEdge = suv.size() >= 2, featureEdge = suv.size() >= 3;
  if (!boundaryEdge) return true;
  const std::size_t n = ring_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t c = ring_.ring[i];
    const std::int32_t l0 = complex_.label(ring_.tets[(i + n - 1) % n]), l1 = complex_.label(ring_.tets[i]);
    const int uc = edgeLabels(nu_, c).size(), vc = edgeLabels(nv_, c).size();
    if (l0 == l1 && uc >= 2 && vc >= 2) return false;                   // 3: pinched boundary
    if (featureEdge && l0 != l1 && uc >= 3 && vc >= 3) return false;  // 4: 1-junction shortcut
  }
  return true;
}

bool EdgeCollapser::linkCondition() const {
  // Lk(u) and Lk(v) may only share Lk(uv) -- in the whole complex and in the
  // closure of every set of labels (each K_X and their intersections) -- and
  // the simplices merged by the contraction must carry nested label sets, so
  // that every such subcomplex after the collapse is the contraction of the
  // one before (Dey et al. 1999; Attali et al. 2012: homotopy preserved).
  const std::size_t n = ring_.size();
  const std::int32_t u = nu_.vertex, v = nv_.vertex;
  // Position in the ring of each one-ring vertex of u and of v, by slot.
  thread_local std::vector<int> ringOfU, ringOfV;
  ringOfU.assign(nu_.neighbors.size(), -1);
  ringOfV.assign(nv_.neighbors.size(), -1);
  for (std::size_t i = 0; i < n; ++i) {
    ringOfU[std::size_t(nu_.find(ring_.ring[i]))] = int(i);
    ringOfV[std::size_t(nv_.find(ring_.ring[i]))] = int(i);
  }
  auto ringIndex = [&](const VertexNeighborhood& nb, std::int32_t w) {
    const int slot = nb.find(w);
    if (slot < 0) return -1;
    return (&nb == &nu_ ? ringOfU : ringOfV)[std::size_t(slot)];
  };
  // Vertices: the common neighbours of u and v are exactly the ring.
  std::size_t common = 0;
  for (std::size_t i = 0; i < nu_.neighbors.size(); ++i) {
    const std::int32_t w = nu_.neighbors[i];
    if (w != v && nv_.find(w) >= 0) {
      if (ringOfU[i] < 0) return false;
      ++common;
    }
  }
  if (common != n) return false;
  // Label sets of the edges (u, c) and (v, c) that merge into one.
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t c = ring_.ring[i];
    LabelSet suvc;
    suvc.insert(complex_.label(ring_.tets[(i + n - 1) % n]));
    suvc.insert(complex_.label(ring_.tets[i]));
    const LabelSet& suc = edgeLabels(nu_, c);
    const LabelSet& svc = edgeLabels(nv_, c);
    if (!suc.intersection(svc).subsetOf(suvc)) return false;
    if (!suc.subsetOf(svc) && !svc.subsetOf(suc)) return false;
  }
  // Facets (u, c, d) and (v, c, d) merge: one of the two tets beyond them
  // must carry the label of the removed tet (u, v, c, d), or that label
  // would vanish from the merged facet and from the edge (c, d).
  for (std::int32_t q : ring_.tets) {
    const std::int32_t l = complex_.label(q);
    const std::int32_t beyondU = complex_.neighbor(q, complex_.localIndex(q, v));
    const std::int32_t beyondV = complex_.neighbor(q, complex_.localIndex(q, u));
    if (complex_.label(beyondU) != l && complex_.label(beyondV) != l) return false;
  }
  // Edges: an edge (c, d) between ring vertices lying in both links must be
  // a ring edge.
  thread_local std::vector<char> inLinkU;
  inLinkU.assign(n * n, 0);
  auto visitLinkEdges = [&](const VertexNeighborhood& nb, std::int32_t other, bool mark) {
    for (std::int32_t q : nb.tets) {
      if (complex_.localIndex(q, other) >= 0) continue;
      int idx[3], m = 0;
      for (std::int32_t w : complex_.tet(q))
        if (w != nb.vertex) idx[m++] = ringIndex(nb, w);
      for (int x = 0; x < 3; ++x)
        for (int y = x + 1; y < 3; ++y) {
          if (idx[x] < 0 || idx[y] < 0) continue;
          const std::size_t i = std::size_t(std::min(idx[x], idx[y])), j = std::size_t(std::max(idx[x], idx[y]));
          if (mark) {
            inLinkU[i * n + j] = 1;
          } else if (inLinkU[i * n + j] && j != i + 1 && !(i == 0 && j == n - 1)) {
            return false;
          }
        }
    }
    return true;
  };
  visitLinkEdges(nu_, v, true);
  return visitLinkEdges(nv_, u, false);
}

bool EdgeCollapser::test1PositiveVolumes(const VertexNeighborhood& r, const VertexNeighborhood& k,
                                         const Eigen::Vector3d& p) const {
  const auto& P = complex_.positions();
  const bool keptMoves = p != P[std::size_t(k.vertex)];
  auto check = [&](const VertexNeighborhood& nb, std::int32_t other) {
    for (std::int32_t q : nb.tets) {
      if (complex_.isDummyTet(q) || complex_.localIndex(q, other) >= 0) continue;  // no geometry, or removed
      const Tet& t = complex_.tet(q);
      Eigen::Vector3d x[4];
      for (int i = 0; i < 4; ++i) x[i] = t[std::size_t(i)] == nb.vertex ? p : P[std::size_t(t[std::size_t(i)])];
      const double after = volumeLengthQuality(x[0], x[1], x[2], x[3]);
      if (!(after > 0.0) || signedVolume(x[0], x[1], x[2], x[3]) <= 0.0) return false;
      if (after < kQualityFloor && after < volumeLengthQuality(P[std::size_t(t[0])], P[std::size_t(t[1])],
                                                               P[std::size_t(t[2])], P[std::size_t(t[3])]))
        return false;
      // No new dihedral angle under kCollapseMinDihedral, unless the tets
      // the collapse replaces already had a worse one. Since
      // V = l_e h1 h2 sin(theta_e) / 6 for every edge e, the quality is at
      // most 2 sin(theta_min): above 2 sin(kCollapseMinDihedral) no angle
      // can be too small and the angles need not be computed.
      if (after > kGuardQuality) continue;
      const double worst = minDihedralCosine(x[0], x[1], x[2], x[3]);
      if (worst > kGuardCosine && (worst > worstBefore(r) || (keptMoves && worst > worstBefore(k)))) return false;
    }
    return true;
  };
  return check(r, k.vertex) && (!keptMoves || check(k, r.vertex));
}

double EdgeCollapser::worstBefore(const VertexNeighborhood& nb) const {
  double& w = worstBefore_[&nb == &nu_ ? 0 : 1];
  if (w == kUnknownCosine) w = complex_.worstDihedralCosineOf(nb.tets);
  return w;
}

bool EdgeCollapser::test2NoLongEdges(const VertexNeighborhood& r, const VertexNeighborhood& k,
                                     const Eigen::Vector3d& p) const {
  const std::int32_t dummy = complex_.dummyVertex();
  const bool keptMoves = p != complex_.position(k.vertex);
  for (std::int32_t w : r.neighbors) {
    if (w == dummy || w == k.vertex) continue;
    if (!keptMoves && k.find(w) >= 0) continue;  // an existing, unchanged edge of k
    const Eigen::Vector3d& pw = complex_.position(w);
    if (bounds_.reachesEmax(pw, p, (pw - p).squaredNorm())) return false;
  }
  if (keptMoves)
    for (std::int32_t w : k.neighbors) {
      if (w == dummy || w == r.vertex) continue;
      const Eigen::Vector3d& pw = complex_.position(w);
      if (bounds_.reachesEmax(pw, p, (pw - p).squaredNorm())) return false;
    }
  return true;
}

void EdgeCollapser::starOf(std::int32_t v, std::vector<std::int32_t>& out) {
  ++clock_;
  for (CachedStar& c : stars_)
    if (c.vertex == v && c.collapses == collapses_) {
      c.used = clock_;
      out = c.tets;
      return;
    }
  walker_.incidentTets(complex_, v, out);
  CachedStar& c = stars_[0].used <= stars_[1].used ? stars_[0] : stars_[1];
  c.vertex = v;
  c.collapses = collapses_;
  c.used = clock_;
  c.tets.assign(out.begin(), out.end());
}

std::int32_t EdgeCollapser::applyPlan(std::int32_t u, std::int32_t v, CollapseMove move) {
  // The same ring, in the same order, as tryCollapse(u, v) finds, and the
  // same position (u and v have not moved since).
  complex_.edgeRing(u, v, walker_.findEdgeTet(complex_, u, v), ring_);
  const Eigen::Vector3d pu = complex_.position(u), pv = complex_.position(v);
  const bool removesU = move != CollapseMove::VOntoU;
  const Eigen::Vector3d p = move == CollapseMove::ToMidpoint ? Eigen::Vector3d(0.5 * (pu + pv)) : removesU ? pv : pu;
  classifiedU_ = -1;
  nu_.vertex = removesU ? u : v;
  walker_.incidentTets(complex_, nu_.vertex, nu_.tets);
  nv_.vertex = removesU ? v : u;
  collapse(nu_, nv_, p);
  return nv_.vertex;
}

void EdgeCollapser::collapse(const VertexNeighborhood& r, const VertexNeighborhood& k, const Eigen::Vector3d& p) {
  const std::int32_t rv = r.vertex, kv = k.vertex;
  if (complex_.features().degree(rv) > 0) {
    std::vector<std::int32_t> ring;
    complex_.starVertices(r.tets, rv, ring);
    complex_.features().merge(rv, kv, ring);
  }
  for (std::int32_t q : r.tets)
    if (complex_.localIndex(q, kv) < 0) complex_.setTetVertex(q, complex_.localIndex(q, rv), kv);
  std::int32_t survivor = -1;
  for (std::int32_t q : ring_.tets) {
    const int ir = complex_.localIndex(q, rv), ik = complex_.localIndex(q, kv);
    const std::int32_t beyondR = complex_.encodedNeighbor(q, ik);  // holds r's side facet
    const std::int32_t beyondK = complex_.encodedNeighbor(q, ir);
    complex_.setEncodedNeighbor(beyondR >> 2, beyondR & 3, beyondK);
    complex_.setEncodedNeighbor(beyondK >> 2, beyondK & 3, beyondR);
    for (std::int32_t w : complex_.tet(q))
      if (w != rv && w != kv) complex_.setAnyTet(w, beyondK >> 2);
    survivor = beyondK >> 2;
    complex_.removeTet(q);
  }
  complex_.setPosition(kv, p);
  complex_.setAnyTet(kv, survivor);
  complex_.removeVertex(rv);
  ++collapses_;
}

std::size_t collapseShortEdges(RemeshComplex& complex, const EdgeLengthBounds& bounds, const HullConstraint& hull,
                               int threads, const InterfaceBound* interfaces) {
  auto tooShort = [&](std::int32_t a, std::int32_t b, double l2) {
    return bounds.belowEmin(complex.position(a), complex.position(b), l2);
  };
  auto shorter = [](const WeightedEdge& x, const WeightedEdge& y) {
    return std::tie(x.length2, x.a, x.b) < std::tie(y.length2, y.a, y.b);
  };
  std::vector<WeightedEdge> edges;
  collectEdges(complex, tooShort, edges, threads);

  // Waves, shortest edge first within each. A wave's candidates are screened
  // on all threads (read-only: most cannot be collapsed), then the promising
  // ones are collapsed in order: as screened while no collapse of this wave
  // has touched their stars, checked again otherwise. The short edges a
  // collapse leaves at its surviving vertex make the next wave (most of them
  // cannot be collapsed either, and finding out is again read-only). Every
  // wave but the last collapses at least its first promising edge. What a
  // wave holds does not depend on the thread count, nor does the result.
  EdgeCollapser collapser(complex, bounds, hull, interfaces);
  std::vector<char> touched(std::size_t(complex.vertexSlots()), 0);
  std::vector<std::int32_t> touchedList, star, ring, byVertex;
  std::vector<CollapseMove> plans;
  std::vector<std::pair<std::int32_t, std::int32_t>> next;  // lengths taken again when the wave starts
  std::size_t collapses = 0;
  while (!edges.empty()) {
    sortCancellable(edges.begin(), edges.end(), shorter);
    edges.erase(std::unique(edges.begin(), edges.end(),
                            [](const WeightedEdge& x, const WeightedEdge& y) { return x.a == y.a && x.b == y.b; }),
                edges.end());
    plans.assign(edges.size(), CollapseMove::None);
    // Screened by first end point, so that a screening collapser's star
    // cache holds that point's star across its edges (a plan does not
    // depend on the order in which plans are found).
    byVertex.resize(edges.size());
    for (std::size_t i = 0; i < edges.size(); ++i) byVertex[i] = std::int32_t(i);
    sortCancellable(byVertex.begin(), byVertex.end(), [&](std::int32_t x, std::int32_t y) {
      return std::tie(edges[std::size_t(x)].a, edges[std::size_t(x)].b) < std::tie(edges[std::size_t(y)].a, edges[std::size_t(y)].b);
    });
    parallelRanges(std::int64_t(edges.size()), threads, [&](std::int64_t b, std::int64_t e) {
      EdgeCollapser screen(complex, bounds, hull, interfaces);
      for (std::int64_t x = b; x < e; ++x) {
        throwIfCancelled();
        const std::size_t i = std::size_t(byVertex[std::size_t(x)]);
        screen.tryCollapse(edges[i].a, edges[i].b, false, &plans[i]);
      }
    });
    std::vector<std::int32_t>().swap(byVertex);  // not needed while the collapses are applied
    for (std::int32_t w : touchedList) touched[std::size_t(w)] = 0;
    touchedList.clear();
    next.clear();
    for (std::size_t i = 0; i < edges.size(); ++i) {
      throwIfCancelled();
      if (plans[i] == CollapseMove::None) continue;
      const WeightedEdge& e = edges[i];
      if (!complex.vertexAlive(e.a) || !complex.vertexAlive(e.b)) continue;
      std::int32_t survivor = -1;
      if (touched[std::size_t(e.a)] || touched[std::size_t(e.b)]) {
        if (!tooShort(e.a, e.b, (complex.position(e.a) - complex.position(e.b)).squaredNorm())) continue;
        survivor = collapser.tryCollapse(e.a, e.b);
        if (survivor < 0) continue;
      } else {
        survivor = collapser.applyPlan(e.a, e.b, plans[i]);
      }
      ++collapses;
      complex.incidentTets(survivor, star);
      complex.starVertices(star, survivor, ring);
      for (std::int32_t w : ring)
        if (!touched[std::size_t(w)]) touched[std::size_t(w)] = 1, touchedList.push_back(w);
      if (!touched[std::size_t(survivor)]) touched[std::size_t(survivor)] = 1, touchedList.push_back(survivor);
      const Eigen::Vector3d pk = complex.position(survivor);
      for (std::int32_t w : ring) {
        const double l2 = (complex.position(w) - pk).squaredNorm();
        if (tooShort(survivor, w, l2)) next.push_back({std::min(survivor, w), std::max(survivor, w)});
      }
    }
    // Deferred edges: alive and still short, at their current lengths.
    edges.clear();
    for (const auto& [a, b] : next) {
      if (!complex.vertexAlive(a) || !complex.vertexAlive(b)) continue;
      const double l2 = (complex.position(a) - complex.position(b)).squaredNorm();
      if (tooShort(a, b, l2)) edges.push_back({a, b, l2});
    }
  }
  return collapses;
}

}  // namespace vox::remesh
