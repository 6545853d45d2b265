#include "gpu/kernels/label_stats.h"

#include "shaders/shared/interface.h"

#include <algorithm>
#include <cstring>

namespace vox::gpu {

namespace {
using shader::LabelStatsPush;
constexpr std::uint64_t kVoxelsPerGroup = VOX_LABEL_STATS_GROUP_SIZE * VOX_LABEL_STATS_VOXELS_PER_THREAD;
constexpr std::uint64_t kVoxelsPerBlock = 8;  // one uvec4 of uint16 labels
}  // namespace

LabelStatsKernel::LabelStatsKernel(Context& context, LabelStatsOptions options)
    : context_(context),
      options_(options),
      pipeline_(context, {"label_stats.comp",
                          {BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::StorageBuffer},
                          sizeof(LabelStatsPush)}) {
  // The shader reads labels eight at a time (one uvec4), so chunks start on
  // multiples of 8 voxels; they are limited by the binding size and the
  // work-group count limit.
  std::uint64_t cap = context.maxBindingBytes() / sizeof(Label);
  cap = std::min<std::uint64_t>(cap, std::uint64_t(context.info().maxWorkGroupCount[0]) * kVoxelsPerGroup);
  chunkVoxels_ = options.chunkVoxels ? std::min(options.chunkVoxels, cap) : cap;
  chunkVoxels_ = std::max<std::uint64_t>(kVoxelsPerBlock, chunkVoxels_ / kVoxelsPerBlock * kVoxelsPerBlock);
}

LabelStats LabelStatsKernel::run(const LabelGrid& grid) {
  LabelStats stats;
  stats.resize(std::size_t(grid.maxLabel()) + 1);
  accumulate(grid.geometry(), 0, grid.dims()[2], grid.data(), stats);
  return stats;
}

void LabelStatsKernel::accumulate(const GridGeometry& g, std::int64_t k0, std::int64_t count, const Label* slices,
                                  LabelStats& stats) {
  lastGpuMs_ = 0.0;
  const std::uint64_t total = std::uint64_t(count) * std::uint64_t(g.sliceVoxels());
  if (total == 0) return;
  const std::uint32_t labelCount = std::uint32_t(stats.counts.size());
  const std::uint64_t chunk = std::min(chunkVoxels_, (total + kVoxelsPerBlock - 1) / kVoxelsPerBlock * kVoxelsPerBlock);
  const std::uint64_t labelBytes = chunk * sizeof(Label);
  if (!labels_.valid() || labels_.size() < labelBytes) labels_ = Buffer(context_, labelBytes, MemoryIntent::Upload);

  Buffer counts(context_, std::uint64_t(labelCount) * 4, MemoryIntent::Readback);
  Buffer boxes(context_, std::uint64_t(labelCount) * 24, MemoryIntent::Readback);
  std::vector<std::uint32_t> hostCounts(labelCount), hostBoxes(std::size_t(labelCount) * 6);
  CommandBatch batch(context_);

  const std::uint64_t nx = std::uint64_t(g.dims[0]), ny = std::uint64_t(g.dims[1]);
  for (std::uint64_t first = 0; first < total; first += chunk) {
    const std::uint64_t n = std::min(chunk, total - first);
    // Host data goes in through a mapped upload buffer (or a staging copy).
    // The last chunk's final block is padded; the shader stops at voxelCount.
    const std::uint64_t paddedBytes = (n + kVoxelsPerBlock - 1) / kVoxelsPerBlock * kVoxelsPerBlock * sizeof(Label);
    if (labels_.mapped()) {
      std::memcpy(labels_.mapped(), slices + first, n * sizeof(Label));
    } else {
      labels_.upload(slices + first, n * sizeof(Label));
    }
    const std::uint64_t startIndex = first;
    LabelStatsPush push{};
    push.voxelCount = std::uint32_t(n);
    push.labelCount = labelCount;
    push.nx = std::uint32_t(nx);
    push.ny = std::uint32_t(ny);
    push.startX = std::uint32_t(startIndex % nx);
    push.startY = std::uint32_t((startIndex / nx) % ny);
    push.startZ = std::uint32_t(std::uint64_t(k0) + startIndex / (nx * ny));

    std::fill(hostCounts.begin(), hostCounts.end(), 0u);
    for (std::uint32_t l = 0; l < labelCount; ++l) {
      std::fill_n(hostBoxes.begin() + 6 * l, 3, 0xFFFFFFFFu);
      std::fill_n(hostBoxes.begin() + 6 * l + 3, 3, 0u);
    }
    counts.upload(hostCounts.data(), hostCounts.size() * 4);
    boxes.upload(hostBoxes.data(), hostBoxes.size() * 4);
    batch.timestamp("start");
    const std::uint32_t groups = std::uint32_t((n + kVoxelsPerGroup - 1) / kVoxelsPerGroup);
    batch.dispatch(pipeline_,
                   {Binding::storage(labels_, 0, paddedBytes), Binding::storage(counts), Binding::storage(boxes)}, push,
                   groups);
    batch.barrier();
    batch.timestamp("end");
    batch.submitAndWait();
    if (batch.timings().size() == 2) lastGpuMs_ += batch.timings()[1].ms;

    counts.download(hostCounts.data(), hostCounts.size() * 4);
    boxes.download(hostBoxes.data(), hostBoxes.size() * 4);
    for (std::uint32_t l = 0; l < labelCount; ++l) {
      if (hostCounts[l] == 0) continue;
      stats.counts[l] += hostCounts[l];
      LabelBox& b = stats.boxes[l];
      for (int a = 0; a < 3; ++a) {
        b.lo[a] = std::min(b.lo[a], std::int32_t(hostBoxes[6 * l + a]));
        b.hi[a] = std::max(b.hi[a], std::int32_t(hostBoxes[6 * l + 3 + a]));
      }
    }
  }
}

}  // namespace vox::gpu
