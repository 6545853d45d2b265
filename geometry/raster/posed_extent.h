#pragma once
// The extent of the posed grid G': the source lattice's voxel centres inside
// the box of the deformed positions, computed in floating point and converted
// to integers only once it is known to fit, so a pose that moves vertices
// astronomically far is an error naming the fault, never a wrapped or
// collapsed dimension. The growth rule on top of it is the deformation's
// (geometry/deform/pose/posed_extent.h).

#include "geometry/label_grid.h"

#include <Eigen/Core>
#include <vector>

namespace vox {

struct PosedExtent {
  Eigen::Vector3d first;  // source-lattice index of G's first voxel centre, per axis
  Eigen::Vector3d dims;   // voxels per axis (whole numbers >= 1)
  double voxels = 0.0;    // their product
};

// Throws InputError("deformed positions", ...) when empty or not finite, or
// when a position lies more than kMaxGridVoxels voxels from the source grid
// (a lattice index that no integer type of a grid can hold).
PosedExtent posedExtent(const GridGeometry& source, const std::vector<Eigen::Vector3d>& deformed);

}  // namespace vox
