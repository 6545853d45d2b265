#include "geometry/deform/pose/pose_frame.h"

#include "geometry/error.h"
#include "geometry/world_frame.h"

#include <Eigen/LU>

namespace vox {

namespace {

// A world box as a grid box: exact for axis-aligned grids (the corners'
// images span the same box).
void mapBox(const GridGeometry& g, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
  const Eigen::Vector3d a = worldToGrid(g, lo), b = worldToGrid(g, hi);
  lo = a.cwiseMin(b);
  hi = a.cwiseMax(b);
}

void mapBox(const GridGeometry& g, Eigen::AlignedBox3d& box) {
  if (box.isEmpty()) return;
  Eigen::Vector3d lo = box.min(), hi = box.max();
  mapBox(g, lo, hi);
  box = Eigen::AlignedBox3d(lo, hi);
}

void mapTransform(const GridGeometry& g, PoseTransform& t) {
  // R' = D^T R D is the rotation about D^T axis by the same angle when D is
  // a rotation, and by the opposite angle when D mirrors.
  t.axis = worldToGrid(g, t.axis);
  if (g.direction.determinant() < 0.0) t.angleDeg = -t.angleDeg;
  t.center = worldToGrid(g, t.center);
  t.translation = worldToGrid(g, t.translation);
}

}  // namespace

void regionInGridFrame(std::optional<Eigen::AlignedBox3d>& region, const GridGeometry& grid, const std::string& source) {
  if (!region || grid.direction.isIdentity(0.0)) return;
  if (!axisAligned(grid)) throw InputError(source, "the grid's axes are oblique to the world frame: a box region is not a box of the grid");
  mapBox(grid, *region);
}

Pose poseInGridFrame(const Pose& pose, const GridGeometry& grid, const std::string& source) {
  if (pose.frame == PoseFrame::Grid || grid.direction.isIdentity(0.0)) return pose;
  if (!axisAligned(grid))
    throw InputError(source, "the grid's axes are oblique to the world frame, so the pose's boxes are not boxes of the grid; "
                             "give the pose in the grid frame (\"frame\": \"grid\")");
  Pose p = pose;
  for (PoseSelection& s : p.selections) {
    mapBox(grid, s.boxMin, s.boxMax);
    s.center = worldToGrid(grid, s.center);
    for (Eigen::Vector3d& q : s.points) q = worldToGrid(grid, q);
    if (s.part) s.part = worldToGrid(grid, *s.part);
    mapTransform(grid, s.transform);
  }
  for (PoseSeparation& s : p.separations) {
    if (s.cage.region) mapBox(grid, *s.cage.region);
    if (s.cutRegion) mapBox(grid, *s.cutRegion);
  }
  for (PoseJoint& j : p.joints) {
    if (j.center) j.center = worldToGrid(grid, *j.center);
    if (j.axis) j.axis = worldToGrid(grid, *j.axis);
  }
  p.frame = PoseFrame::Grid;
  return p;
}

}  // namespace vox
