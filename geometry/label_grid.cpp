#include "geometry/label_grid.h"

#include "geometry/error.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
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

LabelGrid::LabelGrid(const GridGeometry& g, const Label* labels, std::shared_ptr<const void> owner)
    : geom_(g), borrowed_(labels), owner_(std::move(owner)) {}

LabelGrid::LabelGrid(const LabelGrid& other)
    : geom_(other.geom_), labels_(other.borrowed_ ? std::vector<Label>(other.borrowed_, other.borrowed_ + other.voxelCount()) : other.labels_) {}

LabelGrid& LabelGrid::operator=(const LabelGrid& other) {
  if (this != &other) *this = LabelGrid(other);
  return *this;
}

LabelGrid::LabelGrid(LabelGrid&& other) noexcept
    : geom_(std::move(other.geom_)), labels_(std::move(other.labels_)), borrowed_(other.borrowed_), owner_(std::move(other.owner_)) {
  other.borrowed_ = nullptr;
}

LabelGrid& LabelGrid::operator=(LabelGrid&& other) noexcept {
  if (this == &other) return *this;
  geom_ = std::move(other.geom_);
  labels_ = std::move(other.labels_);
  borrowed_ = other.borrowed_;
  owner_ = std::move(other.owner_);
  other.borrowed_ = nullptr;
  return *this;
}

void LabelGrid::throwBorrowed() {
  throw std::logic_error("LabelGrid: the labels are borrowed and read-only; read them through data(), or copy the grid to own them");
}

Label LabelGrid::maxLabel() const {
  if (borrowed_) return voxelCount() == 0 ? Label(0) : *std::max_element(borrowed_, borrowed_ + voxelCount());
  return labels_.empty() ? Label(0) : *std::max_element(labels_.begin(), labels_.end());
}

}  // namespace vox
