#pragma once
// Transfer meshes and smooth deformations for the rasterization tests and
// benchmarks, until the CGAL transfer mesh generator is available: a six-tet
// decomposition of a downsampled copy of the grid (foreground only; the
// downsampling keeps any foreground, so the mesh covers every foreground
// voxel, its corners on full-resolution voxel corners), deformed by analytic
// non-rigid maps (bend, twist) or a rotation.

#include "geometry/raster/out_of_core.h"
#include "geometry/raster/rasterize.h"
#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"
#include "geometry/voxel_tetrahedralization.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

namespace vox::test {

// Six-tet transfer mesh covering the foreground of `grid`, `factor` voxels per
// tet cube edge. Positions are in the grid frame of `grid`.
inline TetMesh coveringTransferMesh(const LabelGrid& grid, int factor) {
  LabelGridSlices slices(grid);
  return tetrahedralizeVoxels(downsampleLabels(slices, factor), {.includeBackground = false});
}

using Deformation = std::function<Eigen::Vector3d(const Eigen::Vector3d&)>;

inline std::vector<Eigen::Vector3d> deformPositions(const std::vector<Eigen::Vector3d>& rest, const Deformation& f) {
  std::vector<Eigen::Vector3d> out(rest.size());
  std::transform(rest.begin(), rest.end(), out.begin(), f);
  return out;
}

// Rotation by `degrees` about `axis` through `centre`.
inline Deformation rotation(const Eigen::Vector3d& centre, const Eigen::Vector3d& axis, double degrees) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(degrees * M_PI / 180.0, axis.normalized()).toRotationMatrix();
  return [=](const Eigen::Vector3d& p) { return Eigen::Vector3d(centre + r * (p - centre)); };
}

// Twist about the z axis through `centre`: slice z turns by
// degreesPerMm * (z - centre.z).
inline Deformation twist(const Eigen::Vector3d& centre, double degreesPerMm) {
  return [=](const Eigen::Vector3d& p) {
    const double a = degreesPerMm * (p.z() - centre.z()) * M_PI / 180.0;
    const double u = p.x() - centre.x(), v = p.y() - centre.y();
    return Eigen::Vector3d(centre.x() + std::cos(a) * u - std::sin(a) * v, centre.y() + std::sin(a) * u + std::cos(a) * v,
                           p.z());
  };
}

// Bend of the z axis around a circle of `radius` mm in the x-z plane (Barr's
// bend): the line x = centre.x keeps its length, z lines curve.
inline Deformation bend(const Eigen::Vector3d& centre, double radius) {
  return [=](const Eigen::Vector3d& p) {
    const double a = (p.z() - centre.z()) / radius;
    const double u = p.x() - centre.x();
    return Eigen::Vector3d(centre.x() + radius - (radius - u) * std::cos(a), p.y(), centre.z() + (radius - u) * std::sin(a));
  };
}

inline Eigen::Vector3d gridCentre(const GridGeometry& g) { return 0.5 * (g.boxMin() + g.boxMax()); }

}  // namespace vox::test
