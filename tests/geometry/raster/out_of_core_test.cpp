// Out-of-core deformation: the covering downsampling, the memory split, and
// the slab-streamed output equal to the in-core result, through compressed
// and plain files, with a memory budget that forces many slabs and windows.

#include "geometry/raster/out_of_core.h"
#include "geometry/raster/raster_engines.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/parallel.h"
#include "geometry/synth.h"
#include "geometry/voxel_tetrahedralization.h"
#include "tests/support/deformation_fixtures.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <filesystem>

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

TEST(OutOfCore, DownsamplingInMemoryEqualsTheStreamOnAnyThreadCount) {
  LabelGrid grid = synthesize(SynthKind::JunctionSphere, 33);
  grid.geometry().spacing = {0.5, 0.75, 1.25};
  LabelGridSlices slices(grid);
  for (int factor : {1, 2, 3, 5}) {
    const LabelGrid streamed = downsampleLabels(slices, factor);
    for (int threads : {1, 3}) {
      const ScopedWorkerThreads scope(threads);
      const LabelGrid d = downsampleLabels(grid, factor);
      EXPECT_EQ(d.labels(), streamed.labels()) << factor << " " << threads;
      EXPECT_EQ(d.dims(), streamed.dims());
      EXPECT_TRUE(d.geometry().boxMin().isApprox(streamed.geometry().boxMin()));
      EXPECT_TRUE(d.spacing().isApprox(streamed.spacing()));
    }
  }
  EXPECT_THROW(downsampleLabels(grid, 0), InputError);
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

LabelGrid figure() {
  LabelGrid grid = synthesize(SynthKind::StickFigure, 64);
  grid.geometry().spacing = {1.5, 1.25, 2.0};
  grid.geometry().origin = {-20.0, 7.0, 3.0};
  return grid;
}

OutOfCoreSource openSource(const std::string& path, std::int64_t maxVoxels, const std::string& dir) {
  return OutOfCoreSource(openGridSlices(path), path, gridSlicesSeekable(path), maxVoxels, dir);
}

// G' written as `voxmorph deform --max-memory` writes it, on the CPU engines.
void writeOutOfCore(OutOfCoreSource& source, const TetMesh& tm, const std::vector<Eigen::Vector3d>& deformed, const std::string& path,
                    int samples = 1, std::int64_t budgetBytes = std::int64_t(2048) << 20) {
  CpuRasterEngines engines;
  const auto engine = makeRasterizer(engines, {.slices = &source.slices()}, tm, deformed, samples, budgetBytes);
  writePosedGrid(*engine, *createGridSlices(path, engine->outputGeometry(), source.maxLabel()));
}

TEST(OutOfCore, StreamedOutputEqualsInCoreThroughFiles) {
  const std::string dir = test::tempDir();
  const LabelGrid grid = figure();
  for (const char* sourceName : {"source.nii.gz", "source.nii"}) {
    const std::string sourcePath = dir + "/" + sourceName;
    writeGrid(sourcePath, grid);
    OutOfCoreSource source = openSource(sourcePath, grid.voxelCount() / 27, dir);
    EXPECT_EQ(source.downsampleFactor(), downsampleFactor(grid.geometry(), grid.voxelCount() / 27));
    EXPECT_GE(source.downsampleFactor(), 3);
    EXPECT_EQ(source.maxLabel(), grid.maxLabel());
    EXPECT_EQ(source.geometry().dims, grid.dims());
    // The pipeline's transfer mesh comes from the downsampled grid.
    const TetMesh tm = tetrahedralizeVoxels(source.downsampled(), {.includeBackground = false});
    const auto deformed = test::deformPositions(tm.positions, test::bend(test::gridCentre(grid.geometry()), 60.0));
    for (int samples : {1, 2}) {
      const LabelGrid expected = rasterizeDeformedGrid(grid, tm, deformed, {.samples = samples});
      for (const char* outputName : {"posed.nii.gz", "posed.mha"}) {
        const std::string outputPath = dir + "/" + outputName;
        // 64 KiB: windows of a few source slices, slabs of a few output slices.
        writeOutOfCore(source, tm, deformed, outputPath, samples, 64 << 10);
        const LabelGrid got = readGrid(outputPath);
        ASSERT_EQ(got.dims(), expected.dims());
        EXPECT_TRUE(got.geometry().origin.isApprox(expected.geometry().origin, 1e-5));
        EXPECT_TRUE(got.spacing().isApprox(expected.spacing(), 1e-5));
        EXPECT_EQ(got.labels(), expected.labels()) << sourceName << " -> " << outputName << " samples " << samples;
        std::filesystem::remove(outputPath);
      }
    }
  }
  // The raw copy of the compressed source was never visible in the directory.
  EXPECT_EQ(test::listFiles(dir), "source.nii\nsource.nii.gz\n");
}

TEST(OutOfCore, FailuresLeaveNoOutput) {
  const std::string dir = test::tempDir();
  const LabelGrid grid = figure();
  EXPECT_THROW(openSource(dir + "/missing.nii.gz", 1000, dir), InputError);
  writeGrid(dir + "/source.nii.gz", grid);
  OutOfCoreSource source = openSource(dir + "/source.nii.gz", 1000, dir);
  const TetMesh tm = tetrahedralizeVoxels(source.downsampled(), {.includeBackground = false});
  auto bad = tm.positions;
  bad[0].x() = std::nan("");
  EXPECT_THROW(writeOutOfCore(source, tm, bad, dir + "/posed.nii.gz"), InputError);
  EXPECT_ANY_THROW(writeOutOfCore(source, tm, tm.positions, dir + "/no/such/dir/posed.nii.gz"));
  EXPECT_EQ(test::listFiles(dir), "source.nii.gz\n");
}

}  // namespace
}  // namespace vox
