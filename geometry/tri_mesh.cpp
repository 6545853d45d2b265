#include "geometry/tri_mesh.h"

#include "geometry/error.h"

namespace vox {

void TriMesh::validate(const std::string& source) const {
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (!positions[v].allFinite()) throw InputError(source, "vertex " + std::to_string(v) + " has a non-finite coordinate");
  const auto nv = std::int64_t(positions.size());
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const Tri& t = triangles[f];
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nv)
        throw InputError(source, "triangle " + std::to_string(f) + " references vertex " + std::to_string(t[k]) +
                                     " (surface has " + std::to_string(nv) + " vertices)");
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      throw InputError(source, "triangle " + std::to_string(f) + " repeats a vertex");
  }
}

}  // namespace vox
