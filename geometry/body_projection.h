#pragma once
// The body's silhouette areas and height, in the world frame of
// world_frame.h (RAS+: x towards the subject's right, y anterior, z
// superior), from a label grid's foreground (every voxel whose label is not
// 0, taken as the box it covers):
//   front: area of the parallel projection along y (anterior-posterior)
//          onto the x-z (coronal) plane, mm^2;
//   side:  along x (left-right) onto the y-z (sagittal) plane, mm^2;
//   top:   along z (superior-inferior) onto the x-y (axial) plane, mm^2;
//   height: extent of the foreground along z, mm.
// The grid's direction matrix places its axes in the world, so "front" is
// the anterior-posterior view whichever way the file stores the axes.
// Whole-body SAR under a plane wave follows the cross-section the body
// presents to the incident field, which changes with the posture.
//
// Grids whose axes run along the world axes (a signed permutation, as
// NIfTI/MetaImage phantoms are stored) are measured exactly: a projection is
// the set of occupied columns along one grid axis. An oblique grid's
// projections are sampled on a raster of a quarter of its smallest spacing
// in the projection plane (a pixel counts when its centre lies in the
// projected hexagon of a foreground voxel); its height is exact.

#include "geometry/label_grid.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace vox {

struct BodyProjection {
  double frontMm2 = 0.0, sideMm2 = 0.0, topMm2 = 0.0;
  double heightMm = 0.0;
  std::int64_t foregroundVoxels = 0;
  bool exact = true;  // false: an oblique grid, areas sampled on a raster
};

// Gathers the projections of a grid given slab by slab (any order; the
// streaming paths of `deform`, which never hold the whole grid).
class BodyProjectionAccumulator {
public:
  explicit BodyProjectionAccumulator(const GridGeometry& geometry);
  // Slices [k0, k0 + count): count * nx * ny labels, x fastest.
  void addSlices(std::int64_t k0, std::int64_t count, const Label* labels);
  BodyProjection result() const;

private:
  // An oblique grid's projection along one world axis, sampled at pixel
  // centres; a voxel's projection is the hexagon (zonogon) spanned by its
  // three projected half-axes, tested against its edges' normals.
  struct Raster {
    int u = 0, v = 0;          // world axes of the image plane
    Eigen::Vector2d lo{0, 0};  // plane coordinates of pixel (0, 0)'s corner
    double pixel = 1.0;        // mm
    std::int64_t width = 0, height = 0;
    std::vector<std::uint8_t> covered;
    Eigen::Vector2d halfBox{0, 0};  // half-size of a voxel's projected bounding box
    std::vector<Eigen::Vector2d> normals;
    std::vector<double> support;  // max of n . q over the hexagon, per normal
  };
  void splat(Raster& raster, const Eigen::Vector3d& centre) const;

  GridGeometry geometry_;
  bool axisAligned_ = true;
  // Axis-aligned: occupied columns along grid axis a, indexed by the other
  // two grid indices (the lower axis fastest).
  std::array<std::vector<std::uint8_t>, 3> columns_;
  std::array<int, 3> gridAxisOfWorld_{0, 1, 2};
  std::array<Raster, 3> rasters_;  // oblique: per world axis of view
  double minWorldZ_ = 0.0, maxWorldZ_ = 0.0;  // of foreground voxel centres
  std::int64_t foreground_ = 0;
};

BodyProjection bodyProjection(const LabelGrid& grid);

}  // namespace vox
