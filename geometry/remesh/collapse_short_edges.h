#pragma once
// Collapse (thesis 2.3.3, Figure 2.18). An edge shorter than e_min is
// contracted according to the condition it meets (Table 2.3): similarity
// gives a mid-point collapse (then, as in CGAL, towards either end point),
// inclusion moves the vertex of higher dimension onto the other one,
// exclusion forbids the collapse. It is performed only if
//   1. every updated tet keeps a positive volume,
//   2. every new edge is shorter than e_max,
//   3. no non-boundary facet around a boundary edge has three boundary edges,
//   4. no boundary facet around a feature edge has three feature edges
//      (the topology exceptions of Figure 2.16),
// and if the label-aware link condition holds: tests 3 and 4 are special
// cases of it, and it also rejects the contractions that would merge two
// simplices of different label sets or empty a label from a simplex, which
// is what keeps every label region, 1-junction and 0-junction intact.
// Tagged features (feature_edges.h) follow Table 2.4 (edgeRule), no
// collapse merges the two tagged edges of a triangle, and a collapse along a
// tagged line keeps its new edges within l / 20 of the vertices it removes.
// With an interface bound (interface_bound.h), a collapse that moves an
// interface is made only when the interface facets around the surviving
// vertex stay within the bound of the input's interfaces, and the input's
// within the bound of them.

#include "geometry/remesh/edge_length_bounds.h"
#include "geometry/remesh/element_classification.h"
#include "geometry/remesh/hull_constraint.h"
#include "geometry/remesh/interface_bound.h"
#include "geometry/remesh/remesh_complex.h"

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vox::remesh {

inline constexpr double kCollapseMinDihedral = 10.0;  // degrees

// A collapse found possible for edge (u, v) as asked: which end point goes
// and where the other one ends up. With the positions of u and v this is
// the whole plan (one byte per candidate edge of a wave).
enum class CollapseMove : std::uint8_t {
  None,        // no collapse possible
  ToMidpoint,  // u removed, v moved to the mid-point of (u, v)
  UOntoV,      // u removed, v stays
  VOntoU,      // v removed, u stays
};

class EdgeCollapser {
public:
  // `interfaces` (may be null: no bound) is not owned.
  EdgeCollapser(RemeshComplex& complex, const EdgeLengthBounds& bounds, const HullConstraint& hull,
                const InterfaceBound* interfaces = nullptr);

  // Collapses edge (u, v) when the rules above allow it. Returns the vertex
  // that remains, or -1 (nothing changed). With apply = false only says
  // which vertex would remain (read-only: collapsers of other threads may
  // evaluate the same complex meanwhile). `move` receives what it did or
  // would do (None when nothing).
  std::int32_t tryCollapse(std::int32_t u, std::int32_t v, bool apply = true, CollapseMove* move = nullptr);
  // Performs the collapse of (u, v) that tryCollapse(u, v, false, &move)
  // found on the complex as it was then, and returns the vertex that
  // remains. The result is the same as tryCollapse(u, v) now, provided that
  // no collapse since has touched u or v (changed a tet around u or v, or
  // moved one of their neighbours): what the rules look at is all in the
  // stars of u and v.
  std::int32_t applyPlan(std::int32_t u, std::int32_t v, CollapseMove move);

private:
  bool anyPositionKeepsEdgesShort() const;
  bool nearPinch() const;
  bool mergesTaggedEdges(std::int32_t u, std::int32_t v) const;
  bool keepsTaggedLine(const VertexNeighborhood& removed, const VertexNeighborhood& kept, const Eigen::Vector3d& p) const;
  bool keepsInterfaces(const VertexNeighborhood& removed, const VertexNeighborhood& kept, const Eigen::Vector3d& p) const;
  bool topologyTests(const LabelSet& edgeLabels) const;
  bool linkCondition() const;
  bool test1PositiveVolumes(const VertexNeighborhood& removed, const VertexNeighborhood& kept,
                            const Eigen::Vector3d& p) const;
  bool test2NoLongEdges(const VertexNeighborhood& removed, const VertexNeighborhood& kept,
                        const Eigen::Vector3d& p) const;
  void collapse(const VertexNeighborhood& removed, const VertexNeighborhood& kept, const Eigen::Vector3d& p);
  const LabelSet& edgeLabels(const VertexNeighborhood& n, std::int32_t w) const;

  RemeshComplex& complex_;
  EdgeLengthBounds bounds_;
  const HullConstraint& hull_;
  const InterfaceBound* interfaces_;
  StarWalker walker_;
  VertexNeighborhood nu_, nv_;
  EdgeRing ring_;
  // The stars of the last two vertices asked for, valid until this
  // collapser collapses an edge: the short edges queued after a collapse
  // all share the surviving vertex.
  struct CachedStar {
    std::int32_t vertex = -1;
    std::uint64_t collapses = 0, used = 0;
    std::vector<std::int32_t> tets;
  };
  void starOf(std::int32_t v, std::vector<std::int32_t>& out);
  CachedStar stars_[2];
  std::uint64_t collapses_ = 0, clock_ = 0;
  // nu_ holds the classified neighbourhood of this vertex as it was after
  // that many collapses (the edges of a wave come by first end point).
  std::int32_t classifiedU_ = -1;
  std::uint64_t classifiedAfter_ = 0;
  // Worst dihedral cosine around u and v, computed when first needed.
  double worstBefore(const VertexNeighborhood& nb) const;
  mutable double worstBefore_[2] = {3.0, 3.0};
};

// Collapses edges shorter than e_min in waves, shortest first within each:
// the edges of a remaining vertex that a collapse made too short form the
// next wave (cascading), until every edge is long enough or cannot be
// collapsed. Returns the number of collapses.
// Each wave's candidates are first screened in parallel (read-only); the
// collapses are then applied one at a time in order: as screened while no
// collapse has touched the edge's end points since, re-checked otherwise.
// The result does not depend on the thread count.
// `interfaces`: the interface bound, or null.
std::size_t collapseShortEdges(RemeshComplex& complex, const EdgeLengthBounds& bounds, const HullConstraint& hull,
                               int threads = 2, const InterfaceBound* interfaces = nullptr);

}  // namespace vox::remesh
