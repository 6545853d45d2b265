#pragma once
// Sizing field of the adaptive remesher (thesis 2.3.7, eq. 2.2): the target
// edge length at every point,
//
//   l(p) = (l_I - l_B) D(p) + l_B,
//
// with D the distance to the label interfaces normalized to [0, 1], so that
// edges on the interfaces aim at l_B and edges deep inside the labels at l_I.
// Splits and collapses compare an edge with 4/3 and 4/5 of l at its
// mid-point (EdgeLengthBounds). The field is a grid of lengths in mm,
// sampled trilinearly; a user may give that grid directly (mm values).

#include "geometry/label_grid.h"
#include "geometry/scalar_grid.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <string>

namespace vox::remesh {

class SizingField {
public:
  // Target lengths (mm, all finite and > 0) at the voxel centres of
  // `lengths`. `meshToGrid` rotates the frame of the points the field is
  // sampled at (the remeshed complex's) into the grid frame of `lengths`
  // (both frames are the world rotated; world_frame.h).
  explicit SizingField(ScalarGrid lengths, const Eigen::Matrix3d& meshToGrid = Eigen::Matrix3d::Identity());

  // l(p), trilinear between voxel centres, clamped to the grid's box.
  double at(const Eigen::Vector3d& p) const { return double(lengths_.sample(meshToGrid_ * p)); }
  double minimum() const { return minimum_; }
  double maximum() const { return maximum_; }
  const ScalarGrid& lengths() const { return lengths_; }

private:
  ScalarGrid lengths_;
  Eigen::Matrix3d meshToGrid_;
  double minimum_ = 0.0, maximum_ = 0.0;
};

// D of eq. 2.2 on the voxels of `grid`: the distance from each voxel centre
// to the nearest voxel that touches a voxel of another label across a face
// (label 0 beyond the grid's border), divided by the largest such distance
// over the labelled voxels and clamped to 1. Interface voxels hold 0, so the
// field is 0 on every interface; D is 0 everywhere on a grid whose labelled
// voxels all touch an interface.
ScalarGrid normalizedInterfaceDistance(const LabelGrid& grid);

// The field of eq. 2.2 on `grid`'s voxels, in its grid frame (the frame
// `voxmorph mesh` remeshes in). Throws InputError("sizing field", ...)
// unless 0 < l_B <= l_I, both finite.
SizingField interfaceSizingField(const LabelGrid& grid, double boundaryLength, double interiorLength);

// The field of eq. 2.2 for a labelled tet mesh, in the frame of its
// positions (`voxmorph remesh`): D on a grid over the domain tets' box
// (label > 0) with voxels of l_B / 2 (coarser where that would exceed
// kMaxSizingVoxels), seeded by points on the facets between tets of
// different labels (a missing tet and label <= 0 count as 0) and normalized
// by the largest distance at a domain tet's vertex. Throws as above.
inline constexpr std::int64_t kMaxSizingVoxels = std::int64_t(1) << 25;
SizingField interfaceSizingField(const TetMesh& mesh, double boundaryLength, double interiorLength);

// Throws InputError(source, ...) naming the first voxel of `lengths` that is
// not a finite positive length.
void checkSizingGrid(const ScalarGrid& lengths, const std::string& source);

}  // namespace vox::remesh
