#pragma once
// TriMesh: triangle surface (cages, envelopes). Positions beside connectivity.

#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <string>
#include <vector>

namespace vox {

struct TriMesh {
  std::vector<Eigen::Vector3d> positions;  // #V, mm
  std::vector<Tri> triangles;              // #F, counter-clockwise seen from outside

  std::size_t vertexCount() const { return positions.size(); }
  std::size_t faceCount() const { return triangles.size(); }

  // Throws InputError(source, ...) for out-of-range or repeated indices and
  // non-finite coordinates.
  void validate(const std::string& source) const;
};

// The point of triangle abc nearest p (Ericson, Real-Time Collision
// Detection, 5.1.5: by the Voronoi region of p); a for a degenerate triangle.
Eigen::Vector3d nearestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c);

}  // namespace vox
