#pragma once
// The rule that bounds the posed grid G' (its extent: raster/posed_extent.h).
// Growth rule: a pose re-arranges the body, it does not enlarge it, so G'
// may hold at most kMaxPosedGrowth times the source's voxels; a larger G'
// (a rotation centre or translation far off) is refused unless the caller
// allows growth (deform --allow-growth).

#include "geometry/deform/pose/pose.h"
#include "geometry/raster/posed_extent.h"
#include "geometry/label_grid.h"

#include <Eigen/Core>
#include <string>
#include <vector>

namespace vox {

inline constexpr double kMaxPosedGrowth = 8.0;

// The selection whose cage handles the pose moved farthest outside the
// source grid's box, as "selection '<name>'" with its transform
// ("translation (x, y, z) mm", "rotation about (x, y, z)"); empty when no
// handle left the box.
std::string selectionMovingFarthest(const Pose& pose, const PoseHandles& handles, const std::vector<Eigen::Vector3d>& deformedCage,
                                    const GridGeometry& source);

// Throws InputError(poseSource, "<culprit> makes a posed grid of A x B x C
// voxels, N times the source's ...; --allow-growth accepts it") when G'
// exceeds the growth rule or the largest supported grid (the latter even with
// allowGrowth).
void checkPosedGrowth(const GridGeometry& source, const std::vector<Eigen::Vector3d>& deformed, const std::string& poseSource,
                      const std::string& culprit, bool allowGrowth);

}  // namespace vox
