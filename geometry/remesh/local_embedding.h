#pragma once
// The checks that make a tet soup safe to remesh: the walks of the remesher
// (around an edge through the faces that hold it, through a vertex's star)
// assume that the tets embed locally, i.e. that around every edge and every
// vertex they cover each direction at most once. A mesh that passes the face
// and conformity checks but has one tet overlapping its neighbours is not
// such a complex: a walk around an edge may not close where it should, and
// the splits then never end.

#include "geometry/tet_mesh.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vox::remesh {

// For positions P (#V), positively oriented tets T (#T by 4 indices into P)
// and their face adjacency N (#T by 4, tetFaceAdjacency's encoding), throws
// InputError(source, "tet N (vertices a, b, c, d) ...") naming the first tet
// where the tets do not embed locally:
//   1. two tets sharing a face lie on the same side of it (the face has the
//      same orientation in both: a duplicated or folded tet);
//   2. the dihedral angles of the tets around an edge add up to more than
//      one turn (2 pi);
//   3. the solid angles of the tets around a vertex add up to more than the
//      whole sphere (4 pi);
//   4. around a vertex on open facets (faces of one tet), two of those facets
//      cross as seen from the vertex, or another tet covers the direction
//      just beyond one of them (the middle of its edge opposite the vertex).
// Parts touching along an edge or at a point, cavities and open boundaries
// pass: their tets cover less than a turn (a sphere) and never overlap.
// Linear in the size of the mesh (each vertex's tets sorted locally).
void checkLocalEmbedding(const std::vector<Eigen::Vector3d>& positions, const std::vector<Tet>& tets,
                         const std::vector<std::array<std::int32_t, 4>>& neighbors, const std::string& source);

}  // namespace vox::remesh
