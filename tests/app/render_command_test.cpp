// voxmorph render end to end: images on the GPU and the CPU, options, and
// bad input (one-line error naming the fault, exit code 1 or 2 for usage
// errors, no output file).

#include "geometry/io/grid_io.h"
#include "geometry/io/png_io.h"
#include "geometry/rgb_image.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace vox {
namespace {

const Rgb kBackground{22, 24, 29};

std::string voxmorph(const std::string& args) { return test::quote(test::voxmorphBinary()) + " " + args; }

std::string stickGrid(const std::string& dir) {
  const std::string grid = dir + "/stick.mha";
  const auto r = test::runCommand(voxmorph("synth stick --size 48 -o " + test::quote(grid) + " --organs " + test::quote(dir + "/stick.dat")));
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return grid;
}

TEST(RenderCommand, RendersOnTheGpuAndAgreesWithTheCpu) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = stickGrid(dir);
  auto r = test::runCommand(voxmorph("render " + test::quote(grid) + " -o " + test::quote(dir + "/gpu.png") +
                                     " --size 96x72 --camera azimuth=30,elevation=20 --verify"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("verify: "), std::string::npos) << r.err;
  r = test::runCommand(voxmorph("render " + test::quote(grid) + " -o " + test::quote(dir + "/cpu.png") +
                                " --size 96x72 --camera azimuth=30,elevation=20 --cpu -q"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const RgbImage gpu = readPng(dir + "/gpu.png"), cpu = readPng(dir + "/cpu.png");
  EXPECT_EQ(gpu.width, 96);
  EXPECT_EQ(gpu.height, 72);
  EXPECT_LE(compareImages(gpu, cpu, 5).differing, 7u);  // 0.1% of 6912
  EXPECT_GT(countNotBackground(gpu, kBackground), 300u);
}

TEST(RenderCommand, CutsAndHiddenOrgansChangeTheImage) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = stickGrid(dir);
  const std::string base = "render " + test::quote(grid) + " --size 64x48 -q --organs " + test::quote(dir + "/stick.dat");
  ASSERT_EQ(test::runCommand(voxmorph(base + " -o " + test::quote(dir + "/all.png"))).exitCode, 0);
  auto r = test::runCommand(voxmorph(base + " -o " + test::quote(dir + "/cut.png") + " --cut " + test::quote("y<25") + " --cut plane=0,0,1,150"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  r = test::runCommand(voxmorph(base + " -o " + test::quote(dir + "/hidden.png") + " --hide trunk,head,muscle,heart"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const RgbImage all = readPng(dir + "/all.png");
  EXPECT_GT(compareImages(all, readPng(dir + "/cut.png"), 0).differing, 50u);
  // Only the humeri are left.
  EXPECT_LT(countNotBackground(readPng(dir + "/hidden.png"), kBackground), countNotBackground(all, kBackground) / 4);
  EXPECT_GT(countNotBackground(readPng(dir + "/hidden.png"), kBackground), 0u);
  // Hiding every label would draw an empty image: a usage error, no file.
  r = test::runCommand(voxmorph(base + " -o " + test::quote(dir + "/none.png") + " --hide trunk,head,muscle,heart,humerus"));
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/none.png"));
}

TEST(RenderCommand, BadInputIsAOneLineErrorAndNoOutput) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = stickGrid(dir);
  const std::string out = " -o " + test::quote(dir + "/out.png");
  struct Case {
    std::string args;
    std::string message;
    int exitCode = 1;  // 2: a usage error
  };
  const std::vector<Case> cases = {
      {"render " + test::quote(dir + "/absent.mha") + out, "absent.mha"},
      {"render " + test::quote(grid) + out + " --camera zoom=2", "--camera: unknown key 'zoom'", 2},
      {"render " + test::quote(grid) + out + " --size 64", "--size: ", 2},
      {"render " + test::quote(grid) + out + " --size 0x0", "--size: ", 2},
      {"render " + test::quote(grid) + " -o " + test::quote(dir + "/out.jpg"), "use .png", 2},
      {"render " + test::quote(grid) + out + " --hide 1-9", "hides every label", 2},
      {"render " + test::quote(grid) + out + " --cut " + test::quote("w>3"), "--cut: ", 2},
      {"render " + test::quote(grid) + out + " --hide 1-999", "--hide: ", 2},
      {"render " + test::quote(grid) + out + " --organs " + test::quote(dir + "/absent.dat"), "absent.dat"},
      {"render " + test::quote(grid) + " -o " + test::quote(dir + "/no/such/dir/out.png"), "out.png"},
  };
  for (const Case& c : cases) {
    const auto r = test::runCommand(voxmorph(c.args));
    EXPECT_EQ(r.exitCode, c.exitCode) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.find("voxmorph: error: "), r.err.rfind("voxmorph: error: ")) << "one error line: " << r.err;
  }
  EXPECT_EQ(test::runCommand(voxmorph("render " + test::quote(grid))).exitCode, 2);  // -o missing: usage
  EXPECT_EQ(test::listFiles(dir), "stick.dat\nstick.mha\n");
}

TEST(RenderCommand, AGridWithoutForegroundIsRefused) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  GridGeometry g;
  g.dims = {8, 9, 10};
  writeGrid(dir + "/empty.mha", LabelGrid(g, 0));
  const auto r = test::runCommand(voxmorph("render " + test::quote(dir + "/empty.mha") + " -o " + test::quote(dir + "/e.png")));
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("empty.mha: has no foreground voxels"), std::string::npos) << r.err;
  EXPECT_EQ(test::listFiles(dir), "empty.mha\n");
}

// --articulated: the joint pose on the transfer mesh that resolves the
// skeleton, ray-cast without rasterizing. The skeleton figure's elbow bent
// 90 degrees shows the silhouette of the grid `deform --articulated` writes
// (4 pixels of 4,147 differ on the figure: grazing rays); the first of its
// steps shows the forearm hardly turned; a step beyond the pose's and
// options without their pose are refused with one line, no image.
TEST(RenderCommand, ArticulatedPoseShowsTheDeformedGridAndItsSteps) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = dir + "/skeleton.nii.gz", organs = dir + "/skeleton.dat", pose = dir + "/elbow.json";
  auto r = test::runCommand(voxmorph("synth skeleton --size 96 -o " + test::quote(grid) + " --organs " + test::quote(organs)));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  std::ofstream(pose) << R"({"joints": {"right_elbow": {"flexion": 90}}})";
  r = test::runCommand(voxmorph("deform " + test::quote(grid) + " --organs " + test::quote(organs) + " --pose " + test::quote(pose) +
                                " --articulated --cpu -q -o " + test::quote(dir + "/posed.nii.gz")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const std::string view = " --cpu --size 160x200 --camera eye=57,-500,96,target=57,28,96,up=0,0,1,fov=30 --organs " + test::quote(organs);
  ASSERT_EQ(test::runCommand(voxmorph("render " + test::quote(dir + "/posed.nii.gz") + view + " -q -o " + test::quote(dir + "/grid.png"))).exitCode, 0);
  const std::string articulated = "render " + test::quote(grid) + view + " --pose " + test::quote(pose) + " --articulated";
  r = test::runCommand(voxmorph(articulated + " -o " + test::quote(dir + "/mesh.png")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("articulated: step 17 of 17, 0 tets inverted"), std::string::npos) << r.err;
  r = test::runCommand(voxmorph(articulated + " --step 1 -q -o " + test::quote(dir + "/step1.png")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const RgbImage posed = readPng(dir + "/grid.png"), mesh = readPng(dir + "/mesh.png"), first = readPng(dir + "/step1.png");
  const auto silhouetteDiffers = [](const RgbImage& a, const RgbImage& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) n += (a.pixels[i] == kBackground) != (b.pixels[i] == kBackground);
    return n;
  };
  const std::size_t body = countNotBackground(posed, kBackground);
  EXPECT_GT(body, 3000u);
  EXPECT_LE(silhouetteDiffers(posed, mesh), body / 100);
  EXPECT_GT(silhouetteDiffers(first, mesh), 100u);

  const std::string out = " -o " + test::quote(dir + "/bad.png");
  const std::string selections = dir + "/selections.json";
  std::ofstream(selections) << R"({"selections": [{"name": "a", "box": {"min": [0, 0, 0], "max": [50, 50, 50]}, "fixed": true}]})";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {articulated + " --step 18" + out, "--step: 18 is beyond the pose's 17 steps"},
      {"render " + test::quote(grid) + view + " --articulated" + out, "--articulated: needs a --pose"},
      {"render " + test::quote(grid) + view + " --step 2" + out, "--step"},
      {"render " + test::quote(grid) + view + " --pose " + test::quote(selections) + " --articulated" + out, "poses joints"},
  };
  for (const auto& [args, message] : cases) {
    r = test::runCommand(voxmorph(args));
    EXPECT_NE(r.exitCode, 0) << args;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << "\n" << r.err;
    EXPECT_EQ(r.err.find("voxmorph: error: "), r.err.rfind("voxmorph: error: ")) << "one error line: " << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad.png"));
}

}  // namespace
}  // namespace vox
