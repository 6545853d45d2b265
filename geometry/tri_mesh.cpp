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

Eigen::Vector3d nearestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double sum = va + vb + vc;
  if (!(sum > 0)) return a;  // degenerate triangle
  return a + ab * (vb / sum) + ac * (vc / sum);
}

}  // namespace vox
