#include "geometry/remesh/insert_steiner_points.h"

#include "geometry/cancellation.h"
#include "geometry/mesh_quality.h"
#include "geometry/remesh/split_long_edges.h"
#include "geometry/remesh/tet_shape.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>
#include <vector>

namespace vox::remesh {

namespace {

// Where the new vertex of a split may go (see the header).
enum class Freedom { Space, Facets, Edge };

// The tets of a split edge's ring, with what a split at p makes of them.
struct RingTet {
  std::array<Eigen::Vector3d, 4> corners;
  int ia = 0, ib = 0;  // local indices of the edge's end points
  bool domain = false;
};

constexpr double kInvalid = 2.0;  // worst cosine of a split that inverts or flattens a tet

class SteinerInserter {
public:
  SteinerInserter(RemeshComplex& complex, double goodCosine, double offsetShare)
      : complex_(complex), goodCosine_(goodCosine), offsetShare_(offsetShare) {}

  // Splits the edge of tet t, among its `edges` edges of largest dihedral
  // angle, that lifts the worst angle around it most; returns whether it did.
  bool treat(std::int32_t t, int edges) {
    const Tet q = complex_.tet(t);
    const auto& P = complex_.positions();
    const auto angles = dihedralAngles(P[std::size_t(q[0])], P[std::size_t(q[1])], P[std::size_t(q[2])], P[std::size_t(q[3])]);
    static constexpr std::array<std::array<int, 2>, 6> kEdges{{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};
    std::array<int, 6> order{0, 1, 2, 3, 4, 5};
    std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return angles[std::size_t(x)] > angles[std::size_t(y)]; });
    // Splits that keep the interfaces and 1-junctions where they are come
    // first, as long as one lifts the tets past the angle.
    double bestCosine = kInvalid, bestKeeping = kInvalid;
    std::int32_t bestA = -1, bestB = -1, keepingA = -1, keepingB = -1;
    Eigen::Vector3d bestP = Eigen::Vector3d::Zero(), keepingP = Eigen::Vector3d::Zero();
    for (int i = 0; i < std::min(edges, 6); ++i) {
      const auto& e = kEdges[std::size_t(order[std::size_t(i)])];
      const std::int32_t a = q[std::size_t(e[0])], b = q[std::size_t(e[1])];
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      double before = 0.0;
      bool leaves = false;
      const double after = bestSplit(a, b, t, p, before, leaves);
      if (!(after < before - 1e-9)) continue;
      if (after < bestCosine) bestCosine = after, bestA = a, bestB = b, bestP = p;
      if (!leaves && after < bestKeeping) bestKeeping = after, keepingA = a, keepingB = b, keepingP = p;
    }
    if (keepingA >= 0 && bestKeeping < goodCosine_) bestA = keepingA, bestB = keepingB, bestP = keepingP;
    if (bestA < 0) return false;
    const std::int32_t m = splitEdge(complex_, bestA, bestB, complex_.findEdgeTet(bestA, bestB));
    complex_.setPosition(m, bestP);
    return true;
  }

private:
  // The best place for a vertex splitting edge (a, b) of tet t, and the
  // worst dihedral cosine of the domain tets there (kInvalid when no split
  // is allowed or valid); `before` gets that of the ring as it is, `leaves`
  // whether p is off the interface or 1-junction the edge lies on.
  double bestSplit(std::int32_t a, std::int32_t b, std::int32_t t, Eigen::Vector3d& p, double& before, bool& leaves) {
    // A tagged edge stays: its new vertex would leave the line.
    if (complex_.features().lineOf(a, b) >= 0) return kInvalid;
    complex_.edgeRing(a, b, t, ring_);
    const std::size_t n = ring_.size();
    for (std::int32_t r : ring_.tets)
      if (complex_.isDummyTet(r)) return kInvalid;  // the hull of the complex stays as it is
    if (splitChangesAContact(complex_, ring_)) return kInvalid;
    tets_.resize(n);
    before = -1.0;
    std::vector<std::int32_t> labels;
    bool anyDomain = false;
    for (std::size_t i = 0; i < n; ++i) {
      const std::int32_t r = ring_.tets[i];
      const Tet& v = complex_.tet(r);
      RingTet& rt = tets_[i];
      for (int k = 0; k < 4; ++k) rt.corners[std::size_t(k)] = complex_.position(v[std::size_t(k)]);
      rt.ia = complex_.localIndex(r, a);
      rt.ib = complex_.localIndex(r, b);
      rt.domain = complex_.label(r) > 0;
      anyDomain = anyDomain || rt.domain;
      if (rt.domain) before = std::max(before, complex_.minDihedralCosineOf(r));
      labels.push_back(complex_.label(r));
    }
    if (!anyDomain) return kInvalid;
    // Boundary facets around the edge: (a, b, ring[i]) between tets i - 1 and i.
    std::vector<std::int32_t> apexes;
    for (std::size_t i = 0; i < n; ++i)
      if (complex_.label(ring_.tets[(i + n - 1) % n]) != complex_.label(ring_.tets[i])) apexes.push_back(ring_.ring[i]);
    std::sort(labels.begin(), labels.end());
    labels.erase(std::unique(labels.begin(), labels.end()), labels.end());
    const Freedom freedom = apexes.empty()                               ? Freedom::Space
                            : apexes.size() == 2 && labels.size() == 2 ? Freedom::Facets
                                                                       : Freedom::Edge;
    const Eigen::Vector3d pa = complex_.position(a), pb = complex_.position(b);
    if (freedom == Freedom::Space) return searchSpace(pa, pb, p, [](const Eigen::Vector3d&) { return true; });
    Eigen::Vector3d side[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    if (freedom == Freedom::Facets) {
      // Offsets of the two facets' apexes from the edge's line, in their planes.
      const Eigen::Vector3d e = (pb - pa).normalized();
      for (int k = 0; k < 2; ++k) {
        const Eigen::Vector3d c = complex_.position(apexes[std::size_t(k)]) - pa;
        side[k] = c - c.dot(e) * e;
      }
    }
    const bool facets = freedom == Freedom::Facets;
    const double onInterface = searchFacets(pa, pb, side, facets, p);
    if (onInterface < goodCosine_ || !(offsetShare_ > 0.0)) return onInterface;
    // Still poor on the interface (or the 1-junction): where its own facets
    // fold at a sharp angle between pinned corners, no vertex on them lifts
    // the tets inside the fold. Let the vertex leave them by a bounded offset.
    const Eigen::Vector3d e = (pb - pa).normalized();
    const Eigen::Vector3d normal[2] = {facets ? e.cross(side[0]).normalized() : Eigen::Vector3d::Zero(),
                                       facets ? e.cross(side[1]).normalized() : Eigen::Vector3d::Zero()};
    const double limit = offsetShare_ * (pb - pa).norm();
    auto offset = [&](const Eigen::Vector3d& x) {
      const Eigen::Vector3d r = x - pa;
      if (!facets) return (r - r.dot(e) * e).norm();
      return std::min(std::abs(normal[0].dot(r)), std::abs(normal[1].dot(r)));
    };
    Eigen::Vector3d q;
    const double off = searchSpace(pa, pb, q, [&](const Eigen::Vector3d& x) { return offset(x) <= limit; });
    if (off < onInterface) {
      p = q;
      leaves = true;
      return off;
    }
    return onInterface;
  }

  // Worst dihedral cosine of the domain tets of the split at p; kInvalid
  // when a tet inverts or falls under the quality floor, or once the worst
  // reaches `bound` (no better than what is already found).
  double splitCosine(const Eigen::Vector3d& p, double bound) const {
    double worst = -1.0;
    for (const RingTet& rt : tets_)
      for (int end : {rt.ia, rt.ib}) {
        std::array<Eigen::Vector3d, 4> c = rt.corners;
        c[std::size_t(end)] = p;
        if (!(signedVolume(c[0], c[1], c[2], c[3]) > 0.0) || volumeLengthQuality(c[0], c[1], c[2], c[3]) < kQualityFloor)
          return kInvalid;
        if (!rt.domain) continue;
        worst = std::max(worst, minDihedralCosine(c[0], c[1], c[2], c[3]));
        if (worst >= bound) return kInvalid;
      }
    return worst;
  }

  // Compass search in space from the edge's mid-point: the 26 directions of
  // a cube's neighbours, steps from a quarter of the edge's length halved
  // down to a 64th, among the places `allowed` accepts.
  template <class Allowed>
  double searchSpace(const Eigen::Vector3d& pa, const Eigen::Vector3d& pb, Eigen::Vector3d& p, const Allowed& allowed) const {
    static const std::vector<Eigen::Vector3d> kDirections = [] {
      std::vector<Eigen::Vector3d> d;
      for (int x = -1; x <= 1; ++x)
        for (int y = -1; y <= 1; ++y)
          for (int z = -1; z <= 1; ++z)
            if (x || y || z) d.push_back(Eigen::Vector3d(x, y, z).normalized());
      return d;
    }();
    p = 0.5 * (pa + pb);
    double best = splitCosine(p, kInvalid);
    const double length = (pb - pa).norm();
    for (double step = 0.25 * length; step > length / 64.0; step *= 0.5) {
      for (bool moved = true; moved;) {
        moved = false;
        Eigen::Vector3d next = p;
        for (const Eigen::Vector3d& d : kDirections) {
          const Eigen::Vector3d x = p + step * d;
          if (!allowed(x)) continue;
          const double c = splitCosine(x, best);
          if (c < best) best = c, next = x, moved = true;
        }
        p = next;
      }
    }
    return best;
  }

  // Compass search over p = a + s (b - a) + |u| side[u < 0]: along the edge
  // (s in [0.05, 0.95]) and, with `facets`, into either boundary facet's
  // plane (|u| up to 0.6 of its apex's offset).
  double searchFacets(const Eigen::Vector3d& pa, const Eigen::Vector3d& pb, const Eigen::Vector3d side[2], bool facets,
                      Eigen::Vector3d& p) const {
    auto at = [&](double s, double u) -> Eigen::Vector3d { return pa + s * (pb - pa) + std::abs(u) * side[u < 0.0 ? 1 : 0]; };
    double s = 0.5, u = 0.0;
    double best = splitCosine(at(s, u), kInvalid);
    static constexpr std::array<std::array<int, 2>, 8> kSteps{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {1, -1}, {-1, 1}, {-1, -1}}};
    for (double step = 0.2; step > 1.0 / 128.0; step *= 0.5) {
      for (bool moved = true; moved;) {
        moved = false;
        double ns = s, nu = u;
        for (const auto& d : kSteps) {
          if (!facets && d[1] != 0) continue;
          const double xs = s + step * d[0], xu = u + step * d[1];
          if (xs < 0.05 || xs > 0.95 || std::abs(xu) > 0.6) continue;
          const double c = splitCosine(at(xs, xu), best);
          if (c < best) best = c, ns = xs, nu = xu, moved = true;
        }
        s = ns, u = nu;
      }
    }
    p = at(s, u);
    return best;
  }

  RemeshComplex& complex_;
  double goodCosine_;   // a split on the interface lifting the worst angle past this is taken as it is
  double offsetShare_;  // largest offset from the interface, per unit of the split edge's length
  EdgeRing ring_;
  std::vector<RingTet> tets_;
};

struct PoorTet {
  double cosine;  // of its smallest dihedral angle
  Tet sorted;     // its vertices, sorted
  std::int32_t slot;
};

}  // namespace

std::size_t insertSteinerPoints(RemeshComplex& complex, const SteinerOptions& options) {
  if (!(options.angle > 0.0)) return 0;
  const double cosine = std::cos(options.angle * M_PI / 180.0);
  SteinerInserter inserter(complex, cosine, options.interfaceOffset);
  std::size_t inserted = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    std::vector<PoorTet> poor;
    for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
      if (t % 65536 == 0) throwIfCancelled();
      if (!complex.tetAlive(t) || complex.isDummyTet(t) || complex.label(t) <= 0) continue;
      const double c = complex.minDihedralCosineOf(t);
      if (c <= cosine) continue;
      Tet s = complex.tet(t);
      std::sort(s.begin(), s.end());
      poor.push_back({c, s, t});
    }
    sortCancellable(poor.begin(), poor.end(), [](const PoorTet& x, const PoorTet& y) {
      return std::tie(y.cosine, x.sorted) < std::tie(x.cosine, y.sorted);  // worst first
    });
    std::size_t now = 0;
    for (const PoorTet& pt : poor) {
      throwIfCancelled();
      // An earlier split may have replaced the tet (its slot then holds one of the halves).
      if (!complex.tetAlive(pt.slot)) continue;
      Tet s = complex.tet(pt.slot);
      std::sort(s.begin(), s.end());
      if (s != pt.sorted) continue;
      now += inserter.treat(pt.slot, options.edgesPerTet) ? 1 : 0;
    }
    inserted += now;
    if (now == 0) break;
  }
  return inserted;
}

}  // namespace vox::remesh
