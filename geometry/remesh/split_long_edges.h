#pragma once
// Split (thesis 2.3.2, Figure 2.17): a vertex is added at the mid-point of
// every edge longer than e_max and each tet around the edge is cut in two,
// both halves keeping its label, so S(new vertex) = S(edge). Insertions
// cannot change any junction, so no feature rule applies.

#include "geometry/remesh/edge_length_bounds.h"
#include "geometry/remesh/remesh_complex.h"

#include <cstddef>
#include <cstdint>

namespace vox::remesh {

// Splits edge (a, b) at its mid-point; t is a tet holding both. Works on
// dummy tets too (an outer edge). Returns the new vertex.
std::int32_t splitEdge(RemeshComplex& complex, std::int32_t a, std::int32_t b, std::int32_t t);

// Whether splitting the edge of `ring` would change where parts of the input
// touch: a contact edge (both ends pinned, on the outer boundary) is kept by
// both sides, and the new vertex may not be adjacent to two copies of one
// pinched vertex (see RemeshComplex::pinchOf).
bool splitChangesAContact(const RemeshComplex& complex, const EdgeRing& ring);

// Splits, longest first, every edge longer than e_max, and again the halves
// that are still too long. Returns the number of splits.
std::size_t splitLongEdges(RemeshComplex& complex, const EdgeLengthBounds& bounds, int threads = 2);

}  // namespace vox::remesh
