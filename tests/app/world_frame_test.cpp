// The world frame (geometry/world_frame.h): a grid stored rotated and in LPS
// (and one stored mirrored) is meshed, and nibabel + meshio find the mesh's
// labelled volume over the image's labelled voxels; info prints the
// orientation nibabel gives.

#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace vox {
namespace {

std::string script() { return test::assetPath("../tests/app/world_frame_overlap.py"); }

double overlap(const std::string& dir, const std::string& variant) {
  const std::string grid = dir + "/" + variant + ".nii.gz", mesh = dir + "/" + variant + ".vtu";
  auto r = test::runCommand(test::quote(test::python()) + " " + test::quote(script()) + " make " + test::quote(grid) + " " + variant);
  EXPECT_EQ(r.exitCode, 0) << r.err;
  r = test::runCommand(test::quote(test::voxmorphBinary()) + " mesh " + test::quote(grid) + " -l 2 --iterations 3 --no-distance -q -o " +
                       test::quote(mesh));
  EXPECT_EQ(r.exitCode, 0) << r.err;
  r = test::runCommand(test::quote(test::voxmorphBinary()) + " info " + test::quote(mesh));
  EXPECT_NE(r.out.find("inverted        0 tets"), std::string::npos) << r.out;
  r = test::runCommand(test::quote(test::python()) + " " + test::quote(script()) + " overlap " + test::quote(grid) + " " + test::quote(mesh));
  EXPECT_EQ(r.exitCode, 0) << r.err;
  double fraction = -1;
  EXPECT_EQ(std::sscanf(r.out.c_str(), "overlap %lf", &fraction), 1) << r.out;
  std::printf("%s: %s", variant.c_str(), r.out.c_str());
  return fraction;
}

TEST(WorldFrame, RotatedLpsGridMeshLiesOverTheImageInNibabelAndMeshio) {
  VOX_REQUIRE_VOXMORPH();
  if (test::python().empty()) GTEST_SKIP() << "python3 with nibabel and meshio not found";
  const std::string dir = test::tempDir();
  EXPECT_GE(overlap(dir, "lps"), 0.95);
  EXPECT_GE(overlap(dir, "mirrored"), 0.95);
  const auto r = test::runCommand(test::quote(test::voxmorphBinary()) + " info --cpu " + test::quote(dir + "/lps.nii.gz"));
  EXPECT_NE(r.out.find("orientation LPS"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("origin      40 -25 60 mm (world, RAS"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace vox
