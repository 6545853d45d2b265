#pragma once
// ScalarGrid: a float field on a regular grid (sizing field F, error field
// e_g of the deformation-adaptive refinement, distance fields). Same geometry
// conventions as LabelGrid: value i sits at the centre of voxel i.

#include "geometry/label_grid.h"

#include <vector>

namespace vox {

struct ScalarGrid {
  GridGeometry geometry;
  std::vector<float> values;  // geometry.voxelCount() values, x fastest

  ScalarGrid() = default;
  ScalarGrid(const GridGeometry& g, float fill) : geometry(g), values(std::size_t(g.voxelCount()), fill) {}

  float at(std::int64_t i, std::int64_t j, std::int64_t k) const { return values[std::size_t(geometry.index(i, j, k))]; }
  float& at(std::int64_t i, std::int64_t j, std::int64_t k) { return values[std::size_t(geometry.index(i, j, k))]; }
  // Trilinear interpolation at a grid-frame point, clamped to the grid.
  float sample(const Eigen::Vector3d& p) const;
};

}  // namespace vox
