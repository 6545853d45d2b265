// The ICRP 110 reference phantoms (NIfTI, gzip): dims, spacing and label
// statistics as nibabel reports them, and the phantom through every format.

#include "geometry/io/grid_io.h"
#include "geometry/label_stats.h"
#include "tests/geometry/io/grid_test_grids.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <set>

namespace vox {
namespace {

struct PhantomFacts {
  const char* file;
  Index3 dims;
  Eigen::Vector3d spacing;
  std::size_t distinctLabels;  // background included
  std::uint64_t foreground;
  std::uint64_t checksum;     // labelChecksum, computed with nibabel
  std::uint64_t label141;
};

// Numbers from nibabel 5.0 on the same files.
const PhantomFacts kMale{"icrp110_am.nii.gz", {254, 127, 222}, {2.137, 2.137, 8.0}, 139, 1950255, 6319237389351ull, 3880};
const PhantomFacts kFemale{"icrp110_af.nii.gz", {299, 137, 348}, {1.775, 1.775, 4.84}, 138, 3887730, 13027206432515ull, 1710};

void checkPhantom(const PhantomFacts& facts) {
  const LabelGrid grid = readGrid(test::assetPath(facts.file));
  EXPECT_EQ(grid.dims(), facts.dims);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(grid.spacing()[a], facts.spacing[a], 1e-5);
  EXPECT_EQ(grid.origin(), Eigen::Vector3d::Zero());
  EXPECT_EQ(grid.geometry().direction, Eigen::Matrix3d::Identity());
  const std::set<Label> distinct(grid.labels().begin(), grid.labels().end());
  EXPECT_EQ(distinct.size(), facts.distinctLabels);
  EXPECT_EQ(grid.maxLabel(), 141);
  const LabelStats stats = computeLabelStats(grid);
  EXPECT_EQ(stats.foregroundVoxels(), facts.foreground);
  EXPECT_EQ(stats.counts[141], facts.label141);
  EXPECT_EQ(test::labelChecksum(grid), facts.checksum);
}

TEST(IcrpPhantom, AdultMale) { checkPhantom(kMale); }
TEST(IcrpPhantom, AdultFemale) { checkPhantom(kFemale); }

TEST(IcrpPhantom, MaleThroughEveryFormat) {
  const LabelGrid grid = readGrid(test::assetPath(kMale.file));
  const std::string dir = test::tempDir();
  for (const char* ext : {".nii", ".nii.gz", ".mha", ".mhd", ".nrrd", ".nhdr", ".inr", ".inr.gz"}) {
    SCOPED_TRACE(ext);
    const std::string path = dir + "/am" + ext;
    writeGrid(path, grid);
    const LabelGrid back = readGrid(path);
    test::expectSameGeometry(grid.geometry(), back.geometry(), 1e-12);
    test::expectSameLabels(grid, back);
  }
}

}  // namespace
}  // namespace vox
