#pragma once
// GPU per-label voxel counts and bounding boxes (shaders/label_stats.comp).
// CPU reference: geometry/label_stats.h. The grid is processed in chunks of
// whole voxels that fit one storage binding, so any size works on lavapipe.

#include "geometry/label_grid.h"
#include "geometry/label_stats.h"
#include "gpu/buffer.h"
#include "gpu/command.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"

#include <memory>
#include <vector>

namespace vox::gpu {

struct LabelStatsOptions {
  // Voxels per chunk; 0 = as many as one storage binding holds. Tests set a
  // small value to exercise chunk boundaries inside rows and slices.
  std::uint64_t chunkVoxels = 0;
};

class LabelStatsKernel {
public:
  explicit LabelStatsKernel(Context& context, LabelStatsOptions options = {});

  LabelStats run(const LabelGrid& grid);
  // Adds slices [k0, k0 + count) of a grid given slice by slice; `stats` must
  // already be sized for every label that occurs (see LabelStats::resize).
  void accumulate(const GridGeometry& geometry, std::int64_t k0, std::int64_t count, const Label* slices, LabelStats& stats);

  // GPU time of the last run / accumulate, in ms (0 without timestamps).
  double lastGpuMs() const { return lastGpuMs_; }

private:
  Context& context_;
  LabelStatsOptions options_;
  ComputePipeline pipeline_;
  std::uint64_t chunkVoxels_ = 0;
  Buffer labels_;
  double lastGpuMs_ = 0.0;
};

}  // namespace vox::gpu
