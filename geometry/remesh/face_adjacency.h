#pragma once
// Face adjacency of a tet soup, built by bucketing faces on their smallest
// vertex (linear time, no hash table): fast enough for tens of millions of tets.

#include "geometry/tet_mesh.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vox::remesh {

// Encoded face reference: 4 * tet + k for the face of `tet` opposite its local
// vertex k; kNoFace for a face on the boundary of the soup.
inline constexpr std::int32_t kNoFace = -1;

// For tets T (#T by 4 indices into [0, vertexCount)), returns #T by 4 encoded
// references: out[t][k] is the face of the neighbouring tet that coincides
// with face k of t, or kNoFace. A face shared by more than two tets throws
// InputError(source, ...) naming the last of them.
std::vector<std::array<std::int32_t, 4>> tetFaceAdjacency(const std::vector<Tet>& tets, std::int32_t vertexCount,
                                                           const std::string& source);

// "tet 12 (vertices 3, 5, 8, 9)": how the input checks name a tet.
std::string describeTet(std::size_t t, const Tet& q);

}  // namespace vox::remesh
