#pragma once
// Vertex insertion, the last step of sliver removal (after the flips of
// thesis 2.3.6 and the polish). Where the four vertices of a sliver are
// junction corners that no operation may move or remove, neither flips nor
// vertex moves can lift it; a Steiner point can. An edge of a poor domain tet
// (the edges with the largest dihedral angles first: a sliver's two, a cap's
// three) is split by a new vertex p, and each tet around the edge is cut in
// two, both halves keeping its label, so S(p) = S(edge) and the topology of
// every label and junction is that of the complex before (a subdivision).
// p is then placed where the smallest dihedral angle of the new domain tets
// is largest, within the freedom its kind allows:
//  - inner edge (one label around it): anywhere in space;
//  - surface edge (two labels, two boundary facets): in the plane of one of
//    the two boundary facets next to the edge, so that the interface stays on
//    that facet and bends at most by p's offset from the other one;
//  - feature edge (1-junction) or anything else: along the edge;
//  - where none of these lifts the tets past the angle (the interface's own
//    facets fold at a sharp angle between pinned corners, and the tets
//    inside the fold cannot be better than the fold), off the interface or
//    the 1-junction by at most `interfaceOffset` times the edge's length;
//  - edges on the hull of the complex, tagged edges (feature_edges.h), and
//    splits that would make a vertex adjacent to two copies of a pinched
//    vertex, are left alone.
// The split is made only when the smallest dihedral angle of the domain tets
// around the edge grows (so the mesh's smallest angle never drops), no tet
// inverts, and no new tet falls under the quality floor (tet_shape.h).

#include "geometry/remesh/remesh_complex.h"

#include <cstddef>

namespace vox::remesh {

struct SteinerOptions {
  // Domain tets whose smallest dihedral angle is under this (degrees) are
  // treated, worst first; 0 turns the step off.
  double angle = 15.0;
  // Edges tried per tet, largest dihedral angles first (6: all).
  int edgesPerTet = 6;
  // Passes over the tets still under the angle (a new vertex opens room for
  // its neighbours' tets); they stop early when one inserts nothing.
  int passes = 4;
  // Where no place on the interface (or the 1-junction) lifts the tets past
  // `angle`, the new vertex may leave it by up to this share of the split
  // edge's length: the interface then moves by that much, its topology not
  // at all. 0 keeps new vertices on their interfaces and 1-junctions.
  double interfaceOffset = 0.2;
};

// Returns the number of vertices inserted. Sequential and deterministic:
// tets in order of their smallest angle, ties by vertex ids.
std::size_t insertSteinerPoints(RemeshComplex& complex, const SteinerOptions& options = {});

}  // namespace vox::remesh
