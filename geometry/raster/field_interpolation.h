#pragma once
// A per-vertex scalar of a tet mesh interpolated onto a grid through the
// containing tet: the barycentric interpolation at every voxel centre that
// lies in a tet. This is how the deformation-adaptive refinement turns
// per-vertex errors into the grid error field e_g (thesis eq. 4.6-4.7) and
// per-vertex resizing factors into a grid (thesis 3.2). CPU reference of
// gpu/kernels/field_interpolation.h.

#include "geometry/label_grid.h"
#include "geometry/scalar_grid.h"
#include "geometry/tet_mesh.h"

#include <functional>
#include <vector>

namespace vox {

struct FieldInterpolationOptions {
  float fill = 0.0f;  // value of voxels whose centre is in no tet
  int threads = 0;    // CPU threads; 0 = every hardware thread
};

// Throws InputError unless mesh is valid and values holds #V finite values.
void validateVertexField(const TetMesh& mesh, const std::vector<double>& values);

// mesh: positions in the grid frame of `target` (mm); values: #V per-vertex
// values. Voxel centres in several tets (shared faces) take the lowest-index
// tet, as in the rasterizer (lattice_tets.h). Throws InputError for a value
// count mismatch, non-finite values or bad connectivity.
ScalarGrid interpolateVertexField(const TetMesh& mesh, const std::vector<double>& values, const GridGeometry& target,
                                  const FieldInterpolationOptions& options = {});

// Interpolation of a per-vertex field of a tet mesh onto a grid (CPU:
// interpolateVertexField; GPU: gpu::FieldInterpolationKernel). `fill` for
// voxel centres in no tet.
using VertexFieldInterpolation =
    std::function<ScalarGrid(const TetMesh& mesh, const std::vector<double>& values, const GridGeometry& target, float fill)>;
VertexFieldInterpolation cpuFieldInterpolation(int threads = 0);

}  // namespace vox
