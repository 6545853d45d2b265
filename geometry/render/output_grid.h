#pragma once
// Geometry of the deformed grid G' (thesis 3.2.4) that the rasterizer fills
// and the ray caster traverses: the source spacing, voxel centres on the
// source lattice (origin + spacing .* integer index), and every lattice point
// inside the bounding box of the deformed transfer mesh. An identity
// deformation therefore reproduces the source voxels exactly.

#include "geometry/label_grid.h"

#include <vector>

namespace vox {

// `deformedPositions`: #V TM vertex positions, grid frame (mm). The direction
// matrix is copied from the source. Axes on which no lattice point lies
// inside the box get 0 voxels.
GridGeometry outputGridGeometry(const GridGeometry& source, const std::vector<Eigen::Vector3d>& deformedPositions);

}  // namespace vox
