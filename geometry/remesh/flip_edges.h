#pragma once
// Flip (edge removal; thesis 2.3.4, Figures 2.19-2.20). The n tets around an
// edge are replaced by a fan towards one link vertex: 3-2 for n = 3, 4-4 for
// n = 4 (two choices), n-m with m = 2n - 4 for n > 4 (n choices). A flip
// never inverts a tet nor creates an edge that already exists.
//  - Inner edges (all tets around them carry one label) take the choice that
//    maximizes the worst dihedral angle, if it beats the current one.
//  - Surface edges (two labels, exactly two boundary facets) are flipped
//    towards one of the two boundary facets' apexes, so the interface stays
//    a surface, when it lowers the deviation of the boundary valences from 6
//    (surface vertices) and 4 (feature vertices), or when it lifts a worst
//    dihedral angle under 30 degrees; no 3-2 boundary flip.
//  - Feature edges are never flipped, nor are tagged edges (feature_edges.h).
// Then the faces of the tets still under `innerFlipAngle` get 2-3 flips
// (the face flip of the thesis' sliver removal, 2.3.6) when that helps.
// Inner and face flips start from domain tets and from the imaginary tets
// that touch the domain: the rest of the imaginary layer is not output and
// only needs to stay valid.

#include "geometry/remesh/interface_bound.h"
#include "geometry/remesh/remesh_complex.h"

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace vox::remesh {

struct FlipOptions {
  // Inner edges of tets whose smallest dihedral angle is under this are
  // candidates (degrees); better tets have nothing to gain.
  double innerFlipAngle = 40.0;
  // Edges tried per such tet, largest dihedral angles first (6: all).
  int edgesPerPoorTet = 3;
  // Largest ring considered for an n-m flip.
  int maxRing = 10;
  // A surface flip may not bend the interface more than this (degrees,
  // angle between the normals of the two facets replaced).
  double surfaceFlipMaxBend = 20.0;
  // The interface bound (interface_bound.h; not owned): a surface flip is
  // made only when its two new facets keep it. Null: no bound.
  const InterfaceBound* interfaces = nullptr;
  int threads = 2;  // for the quality scans
};

struct FlipCounts {
  std::size_t surface = 0;
  std::size_t inner = 0;
  std::size_t face = 0;
};

class EdgeFlipper {
public:
  EdgeFlipper(RemeshComplex& complex, const FlipOptions& options);
  // Each returns whether it flipped; with apply = false only whether it
  // would (read-only: flippers of other threads may read the complex too).
  // `apex` receives the ring position of the fan's apex when it would flip.
  bool tryFlipInnerEdge(std::int32_t a, std::int32_t b, bool apply = true, std::uint8_t* apex = nullptr);
  bool tryFlipSurfaceEdge(std::int32_t a, std::int32_t b, bool apply = true, std::uint8_t* apex = nullptr);
  // Performs the flip of edge (a, b) towards `apex` that one of the above
  // found (apply = false) on the complex as it was then, if neither a, b nor
  // any vertex of the edge's ring is `touched` (no flip since has changed a
  // tet around them: what the rules look at is all in their stars), and
  // returns true; returns false, changing nothing, otherwise.
  bool applyEdgePlan(std::int32_t a, std::int32_t b, std::uint8_t apex, const std::vector<char>& touched);
  // The edge ring of the last edge tried (after a flip: the ring it removed).
  const EdgeRing& lastRing() const { return ring_; }
  // 2-3 flip of face k of tet t (sliver removal, thesis 2.3.6).
  bool tryFlipFace(std::int32_t t, int k, bool apply = true);
  // The worst dihedral cosine of every tet slot of the complex as it is
  // (minDihedralCosine, 2 for dummy tets), for a flipper that only screens:
  // the tets' current worst angles are read from it instead of computed.
  void useWorstCosines(const std::vector<double>* worst) { worst_ = worst; }

private:
  // Tets of the fan towards ring[apex], with their labels.
  void fanTowards(std::size_t apex);
  // Worst dihedral cosine of the fan, or +inf when a tet is invalid; stops
  // early once it reaches `bound`.
  double fanWorstCosine(double bound) const;
  bool fanCreatesExistingEdge(std::size_t apex);
  bool ringNearPinch() const;
  // Worst dihedral cosine of tet q as it is now.
  double tetWorstCosine(std::int32_t q) const;
  // Edges of v on the x|y interface, and |S(v)|.
  std::pair<int, int> boundaryValence(std::int32_t v, std::int32_t x, std::int32_t y);

  RemeshComplex& complex_;
  FlipOptions options_;
  StarWalker walker_;
  EdgeRing ring_;
  std::vector<Tet> fan_;
  std::vector<std::int32_t> fanLabels_;
  std::vector<std::int32_t> star_, scratch_;
  const std::vector<double>* worst_ = nullptr;
};

// Surface flips first (valence), then inner flips (dihedral angle), then
// face flips. The candidates of each kind are screened on all threads first.
FlipCounts flipEdges(RemeshComplex& complex, const FlipOptions& options = {});

}  // namespace vox::remesh
