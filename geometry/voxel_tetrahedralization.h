#pragma once
// Six-tet (Kuhn / Freudenthal) decomposition of the voxels of a label grid:
// every voxel cube is split into six tets around its main diagonal, the same
// way in every voxel, so the decomposition is conforming across voxels.

#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"

namespace vox {

struct VoxelTetrahedralizationOptions {
  // Keep the tets of label-0 voxels (the whole bounding box) or only the
  // foreground voxels' tets.
  bool includeBackground = true;
};

// Vertices sit at voxel corners: origin + spacing .* (i - 1/2, j - 1/2, k - 1/2)
// in the grid frame. Tet labels are the voxel labels. Every tet is positively
// oriented. Vertices not used by any kept tet are dropped; vertex order is
// corner-index order, tet order is voxel order then the six tets of a voxel.
TetMesh tetrahedralizeVoxels(const LabelGrid& grid, const VoxelTetrahedralizationOptions& options = {});

}  // namespace vox
