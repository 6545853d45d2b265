#pragma once
// GPU field interpolation (shaders/rasterize_locate.comp then
// shaders/interpolate_field.comp): a per-vertex scalar of a tet mesh
// interpolated onto a grid through the containing tet, for the refinement's
// error and sizing fields. CPU reference: geometry/raster/field_interpolation.h
// (same tie rule; float evaluation on the GPU).

#include "geometry/label_grid.h"
#include "geometry/scalar_grid.h"
#include "geometry/tet_mesh.h"
#include "gpu/buffer.h"
#include "gpu/command.h"
#include "gpu/context.h"
#include "gpu/kernels/lattice_locate.h"
#include "gpu/pipeline.h"

#include <cstdint>
#include <vector>

namespace vox::gpu {

struct FieldInterpolationKernelOptions {
  // Grid points per slab, 0 = as many as one storage binding holds. Tests
  // set small values to cross slab boundaries.
  std::uint64_t maxSlabPoints = 0;
};

class FieldInterpolationKernel {
public:
  explicit FieldInterpolationKernel(Context& context, const FieldInterpolationKernelOptions& options = {});

  // mesh positions in the grid frame of `target` (mm), values: #V per-vertex
  // values; `fill` where no tet contains the voxel centre. Throws InputError
  // as interpolateVertexField does.
  ScalarGrid run(const TetMesh& mesh, const std::vector<double>& values, const GridGeometry& target, float fill = 0.0f);

  // GPU time of the last run, in ms (0 without timestamps).
  double lastGpuMs() const { return lastGpuMs_; }

private:
  void runSlab(const std::vector<LatticeTet>& tets, const TetMesh& mesh, const std::vector<double>& values,
               const GridGeometry& target, float fill, std::int64_t z0, std::int64_t z1, float* out);

  Context& context_;
  FieldInterpolationKernelOptions options_;
  LatticeLocateKernel locate_;
  ComputePipeline pipeline_;
  CommandBatch batch_;
  Buffer maps_, output_;
  double lastGpuMs_ = 0.0;
};

}  // namespace vox::gpu
