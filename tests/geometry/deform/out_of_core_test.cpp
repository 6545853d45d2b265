// Out-of-core pieces that need no file format: the covering downsampling and
// the memory split. (Out-of-core through files: out_of_core_file_test.cpp.)

#include "geometry/deform/out_of_core.h"
#include "geometry/synth.h"

#include <gtest/gtest.h>

namespace vox {
namespace {

TEST(OutOfCore, DownsamplingCoversTheForegroundWithTheMajorityLabel) {
  LabelGrid grid = synthesize(SynthKind::JunctionSphere, 33);
  grid.geometry().spacing = {0.5, 0.75, 1.25};
  grid.geometry().origin = {10, -4, 2};
  LabelGridSlices slices(grid);
  for (int factor : {1, 2, 3, 5}) {
    const LabelGrid d = downsampleLabels(slices, factor);
    const GridGeometry& g = d.geometry();
    ASSERT_EQ(g.dims[0], (grid.dims()[0] + factor - 1) / factor);
    // Block corners are source voxel corners.
    EXPECT_TRUE(g.boxMin().isApprox(grid.geometry().boxMin()));
    for (std::int64_t k = 0; k < grid.dims()[2]; ++k)
      for (std::int64_t j = 0; j < grid.dims()[1]; ++j)
        for (std::int64_t i = 0; i < grid.dims()[0]; ++i) {
          const Label block = d.at(i / factor, j / factor, k / factor);
          if (grid.at(i, j, k) != 0) {
            ASSERT_NE(block, 0) << factor;
          }
          if (factor == 1) {
            ASSERT_EQ(block, grid.at(i, j, k));
          }
        }
  }
  // Majority with ties to the lowest label, background ignored.
  GridGeometry small;
  small.dims = {2, 2, 2};
  LabelGrid g(small);
  g.labels() = {0, 0, 0, 7, 7, 3, 3, 0};
  LabelGridSlices s(g);
  EXPECT_EQ(downsampleLabels(s, 2).labels(), std::vector<Label>{3});
  GridGeometry even;
  even.dims = {40, 20, 60};
  EXPECT_EQ(downsampleFactor(even, even.voxelCount()), 1);
  EXPECT_EQ(downsampleFactor(even, even.voxelCount() / 8), 2);
  EXPECT_EQ(downsampleFactor(even, even.voxelCount() / 8 - 1), 3);
}

TEST(OutOfCore, MemoryLimitsStayWithinTheBudget) {
  for (int samples : {1, 2, 3}) {
    const std::int64_t budget = std::int64_t(2048) << 20;
    const RasterMemoryLimits l = rasterMemoryLimits(budget, samples);
    const double k3 = double(samples * samples * samples);
    const double used = 2.0 * double(l.windowVoxels) + double(l.slabSamples) * (4.0 + 4.0 / k3);
    EXPECT_LE(used, double(budget));
    EXPECT_GT(used, 0.8 * double(budget));
  }
}

}  // namespace
}  // namespace vox
