#pragma once
// Transfer meshes for rendering a grid at rest (identity deformation), and
// coarse voxel TMs for tests and benchmarks until a real TM is at hand.

#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"

namespace vox {

// Six tets filling the box of the grid's foreground voxels (voxel corners,
// grid frame). Throws InputError(name, "has no foreground voxels").
TetMesh boxTransferMesh(const LabelGrid& grid, const std::string& name = "grid");

// Six-tet decomposition (voxel_tetrahedralization.h) of the grid downsampled
// by `factor` per axis, keeping the coarse cells that hold any foreground
// voxel: a conforming TM whose vertices sit on voxel corners and which covers
// every foreground voxel. factor >= 1.
TetMesh coarseVoxelTransferMesh(const LabelGrid& grid, int factor);

}  // namespace vox
