#include "geometry/label_grid.h"

#include "geometry/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace vox {

bool GridGeometry::voxelAt(const Eigen::Vector3d& p, Index3& out) const {
  const Eigen::Vector3d c = continuousIndex(p);
  for (int a = 0; a < 3; ++a) {
    const double r = std::floor(c[a] + 0.5);
    if (!(r >= 0.0) || r >= double(dims[a])) return false;
    out[a] = std::int64_t(r);
  }
  return true;
}

Eigen::Matrix4d GridGeometry::indexToWorld() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = direction * spacing.asDiagonal();
  m.topRightCorner<3, 1>() = direction * origin;
  return m;
}

void GridGeometry::validate(const std::string& source) const {
  for (int a = 0; a < 3; ++a) {
    if (dims[a] <= 0) throw InputError(source, "grid dimension " + std::to_string(a) + " is " + std::to_string(dims[a]) + " (must be positive)");
    if (!std::isfinite(spacing[a]) || spacing[a] <= 0.0)
      throw InputError(source, "voxel spacing along axis " + std::to_string(a) + " is " + std::to_string(spacing[a]) + " (must be finite and positive)");
    if (!std::isfinite(origin[a])) throw InputError(source, "grid origin is not finite");
  }
  // Product check without overflow.
  std::int64_t n = 1;
  for (int a = 0; a < 3; ++a) {
    if (dims[a] > kMaxGridVoxels / n)
      throw InputError(source, "grid dimensions " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                                   std::to_string(dims[2]) + " exceed the supported voxel count");
    n *= dims[a];
  }
  if (!direction.allFinite()) throw InputError(source, "grid orientation is not finite");
  const Eigen::Matrix3d dtd = direction.transpose() * direction;
  if (!dtd.isApprox(Eigen::Matrix3d::Identity(), 1e-3))
    throw InputError(source, "grid orientation is not orthonormal");
}

LabelGrid::LabelGrid(const GridGeometry& g, Label fill) : geom_(g), labels_(std::size_t(g.voxelCount()), fill) {}

Label LabelGrid::maxLabel() const {
  return labels_.empty() ? Label(0) : *std::max_element(labels_.begin(), labels_.end());
}

}  // namespace vox
