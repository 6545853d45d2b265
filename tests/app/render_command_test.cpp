// voxmorph render end to end: images on the GPU and the CPU, options, and
// bad input (one-line error naming the fault, exit code 1 or 2 for usage
// errors, no output file).

#include "geometry/io/grid_io.h"
#include "geometry/io/png_io.h"
#include "geometry/rgb_image.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <filesystem>

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

}  // namespace
}  // namespace vox
