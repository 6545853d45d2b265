#include "geometry/render/rest_transfer_mesh.h"

#include "geometry/error.h"
#include "geometry/voxel_tetrahedralization.h"

#include <algorithm>

namespace vox {

TetMesh boxTransferMesh(const LabelGrid& grid, const std::string& name) {
  const GridGeometry& g = grid.geometry();
  Index3 lo{g.dims[0], g.dims[1], g.dims[2]}, hi{-1, -1, -1};
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j) {
      const Label* row = grid.data() + g.index(0, j, k);
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        if (row[i] == 0) continue;
        lo = {std::min(lo[0], i), std::min(lo[1], j), std::min(lo[2], k)};
        hi = {std::max(hi[0], i), std::max(hi[1], j), std::max(hi[2], k)};
      }
    }
  if (hi[0] < 0) throw InputError(name, "has no foreground voxels");
  // One "voxel" as large as the box, decomposed like any voxel.
  GridGeometry box;
  box.dims = {1, 1, 1};
  for (int a = 0; a < 3; ++a) {
    box.spacing[a] = g.spacing[a] * double(hi[a] - lo[a] + 1);
    box.origin[a] = g.origin[a] + g.spacing[a] * 0.5 * double(lo[a] + hi[a]);
  }
  return tetrahedralizeVoxels(LabelGrid(box, 1));
}

TetMesh coarseVoxelTransferMesh(const LabelGrid& grid, int factor) {
  if (factor < 1) throw InputError("coarse transfer mesh", "downsampling factor must be at least 1");
  const GridGeometry& g = grid.geometry();
  GridGeometry c;
  for (int a = 0; a < 3; ++a) {
    c.dims[a] = (g.dims[a] + factor - 1) / factor;
    c.spacing[a] = g.spacing[a] * factor;
    // Coarse cell I covers voxels [factor I, factor I + factor).
    c.origin[a] = g.origin[a] + g.spacing[a] * 0.5 * double(factor - 1);
  }
  LabelGrid coarse(c, 0);
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i)
        if (grid.at(i, j, k) != 0) coarse.at(i / factor, j / factor, k / factor) = 1;
  return tetrahedralizeVoxels(coarse, {.includeBackground = false});
}

}  // namespace vox
