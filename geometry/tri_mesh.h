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

}  // namespace vox
