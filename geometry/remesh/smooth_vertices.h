#pragma once
// Filtering (thesis 2.3.5, Figure 2.21): hierarchical smoothing of the
// vertex positions. Feature vertices first (the mean of their two neighbours
// along the 1-junction, projected onto its MLS line), then surface vertices
// (tangential Laplacian over the neighbours of their 2-junction, projected
// onto its PSS), then inside vertices (Laplacian over the whole one-ring),
// each level using the already smoothed positions of the level before.
// A vertex of a tagged line (feature_edges.h) goes to the mean of its two
// neighbours on the line, projected onto the line's input geometry.
// Corners never move, nor do vertices without a domain tet (the imaginary
// layer is not output); hull vertices slide within the planes of their hull facets. A move is
// shortened until no incident tet inverts (nor drops under the quality
// floor) and the worst dihedral angle around the vertex does not get worse
// unless it stays above 30 degrees; it is dropped when even a small step
// fails. (The thesis only forbids inversions; on voxel input with many
// fixed junction points, plain Laplacian moves create most slivers.)
//
// Targets are computed in parallel from the positions of the previous level;
// moves then give the result of applying them one vertex at a time in index
// order (on all threads: a vertex waits only for its moving neighbours of
// lower index), so it does not depend on the thread count.

#include "geometry/remesh/hull_constraint.h"
#include "geometry/remesh/interface_bound.h"
#include "geometry/remesh/interface_surfaces.h"
#include "geometry/remesh/remesh_complex.h"

#include <cstddef>

namespace vox::remesh {

struct SmoothCounts {
  std::size_t feature = 0, surface = 0, inside = 0;  // vertices moved
};

// `surfaces` may be null: boundary vertices then move tangentially only.
// With `interfaces` (the interface bound, may be null) a move of an
// interface vertex is shortened like an inverting one until its interface
// facets keep the bound (InterfaceBound::keepsMove).
SmoothCounts smoothVertices(RemeshComplex& complex, const InterfaceSurfaces* surfaces, const HullConstraint& hull,
                            int threads, const InterfaceBound* interfaces = nullptr);

// Polish: the vertices of the domain tets whose smallest dihedral angle is
// under `angleDeg` move, one at a time in index order, to where the smallest
// dihedral angle of the domain tets around them is largest, by a compass
// search within their freedom: inside vertices in space, surface vertices in
// the interface's tangent plane and back onto its PSS, feature vertices along
// their 1-junction and back onto its MLS line; corners and hull vertices
// stay. A move is kept only when that angle grows and no tet around the
// vertex inverts or falls under the quality floor, so the smallest angle of
// the mesh never drops. Returns the vertices moved. Sequential: the result
// does not depend on `threads` (used for the scan). With `interfaces`, no
// place that breaks the interface bound is taken.
std::size_t polishWorstTets(RemeshComplex& complex, const InterfaceSurfaces* surfaces, const HullConstraint& hull,
                            double angleDeg, int threads, const InterfaceBound* interfaces = nullptr);

}  // namespace vox::remesh
