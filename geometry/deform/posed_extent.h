#pragma once
// The extent of the posed grid G' and the rule that bounds it. G' holds the
// source lattice's voxel centres inside the box of the deformed positions;
// its size is computed in floating point and converted to integers only once
// it is known to fit, so a pose that moves vertices astronomically far is an
// error naming the fault, never a wrapped or collapsed dimension.
//
// Growth rule: a pose re-arranges the body, it does not enlarge it, so G'
// may hold at most kMaxPosedGrowth times the source's voxels; a larger G'
// (a rotation centre or translation far off) is refused unless the caller
// allows growth (deform --allow-growth).

#include "geometry/deform/pose.h"
#include "geometry/label_grid.h"

#include <Eigen/Core>
#include <string>
#include <vector>

namespace vox {

inline constexpr double kMaxPosedGrowth = 8.0;

struct PosedExtent {
  Eigen::Vector3d first;  // source-lattice index of G's first voxel centre, per axis
  Eigen::Vector3d dims;   // voxels per axis (whole numbers >= 1)
  double voxels = 0.0;    // their product
};

// Throws InputError("deformed positions", ...) when empty or not finite, or
// when a position lies more than kMaxGridVoxels voxels from the source grid
// (a lattice index that no integer type of a grid can hold).
PosedExtent posedExtent(const GridGeometry& source, const std::vector<Eigen::Vector3d>& deformed);

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
