#pragma once
// A pose in the grid frame, where the deformation pipeline works: world-frame
// poses (the default, world_frame.h) are mapped by the grid's direction;
// "frame": "grid" poses pass unchanged.

#include "geometry/deform/pose/pose.h"
#include "geometry/label_grid.h"

#include <Eigen/Geometry>
#include <optional>
#include <string>

namespace vox {

// Throws InputError(source, ...) for a world-frame pose on a grid whose axes
// are oblique to the world's: its boxes would not be boxes in the grid frame
// (give such a pose in the grid frame).
Pose poseInGridFrame(const Pose& pose, const GridGeometry& grid, const std::string& source);
// A world-frame region (--separate's box) in the grid frame; the same fault.
void regionInGridFrame(std::optional<Eigen::AlignedBox3d>& region, const GridGeometry& grid, const std::string& source);

}  // namespace vox
