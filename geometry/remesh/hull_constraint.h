#pragma once
// The outer hull of the imaginary layer (its facets face the dummy tets of
// label -1). For grid input it is made of axis-aligned faces: the box of the
// grid, or the faces of the cubes of a shell around the domain. A hull
// vertex may only slide within the axis-aligned planes of its hull facets
// (in a flat part of the hull, within its plane; on a crease, along it; at
// a corner, not at all), so the hull stays the same surface and the complex
// stays embedded: a hull facet that folded over would turn the imaginary
// tet behind it over. A vertex with a hull facet in no axis-aligned plane
// (an input mesh with its own imaginary layer) is fixed.

#include "geometry/remesh/element_classification.h"

#include <Eigen/Core>
#include <cstdint>

namespace vox::remesh {

class HullConstraint {
public:
  // Empty when the complex has no imaginary layer.
  explicit HullConstraint(const RemeshComplex& complex);

  // The axes (bit a) whose coordinate a hull vertex must keep, with those
  // coordinates: the axis-aligned planes of its hull facets. `frozen` when
  // one of its hull facets lies in no such plane.
  struct Planes {
    std::uint8_t mask = 0;
    Eigen::Vector3d at = Eigen::Vector3d::Zero();
    bool frozen = false;
  };
  Planes planes(const RemeshComplex& complex, const VertexNeighborhood& vertex) const;

  // p lies exactly on every plane of `planes` (and the vertex is not frozen).
  static bool allows(const Planes& planes, const Eigen::Vector3d& p);
  // p with its constrained coordinates set to the planes'.
  static Eigen::Vector3d snap(const Planes& planes, const Eigen::Vector3d& p);

private:
  bool empty_ = true;
};

}  // namespace vox::remesh
