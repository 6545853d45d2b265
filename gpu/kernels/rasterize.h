#pragma once
// GPU rasterization of the deformed grid (shaders/rasterize_*.comp). CPU
// reference: geometry/raster/rasterize.h, whose contract, tie rule and
// supersampling this kernel follows; planes and maps are computed in double
// on the host and evaluated in float on the GPU, so the two can differ only
// where a voxel centre lies within float rounding of a tet face (or its
// source position within float rounding of a source voxel boundary).
//
// Per slab of output slices: locate (lattice_locate.h: per-tet scanline
// spans, atomicMin of the tet index), resolve once per source window (the
// same tasks label the samples their tet won), reduce (majority of the k^3
// samples, uint16 pack). Chunking keeps every storage binding under
// Context::maxBindingBytes(): the sample states of a slab fill at most one
// binding, the source window spans up to VOX_RASTER_SOURCE_PARTS bindings of
// one allocation (2 GiB at most), and slabs with too many tets or tasks are
// split. Supersampling is limited to output slices of at most
// maxBindingBytes / (4 k^3) voxels.

#include "geometry/raster/rasterize.h"
#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"
#include "gpu/buffer.h"
#include "gpu/command.h"
#include "gpu/context.h"
#include "gpu/kernels/lattice_locate.h"
#include "gpu/pipeline.h"

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

namespace vox::gpu {

struct RasterizeKernelOptions {
  int samples = 1;  // k: k^3 samples per output voxel (RasterizeOptions::samples)
  // Upper bounds, 0 = the device's: sample states per slab (4 bytes each) and
  // source labels per window (2 bytes each). The out-of-core driver derives
  // them from its memory budget; tests set small ones to cross boundaries.
  std::uint64_t maxSlabSamples = 0;
  std::uint64_t maxWindowVoxels = 0;
};

class RasterizeKernel : public SlabRasterizer {
public:
  // In core: `source` (which must outlive the kernel) is uploaded once, on
  // the first slab, and stays on the GPU while its size allows.
  RasterizeKernel(Context& context, const LabelGrid& source, const TetMesh& rest, const RasterizeKernelOptions& options = {});
  // Streaming: source slices are read through `source` (which must outlive
  // the kernel) when a slab needs them.
  RasterizeKernel(Context& context, GridSliceReader& source, const TetMesh& rest, const RasterizeKernelOptions& options = {});

  // Deformed TM positions (#V, rest vertex order): plans G' and its slabs.
  // Throws InputError as RasterizationPlan does.
  void setDeformedPositions(const std::vector<Eigen::Vector3d>& deformed);
  // In core: G' for these positions.
  LabelGrid rasterize(const std::vector<Eigen::Vector3d>& deformed);
  const RasterizationPlan& plan() const;

  const GridGeometry& outputGeometry() const override { return plan().output(); }
  std::int64_t slabSlices() const override;
  void rasterizeSlab(std::int64_t z0, std::int64_t z1, Label* out) override;

  // GPU time (ms) since the last setDeformedPositions (0 without
  // timestamps), and the parts of it spent in the locate and resolve stages
  // (the rest: reduce).
  double gpuMs() const { return gpuMs_; }
  double locateMs() const { return locateMs_; }
  double resolveMs() const { return resolveMs_; }

private:
  RasterizeKernel(Context& context, std::unique_ptr<GridSliceReader> owned, GridSliceReader* borrowed, const TetMesh& rest,
                  const RasterizeKernelOptions& options);
  static std::int64_t windowSlicesFor(const Context& context, const GridGeometry& source,
                                      const RasterizeKernelOptions& options);
  void loadWindow(const SliceRange& window);
  Binding sourcePart(int part) const;

  Context& context_;
  std::unique_ptr<GridSliceReader> ownedSource_;
  GridSliceReader& source_;
  TetMesh rest_;
  RasterizeKernelOptions options_;
  LatticeLocateKernel locate_;
  std::int64_t windowSlices_ = 0;  // source slices the window holds
  ComputePipeline resolve_, reduce_;
  CommandBatch batch_;
  Buffer maps_, output_, window_;
  SliceRange resident_;
  std::unique_ptr<RasterizationPlan> plan_;
  std::uint64_t maxSlabSamples_ = 0;
  double gpuMs_ = 0.0;
  double locateMs_ = 0.0;
  double resolveMs_ = 0.0;
};

}  // namespace vox::gpu
