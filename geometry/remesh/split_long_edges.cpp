#include "geometry/remesh/split_long_edges.h"

#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/remesh/mesh_edges.h"

#include <algorithm>
#include <queue>
#include <tuple>

namespace vox::remesh {

std::int32_t splitEdge(RemeshComplex& complex, std::int32_t a, std::int32_t b, std::int32_t t) {
  thread_local EdgeRing ring;
  thread_local std::vector<std::int32_t> halves;
  complex.edgeRing(a, b, t, ring);
  const std::int32_t m = complex.addVertex(0.5 * (complex.position(a) + complex.position(b)));
  const std::size_t n = ring.size();
  halves.resize(n);
  // Each ring tet keeps its slot with a replaced by m; its twin is the tet
  // with b replaced by m. The twin takes over the face opposite b.
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t q = ring.tets[i];
    const int ia = complex.localIndex(q, a), ib = complex.localIndex(q, b);
    Tet twin = complex.tet(q);
    twin[std::size_t(ib)] = m;
    const std::int32_t h = complex.addTet(twin, complex.label(q));
    halves[i] = h;
    const std::int32_t outer = complex.encodedNeighbor(q, ib);
    complex.setEncodedNeighbor(h, ib, outer);
    complex.setEncodedNeighbor(outer >> 2, outer & 3, 4 * h + ib);
    complex.setTetVertex(q, ia, m);
    complex.glue(q, ib, h, ia);
  }
  // Twins of consecutive ring tets meet across the faces holding the edge,
  // with the same local face indices as the tets they came from.
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t q = ring.tets[i];
    const int k = complex.localIndex(q, ring.ring[i]);
    const std::int32_t across = complex.encodedNeighbor(q, k);  // the next ring tet, unchanged slot
    complex.glue(halves[i], k, halves[(i + 1) % n], across & 3);
  }
  complex.setAnyTet(m, ring.tets[0]);
  complex.setAnyTet(b, ring.tets[0]);
  complex.setAnyTet(a, halves[0]);
  complex.features().split(a, b, m);
  return m;
}

bool splitChangesAContact(const RemeshComplex& complex, const EdgeRing& ring) {
  if (complex.isPinned(ring.a) && complex.isPinned(ring.b) &&
      std::any_of(ring.tets.begin(), ring.tets.end(), [&](std::int32_t q) { return complex.isDummyTet(q); }))
    return true;
  std::vector<std::int32_t> pinches;
  for (std::int32_t w : ring.ring)
    if (complex.pinchOf(w) >= 0) pinches.push_back(complex.pinchOf(w));
  for (std::int32_t w : {ring.a, ring.b})
    if (complex.pinchOf(w) >= 0) pinches.push_back(complex.pinchOf(w));
  std::sort(pinches.begin(), pinches.end());
  return std::adjacent_find(pinches.begin(), pinches.end()) != pinches.end();
}

namespace {

// 3/4, and a margin for the rounding of a mid-point.
constexpr double kNewEdgeBound = 0.75 * (1.0 + 1e-9);

bool aboveEmax(const RemeshComplex& complex, const EdgeLengthBounds& bounds, std::int32_t x, std::int32_t y) {
  const Eigen::Vector3d& px = complex.position(x);
  const Eigen::Vector3d& py = complex.position(y);
  return bounds.aboveEmax(px, py, (px - py).squaredNorm());
}

}  // namespace

std::size_t splitLongEdges(RemeshComplex& complex, const EdgeLengthBounds& bounds, int threads) {
  // Longest first: the initial candidates sorted once (ties by vertex ids),
  // the edges of new vertices that are still too long in a heap.
  std::vector<WeightedEdge> edges;
  collectEdges(
      complex,
      [&](std::int32_t a, std::int32_t b, double length2) {
        return bounds.aboveEmax(complex.position(a), complex.position(b), length2);
      },
      edges, threads);
  auto longer = [](const WeightedEdge& x, const WeightedEdge& y) {
    return x.length2 > y.length2 || (x.length2 == y.length2 && std::tie(x.a, x.b) < std::tie(y.a, y.b));
  };
  sortCancellable(edges.begin(), edges.end(), longer);
  auto later = [&](const WeightedEdge& x, const WeightedEdge& y) { return longer(y, x); };
  std::priority_queue<WeightedEdge, std::vector<WeightedEdge>, decltype(later)> queue(later);
  std::size_t next = 0, splits = 0;
  std::vector<std::int32_t> star, around;
  EdgeRing contactRing;
  while (next < edges.size() || !queue.empty()) {
    throwIfCancelled();  // a split of the whole complex runs for seconds
    WeightedEdge e;
    if (queue.empty() || (next < edges.size() && longer(edges[next], queue.top()))) {
      e = edges[next++];
    } else {
      e = queue.top();
      queue.pop();
    }
    const std::int32_t t = complex.findEdgeTet(e.a, e.b);
    if (t < 0) continue;
    if (complex.hasPinches() || (complex.isPinned(e.a) && complex.isPinned(e.b))) {
      complex.edgeRing(e.a, e.b, t, contactRing);
      if (splitChangesAContact(complex, contactRing)) continue;
    }
    const std::int32_t m = splitEdge(complex, e.a, e.b, t);
    ++splits;
    // The split replaced every tet of the ring; a tet still holding both end
    // points was off the ring (its tets formed more than one cycle, which the
    // complex's checks refuse): the edge would be split again and again.
    if (complex.findEdgeTet(e.a, e.b) >= 0)
      throw RuntimeFailure("remesh: edge (" + std::to_string(e.a) + ", " + std::to_string(e.b) +
                           ") is still there after its split: its tets form more than one cycle (corrupt complex)");
    // The halves and the new edges at m may still be too long. A new edge
    // (m, w) is at most sqrt(3/4) |ab| long when (a, w) and (b, w) are at
    // most |ab|; an edge above e_max longer than (a, b) has been split
    // before it, unless it could not be split (a contact, see
    // splitChangesAContact). Splitting the triangles at such an edge would
    // never end when it is near 2 e_max long or longer (each split adds a
    // vertex nearer a fixed point, and the contact's end points gain tets
    // without bound), so a new edge longer than that beside an edge above
    // e_max is left to the next round. Elsewhere nothing changes.
    complex.incidentTets(m, star);
    complex.starVertices(star, m, around);
    const Eigen::Vector3d pm = complex.position(m);
    for (std::int32_t w : around) {
      const Eigen::Vector3d& pw = complex.position(w);
      const double l2 = (pw - pm).squaredNorm();
      if (!bounds.aboveEmax(pw, pm, l2)) continue;
      if (l2 > kNewEdgeBound * e.length2 &&
          (aboveEmax(complex, bounds, e.a, w) || aboveEmax(complex, bounds, e.b, w)))
        continue;
      queue.push({std::min(m, w), std::max(m, w), l2});
    }
  }
  return splits;
}

}  // namespace vox::remesh
