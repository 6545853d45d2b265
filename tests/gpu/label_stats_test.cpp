// GPU label statistics equal the CPU reference, on synthetic grids with chunk
// boundaries inside rows and slices, and on both ICRP 110 phantoms.

#include "geometry/io/grid_io.h"
#include "geometry/label_stats.h"
#include "geometry/synth.h"
#include "gpu/context.h"
#include "gpu/kernels/label_stats.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <random>

namespace vox {
namespace {

gpu::Context& context() {
  static gpu::Context ctx;
  return ctx;
}

TEST(LabelStatsGpu, SynthFiguresEqualCpuReference) {
  for (SynthKind kind : {SynthKind::NestedSpheres, SynthKind::JunctionSphere, SynthKind::StickFigure}) {
    const LabelGrid grid = synthesize(kind, 40);
    gpu::LabelStatsKernel kernel(context());
    EXPECT_EQ(kernel.run(grid), computeLabelStats(grid)) << synthKindName(kind);
  }
}

TEST(LabelStatsGpu, ChunkBoundariesInsideRowsAndSlices) {
  // Odd dims, random labels (short runs, every label) and tiny chunks whose
  // boundaries fall mid-row and mid-slice, including odd voxel counts.
  GridGeometry g;
  g.dims = {37, 23, 11};
  LabelGrid grid(g);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick(0, 300);
  for (auto& l : grid.labels()) l = Label(pick(rng) < 250 ? pick(rng) % 7 : pick(rng));
  grid.at(36, 22, 10) = 65535;
  const LabelStats cpu = computeLabelStats(grid);
  for (std::uint64_t chunk : {2ull, 10ull, 1000ull, 4096ull, 37ull * 23 + 1, 0ull}) {
    gpu::LabelStatsKernel kernel(context(), {chunk});
    EXPECT_EQ(kernel.run(grid), cpu) << "chunk " << chunk;
  }
}

TEST(LabelStatsGpu, StreamedSlicesAccumulateLikeWholeGrid) {
  const LabelGrid grid = synthesize(SynthKind::StickFigure, 50);
  LabelStats streamed;
  streamed.resize(std::size_t(grid.maxLabel()) + 1);
  gpu::LabelStatsKernel kernel(context(), {777});
  const auto& g = grid.geometry();
  for (std::int64_t k = 0; k < g.dims[2]; k += 7) {
    const std::int64_t n = std::min<std::int64_t>(7, g.dims[2] - k);
    kernel.accumulate(g, k, n, grid.data() + k * g.sliceVoxels(), streamed);
  }
  EXPECT_EQ(streamed, computeLabelStats(grid));
}

TEST(LabelStatsGpu, IcrpPhantomsEqualCpuReference) {
  for (const char* name : {"icrp110_am.nii.gz", "icrp110_af.nii.gz"}) {
    const LabelGrid grid = readGrid(test::assetPath(name));
    gpu::LabelStatsKernel kernel(context());
    const LabelStats gpu = kernel.run(grid);
    const LabelStats cpu = computeLabelStats(grid);
    EXPECT_EQ(gpu, cpu) << name;
    EXPECT_GT(cpu.presentLabels(), 100u) << name;
    EXPECT_EQ(cpu.counts[0] + cpu.foregroundVoxels(), std::uint64_t(grid.voxelCount()));
  }
}

}  // namespace
}  // namespace vox
