// The grid formats through the `voxmorph` CLI: one-line errors with exit
// code 1 for corrupt input, no output or temporary left by a failed write,
// and files a real client (nibabel) reads.

#include "tests/geometry/io/grid_test_grids.h"
#include "tests/support/test_environment.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

namespace vox {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::StartsWith;

test::CommandResult voxmorph(const std::string& args) { return test::runCommand(test::quote(test::voxmorphBinary()) + " " + args); }

void expectOneErrorLine(const test::CommandResult& r, const std::string& mention) {
  EXPECT_EQ(r.exitCode, 1) << r.out << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_THAT(r.err, StartsWith("voxmorph: error:"));
  EXPECT_THAT(r.err, HasSubstr(mention));
}

TEST(GridCli, InfoOnCorruptFilesPrintsOneErrorLine) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  // Each a different reader and fault.
  test::NiftiFields badMagic;
  std::memcpy(badMagic.magic, "abc", 4);
  test::writeBytes(dir + "/magic.nii", test::niftiHeader(badMagic) + std::string(24, '\1'));
  test::writeBytes(dir + "/short.mha", "NDims = 3\nDimSize = 400 400 400\nElementType = MET_UCHAR\nElementDataFile = LOCAL\nxx");
  test::writeBytes(dir + "/dims.nrrd", "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 99999 99999 99999\nencoding: raw\n\n");
  const std::string cut = dir + "/cut.nii.gz";
  ASSERT_EQ(voxmorph("synth spheres --size 24 -o " + test::quote(cut)).exitCode, 0);
  std::string bytes = test::readBytes(cut);
  bytes.resize(bytes.size() / 2);
  test::writeBytes(cut, bytes);

  const std::pair<const char*, const char*> cases[] = {
      {"magic.nii", "bad magic"}, {"short.mha", "voxel data is truncated"}, {"dims.nrrd", "exceed the largest supported grid"},
      {"cut.nii.gz", "truncated"}, {"missing.nii.gz", "No such file or directory"}};
  for (const auto& [name, fault] : cases) {
    SCOPED_TRACE(name);
    const test::CommandResult r = voxmorph("info --cpu " + test::quote(dir + "/" + name));
    expectOneErrorLine(r, fault);
    EXPECT_THAT(r.err, HasSubstr(dir + "/" + name));
  }
}

TEST(GridCli, SynthWritesNiftiThatNibabelReads) {
  VOX_REQUIRE_VOXMORPH();
  if (test::python().empty()) GTEST_SKIP() << "python3 with nibabel is not installed";
  const std::string dir = test::tempDir();
  const std::string path = dir + "/x.nii.gz";
  const test::CommandResult synth = voxmorph("synth spheres --size 32 -o " + test::quote(path));
  ASSERT_EQ(synth.exitCode, 0) << synth.err;
  const test::CommandResult r = test::runCommand(
      test::quote(test::python()) + " -c " +
      test::quote("import sys, nibabel as nib, numpy as np\n"
                  "img = nib.load(sys.argv[1]); d = np.asanyarray(img.dataobj)\n"
                  "print(d.dtype, *d.shape, *sorted(np.unique(d).tolist()))\n") +
      " " + test::quote(path));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.out, "uint8 32 32 32 0 1 2 3\n");
  EXPECT_EQ(test::listFiles(dir), "x.nii.gz\n");
}

TEST(GridCli, WriteIntoMissingDirectoryFailsAndLeavesNothing) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  for (const char* name : {"x.nii.gz", "x.mhd", "x.nrrd", "x.inr"}) {
    const std::string target = dir + "/missing/" + name;
    expectOneErrorLine(voxmorph("synth spheres --size 16 -o " + test::quote(target)), dir + "/missing/" + name);
    EXPECT_FALSE(fs::exists(dir + "/missing"));
  }
  EXPECT_EQ(test::listFiles(dir), "");
}

TEST(GridCli, FailingWriterLeavesNoTemporary) {
  VOX_REQUIRE_VOXMORPH();
  // The targets are non-empty directories: every byte is written, then the
  // final rename fails. Nothing else may remain (for .mhd, not the .raw).
  const std::string dir = test::tempDir();
  for (const char* name : {"y.nii.gz", "y.nii", "y.mha", "y.mhd", "y.nrrd", "y.nhdr", "y.inr.gz"}) {
    SCOPED_TRACE(name);
    fs::create_directory(dir + "/" + name);
    test::writeBytes(dir + "/" + name + "/keep", "x");
    const test::CommandResult r = voxmorph("synth spheres --size 16 -o " + test::quote(dir + "/" + name));
    expectOneErrorLine(r, dir + "/" + name);
    EXPECT_EQ(test::listFiles(dir), std::string(name) + "\n");
    EXPECT_EQ(test::listFiles(dir + "/" + name), "keep\n");
    fs::remove_all(dir + "/" + name);
  }
}

}  // namespace
}  // namespace vox
