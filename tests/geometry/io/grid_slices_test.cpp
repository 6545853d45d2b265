// Streaming by z-slices (GridSliceReader / GridSliceWriter): what the
// out-of-core rasterizer relies on.

#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/label_stats.h"
#include "tests/geometry/io/grid_test_grids.h"
#include "tests/support/test_environment.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace vox {
namespace {

using ::testing::HasSubstr;

const char* const kStreamedFormats[] = {".nii", ".nii.gz", ".mha", ".mhd", ".nrrd", ".inr", ".inr.gz"};

// info --max-memory: statistics streamed through a buffer of a few slices
// (or less than one) equal those of the grid held whole.
TEST(GridSlices, StreamedLabelStatisticsEqualTheHeldGrid) {
  const std::string path = test::tempDir() + "/stats.nii.gz";
  const LabelGrid grid = test::makeTestGrid(40000, true);
  writeGrid(path, grid);
  const LabelStats held = computeLabelStats(grid);
  const std::int64_t sliceBytes = grid.geometry().sliceVoxels() * std::int64_t(sizeof(Label));
  for (const std::int64_t buffer : {std::int64_t(1), 3 * sliceBytes, std::int64_t(1) << 30}) {
    auto reader = openGridSlices(path);
    EXPECT_EQ(computeLabelStats(*reader, buffer), held) << buffer;
  }
}

TEST(GridSlices, WrittenInChunksReadInAnyOrder) {
  const std::string dir = test::tempDir();
  const LabelGrid grid = test::makeTestGrid(40000, true);
  const std::int64_t nz = grid.dims()[2];
  const std::int64_t sliceVoxels = grid.geometry().sliceVoxels();
  for (const char* ext : kStreamedFormats) {
    SCOPED_TRACE(ext);
    const std::string path = dir + "/streamed" + ext;
    {
      auto writer = createGridSlices(path, grid.geometry(), grid.maxLabel());
      // Chunks of 1, 2, 3, ... slices.
      for (std::int64_t k = 0, n = 1; k < nz; k += n, ++n)
        writer->writeSlices(grid.data() + k * sliceVoxels, std::min(n, nz - k));
      writer->commit();
    }
    auto reader = openGridSlices(path);
    test::expectSameGeometry(grid.geometry(), reader->geometry(), ext[1] == 'n' && ext[2] == 'i' ? 2e-6 : 1e-12);
    // Backwards first (compressed streams restart), then forwards in pairs.
    std::vector<Label> slice(static_cast<std::size_t>(sliceVoxels));
    for (std::int64_t k = nz - 1; k >= 0; k -= 4) {
      reader->readSlices(k, 1, slice.data());
      ASSERT_TRUE(std::equal(slice.begin(), slice.end(), grid.data() + k * sliceVoxels)) << "slice " << k;
    }
    std::vector<Label> all(std::size_t(grid.voxelCount()));
    for (std::int64_t k = 0; k < nz; k += 2) reader->readSlices(k, std::min<std::int64_t>(2, nz - k), all.data() + k * sliceVoxels);
    EXPECT_TRUE(all == grid.labels());
  }
}

TEST(GridSlices, WriterWithoutCommitLeavesNothing) {
  const std::string dir = test::tempDir();
  const LabelGrid grid = test::makeTestGrid(300);
  for (const char* ext : kStreamedFormats) {
    auto writer = createGridSlices(dir + "/abandoned" + ext, grid.geometry(), grid.maxLabel());
    writer->writeSlices(grid.data(), 2);
  }
  EXPECT_EQ(test::listFiles(dir), "");
}

TEST(GridSlices, CommitNeedsEverySlice) {
  const std::string dir = test::tempDir();
  const LabelGrid grid = test::makeTestGrid(12);
  for (const char* ext : kStreamedFormats) {
    auto writer = createGridSlices(dir + "/partial" + ext, grid.geometry(), grid.maxLabel());
    writer->writeSlices(grid.data(), grid.dims()[2] - 1);
    try {
      writer->commit();
      ADD_FAILURE() << ext << ": commit succeeded";
    } catch (const RuntimeFailure& e) {
      EXPECT_THAT(e.what(), HasSubstr("only 10 of 11 slices were written"));
    }
  }
  EXPECT_EQ(test::listFiles(dir), "");
}

TEST(GridSlices, WriterRejectsExtraSlicesAndLabelsAboveTheDeclaredMaximum) {
  const std::string dir = test::tempDir();
  const LabelGrid grid = test::makeTestGrid(300);
  auto writer = createGridSlices(dir + "/a.nii.gz", grid.geometry(), 255);  // stores uint8
  EXPECT_THROW(writer->writeSlices(grid.data(), 1), RuntimeFailure);         // label 300 in slice 0
  auto second = createGridSlices(dir + "/b.mhd", grid.geometry(), grid.maxLabel());
  second->writeSlices(grid.data(), grid.dims()[2]);
  EXPECT_THROW(second->writeSlices(grid.data(), 1), RuntimeFailure);
}

TEST(GridSlices, ReaderRejectsSlicesOutsideTheGrid) {
  const std::string path = test::tempDir() + "/g.nii";
  writeGrid(path, test::makeTestGrid(5));
  auto reader = openGridSlices(path);
  std::vector<Label> buffer(std::size_t(reader->geometry().voxelCount()));
  EXPECT_THROW(reader->readSlices(10, 2, buffer.data()), RuntimeFailure);
  EXPECT_THROW(reader->readSlices(-1, 1, buffer.data()), RuntimeFailure);
}

TEST(GridSlices, PhantomStreamedEqualsReadWhole) {
  const std::string path = test::assetPath("icrp110_am.nii.gz");
  const LabelGrid whole = readGrid(path);
  auto reader = openGridSlices(path);
  const std::int64_t sliceVoxels = whole.geometry().sliceVoxels();
  std::vector<Label> chunk;
  for (std::int64_t k = 0; k < whole.dims()[2]; k += 16) {
    const std::int64_t n = std::min<std::int64_t>(16, whole.dims()[2] - k);
    chunk.resize(std::size_t(n * sliceVoxels));
    reader->readSlices(k, n, chunk.data());
    ASSERT_TRUE(std::equal(chunk.begin(), chunk.end(), whole.data() + k * sliceVoxels)) << "slices from " << k;
  }
}

}  // namespace
}  // namespace vox
