#pragma once
// LabelGrid: a segmented volume. Index math lives here and nowhere else.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace vox {

using Label = std::uint16_t;
using Index3 = std::array<std::int64_t, 3>;

// Largest grid we accept, in voxels (guards against headers whose dims
// multiply to something absurd before any allocation happens).
inline constexpr std::int64_t kMaxGridVoxels = std::int64_t(1) << 36;

// Geometry of a voxel grid without its data; shared by in-core grids and the
// out-of-core streaming paths.
//
// Coordinates: the grid frame (mm) places the centre of voxel (i,j,k) at
//   origin + spacing .* (i,j,k).
// `direction` (orthonormal columns, from the file's affine) maps the grid frame
// axes to the file's world axes; it is carried through unchanged and only
// matters for writing. Deformation, poses and rendering work in the grid frame.
struct GridGeometry {
  Index3 dims{0, 0, 0};                     // nx, ny, nz (x fastest in memory)
  Eigen::Vector3d spacing{1, 1, 1};         // voxel size in mm, all > 0
  Eigen::Vector3d origin{0, 0, 0};          // centre of voxel (0,0,0), mm
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();

  std::int64_t voxelCount() const { return dims[0] * dims[1] * dims[2]; }
  std::int64_t sliceVoxels() const { return dims[0] * dims[1]; }
  double voxelVolume() const { return spacing.prod(); }  // mm^3

  std::int64_t index(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return i + dims[0] * (j + dims[1] * k);
  }
  Index3 ijk(std::int64_t idx) const {
    const std::int64_t i = idx % dims[0];
    const std::int64_t r = idx / dims[0];
    return {i, r % dims[1], r / dims[1]};
  }
  bool contains(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < dims[0] && j < dims[1] && k < dims[2];
  }
  // Centre of voxel (i,j,k) in the grid frame.
  Eigen::Vector3d voxelCenter(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return origin + spacing.cwiseProduct(Eigen::Vector3d(double(i), double(j), double(k)));
  }
  // Continuous index of a grid-frame point (voxel centres at integers).
  Eigen::Vector3d continuousIndex(const Eigen::Vector3d& p) const {
    return (p - origin).cwiseQuotient(spacing);
  }
  // Voxel containing a grid-frame point: round to nearest centre. Returns
  // false when it lies outside the grid.
  bool voxelAt(const Eigen::Vector3d& p, Index3& out) const;
  // Axis-aligned box covered by the voxels (corners, not centres).
  Eigen::Vector3d boxMin() const { return origin - 0.5 * spacing; }
  Eigen::Vector3d boxMax() const {
    return origin + spacing.cwiseProduct(
                        Eigen::Vector3d(double(dims[0]), double(dims[1]), double(dims[2])) -
                        Eigen::Vector3d::Constant(0.5));
  }
  double diagonal() const { return (boxMax() - boxMin()).norm(); }
  // 4x4 affine from voxel index to world (file) coordinates.
  Eigen::Matrix4d indexToWorld() const;

  // Throws InputError(source, ...) when dims, spacing or direction are unusable.
  void validate(const std::string& source) const;
};

// The labels are the grid's own (a vector), or borrowed: another owner's
// buffer that the grid reads and never writes (the Python module's numpy
// arrays), kept alive by the grid. The mutable accessors throw
// std::logic_error on a borrowed grid, and so does `labels()`, whose vector
// it does not have: code that may be given one reads through data() and at().
// A copy of a grid owns its labels (a borrowed grid is copied into a vector),
// so whatever needs to write takes a copy; a move keeps the borrow.
class LabelGrid {
public:
  LabelGrid() = default;
  explicit LabelGrid(const GridGeometry& g, Label fill = 0);
  // Borrows g.voxelCount() labels at `labels` (x fastest), valid while
  // `owner` lives.
  LabelGrid(const GridGeometry& g, const Label* labels, std::shared_ptr<const void> owner);

  LabelGrid(const LabelGrid& other);
  LabelGrid& operator=(const LabelGrid& other);
  LabelGrid(LabelGrid&& other) noexcept;
  LabelGrid& operator=(LabelGrid&& other) noexcept;
  ~LabelGrid() = default;

  const GridGeometry& geometry() const { return geom_; }
  GridGeometry& geometry() { return geom_; }
  const Index3& dims() const { return geom_.dims; }
  const Eigen::Vector3d& spacing() const { return geom_.spacing; }
  const Eigen::Vector3d& origin() const { return geom_.origin; }
  std::int64_t voxelCount() const { return geom_.voxelCount(); }
  bool borrowed() const { return borrowed_ != nullptr; }

  Label at(std::int64_t i, std::int64_t j, std::int64_t k) const { return data()[geom_.index(i, j, k)]; }
  Label& at(std::int64_t i, std::int64_t j, std::int64_t k) { return labels()[geom_.index(i, j, k)]; }
  // Label at (i,j,k), or `outside` when the index is off the grid.
  Label atOr(std::int64_t i, std::int64_t j, std::int64_t k, Label outside = 0) const {
    return geom_.contains(i, j, k) ? at(i, j, k) : outside;
  }

  const std::vector<Label>& labels() const {
    if (borrowed_) throwBorrowed();
    return labels_;
  }
  std::vector<Label>& labels() {
    if (borrowed_) throwBorrowed();
    return labels_;
  }
  const Label* data() const { return borrowed_ ? borrowed_ : labels_.data(); }
  Label* data() { return labels().data(); }

  Label maxLabel() const;

private:
  [[noreturn]] static void throwBorrowed();

  GridGeometry geom_;
  std::vector<Label> labels_;
  const Label* borrowed_ = nullptr;     // the borrowed labels, or null when the grid owns them
  std::shared_ptr<const void> owner_;  // keeps borrowed_ alive
};

}  // namespace vox
