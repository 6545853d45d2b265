// Provenance (provenance.h): digests of the inputs against coreutils'
// sha256sum, a detached grid's data file listed beside its header (every
// grid format), empty
// paths skipped, a missing file named, shell quoting that round-trips
// through /bin/sh, and the JSON object's fields.

#include "geometry/error.h"
#include "geometry/io/grid_files.h"
#include "geometry/io/grid_io.h"
#include "geometry/provenance.h"
#include "geometry/io/input_provenance.h"
#include "geometry/synth.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace vox {
namespace {

std::string sha256sum(const std::string& path) {
  const auto r = test::runCommand("sha256sum " + test::quote(path));
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return r.out.substr(0, 64);
}

TEST(Provenance, DigestsOfTheInputsAndADetachedGridsDataFile) {
  const std::string dir = test::tempDir();
  writeGrid(dir + "/g.mhd", synthesize(SynthKind::StickFigure, 24));
  const std::string pose = dir + "/pose.json";
  std::ofstream(pose) << R"({"selections": []})";
  const Provenance p = makeProvenance("voxmorph deform g.mhd", {{"grid", dir + "/g.mhd"}, {"organs", ""}, {"pose", pose}});
  ASSERT_EQ(p.inputs.size(), 3u);
  EXPECT_EQ(p.inputs[0].role, "grid");
  EXPECT_EQ(p.inputs[0].sha256, sha256sum(dir + "/g.mhd"));
  EXPECT_EQ(p.inputs[1].role, "grid data");
  EXPECT_EQ(p.inputs[1].path, dir + "/g.raw");
  EXPECT_EQ(p.inputs[1].sha256, sha256sum(dir + "/g.raw"));
  EXPECT_GT(p.inputs[1].bytes, 0u);
  EXPECT_EQ(p.inputs[2].role, "pose");
  EXPECT_EQ(p.inputs[2].sha256, sha256sum(pose));
  EXPECT_EQ(p.inputs[2].bytes, 18u);
  EXPECT_EQ(p.commandLine, "voxmorph deform g.mhd");
  EXPECT_FALSE(p.workingDirectory.empty());
  EXPECT_EQ(p.version, voxmorphVersion());

  const nlohmann::json j = nlohmann::json::parse(provenanceJson(p));
  EXPECT_EQ(j["voxmorph_version"], voxmorphVersion());
  EXPECT_EQ(j["command_line"], "voxmorph deform g.mhd");
  ASSERT_EQ(j["inputs"].size(), 3u);
  EXPECT_EQ(j["inputs"][2]["sha256"], p.inputs[2].sha256);
  if (voxmorphGitDescribe().empty())
    EXPECT_TRUE(j["git_describe"].is_null());
  else
    EXPECT_EQ(j["git_describe"], voxmorphGitDescribe());
}

TEST(Provenance, GridFilesListDetachedDataFiles) {
  const std::string dir = test::tempDir();
  const LabelGrid grid = synthesize(SynthKind::StickFigure, 16);
  for (const char* name : {"/g.nii.gz", "/g.mha", "/g.mhd", "/g.nrrd", "/g.nhdr", "/g.inr"}) writeGrid(dir + name, grid);
  EXPECT_EQ(gridFiles(dir + "/g.nii.gz"), std::vector<std::string>{dir + "/g.nii.gz"});
  EXPECT_EQ(gridFiles(dir + "/g.mha"), std::vector<std::string>{dir + "/g.mha"});
  EXPECT_EQ(gridFiles(dir + "/g.mhd"), (std::vector<std::string>{dir + "/g.mhd", dir + "/g.raw"}));
  EXPECT_EQ(gridFiles(dir + "/g.nrrd"), std::vector<std::string>{dir + "/g.nrrd"});
  EXPECT_EQ(gridFiles(dir + "/g.nhdr"), (std::vector<std::string>{dir + "/g.nhdr", dir + "/g.raw.gz"}));
  EXPECT_EQ(gridFiles(dir + "/g.inr"), std::vector<std::string>{dir + "/g.inr"});
  EXPECT_THROW(gridFiles(dir + "/absent.mhd"), InputError);
}

TEST(Provenance, MissingInputIsNamed) {
  const std::string missing = test::tempDir() + "/absent.json";
  try {
    makeProvenance("x", {{"pose", missing}});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
}

TEST(Provenance, CommandLineQuotingRoundTripsThroughTheShell) {
  const char* argv[] = {"voxmorph", "deform", "my grid.nii.gz", "--pose", "it's.json", "--separate", "a:b@1,2,3,4,5,6", "$HOME", ""};
  const std::string line = shellCommandLine(9, argv);
  EXPECT_EQ(line.rfind("voxmorph deform 'my grid.nii.gz' --pose 'it'\\''s.json' --separate a:b@1,2,3,4,5,6 '$HOME' ''", 0), 0u) << line;
  // printf '%s\n' with the quoted words prints the original arguments.
  const auto r = test::runCommand("printf '%s\\n' " + line.substr(std::string("voxmorph ").size()));
  EXPECT_EQ(r.out, "deform\nmy grid.nii.gz\n--pose\nit's.json\n--separate\na:b@1,2,3,4,5,6\n$HOME\n\n");
  EXPECT_NE(voxmorphVersionLine().find("voxmorph " + voxmorphVersion()), std::string::npos);
}

}  // namespace
}  // namespace vox
