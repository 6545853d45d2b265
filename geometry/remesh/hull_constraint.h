#pragma once
// The outer hull of the imaginary layer (its facets face the dummy tets of
// label -1) is an axis-aligned box for grid input. Hull vertices may only
// slide within the box faces they lie on, so the hull stays that box and the
// complex stays embedded: all tets positive inside a convex, fixed boundary.
// A hull that is not a box (an input mesh with its own imaginary layer)
// keeps its non-planar vertices fixed.

#include "geometry/remesh/element_classification.h"

#include <Eigen/Core>
#include <cstdint>

namespace vox::remesh {

class HullConstraint {
public:
  // Box of the hull vertices (vertices of tets labelled kDummyLabel), empty
  // when the complex has no imaginary layer.
  explicit HullConstraint(const RemeshComplex& complex);

  // Which box planes (bit 2 axis + 0 for the low side, + 1 for the high side)
  // a hull vertex must stay on: the planes of its hull facets. `frozen` when
  // one of its hull facets lies on no box plane.
  struct Planes {
    std::uint8_t mask = 0;
    bool frozen = false;
  };
  Planes planes(const RemeshComplex& complex, const VertexNeighborhood& vertex) const;

  // p lies exactly on every plane of `planes` (and the vertex is not frozen).
  bool allows(const Planes& planes, const Eigen::Vector3d& p) const;
  // p with its constrained coordinates set to the planes'.
  Eigen::Vector3d snap(const Planes& planes, const Eigen::Vector3d& p) const;

private:
  std::uint8_t planeMask(const Eigen::Vector3d& p) const;
  Eigen::Vector3d lo_, hi_;
  bool empty_ = true;
};

}  // namespace vox::remesh
