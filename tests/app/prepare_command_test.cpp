// voxmorph prepare, and deform and render --prepared, end to end on the
// synthetic skeleton figure: a prepared state gives byte-identical posed
// grids and images for a joint pose and a box pose with separations; a
// stale state (another grid, another organ table, a pose with other
// separations, other cage options) and a corrupted or truncated file are
// refused with one line naming the file and what differs, exit 1, nothing
// written.

#include "tests/support/test_environment.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace vox {
namespace {

std::string voxmorph(const std::string& args) { return test::quote(test::voxmorphBinary()) + " " + args; }

struct Prepared {
  std::string dir, grid, organs, joint, arm, state;
};

std::string writeFile(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

// The skeleton figure (56 x 28 x 96 voxels of 2 mm) prepared for its right
// shoulder turned (a joint pose) and for the box pose below, which raises the
// right arm and separates it from the trunk.
const Prepared& prepared() {
  static const Prepared p = [] {
    Prepared s;
    s.dir = test::tempDir();
    s.grid = s.dir + "/figure.mha";
    s.organs = s.dir + "/figure.dat";
    auto r = test::runCommand(voxmorph("synth skeleton --size 96 -o " + test::quote(s.grid) + " --organs " + test::quote(s.organs)));
    EXPECT_EQ(r.exitCode, 0) << r.err;
    s.joint = writeFile(s.dir + "/joint.json", R"({"joints": {"right_shoulder": {"abduction": 30}, "right_elbow": {"flexion": 40}}})");
    s.arm = writeFile(s.dir + "/arm.json", R"({
      "selections": [
        {"name": "body", "box": {"min": [-1000, -1000, -1000], "max": [1000, 1000, 1000]}, "fixed": true},
        {"name": "right arm", "box": {"min": [-1000, -1000, 80], "max": [20, 1000, 160]}, "group": "right_arm",
         "transform": {"rotation": {"axis": [0, 1, 0], "angle_deg": 20, "center": [28, 28, 150]}}}
      ],
      "separations": [{"groups": ["right_arm", "trunk"]}]
    })");
    s.state = s.dir + "/figure.vxprep";
    r = test::runCommand(voxmorph("prepare " + test::quote(s.grid) + " --organs " + test::quote(s.organs) + " --pose " + test::quote(s.joint) +
                                  " --pose " + test::quote(s.arm) + " -o " + test::quote(s.state)));
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("prepared state of"), std::string::npos) << r.out;
    return s;
  }();
  return p;
}

std::string deformLine(const Prepared& p, const std::string& pose, const std::string& out, const std::string& extra = "") {
  return voxmorph("deform " + test::quote(p.grid) + " --organs " + test::quote(p.organs) + " --pose " + test::quote(pose) + " -o " +
                  test::quote(out) + " --cpu --force -q " + extra);
}

void expectOneLineError(const test::CommandResult& r, const std::string& fault) {
  EXPECT_EQ(r.exitCode, 1) << r.err;
  EXPECT_NE(r.err.find(fault), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
}

TEST(PrepareCommand, DeformWithThePreparedStateWritesTheSameBytes) {
  VOX_REQUIRE_VOXMORPH();
  const Prepared& p = prepared();
  for (const std::string& pose : {p.joint, p.arm}) {
    const std::string name = std::filesystem::path(pose).stem().string();
    const std::string without = p.dir + "/" + name + "_without.nii.gz", with = p.dir + "/" + name + "_with.nii.gz";
    const std::string report = p.dir + "/" + name + "_report.json";
    auto r = test::runCommand(deformLine(p, pose, without, "--preserve-volumes"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    r = test::runCommand(deformLine(p, pose, with, "--preserve-volumes --prepared " + test::quote(p.state) + " --report " + test::quote(report)));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string a = test::readText(without), b = test::readText(with);
    EXPECT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << name << ": the posed grids differ";
    // The report names the load and the prepared file among the inputs.
    const nlohmann::json j = nlohmann::json::parse(std::ifstream(report));
    bool loaded = false;
    for (const auto& s : j["stages"]) loaded = loaded || s["stage"] == "prepared state";
    EXPECT_TRUE(loaded);
    bool input = false;
    for (const auto& in : j["provenance"]["inputs"]) input = input || in["role"] == "prepared";
    EXPECT_TRUE(input);
  }
}

TEST(PrepareCommand, RenderWithThePreparedStateDrawsTheSameImage) {
  VOX_REQUIRE_VOXMORPH();
  const Prepared& p = prepared();
  const std::string without = p.dir + "/render_without.png", with = p.dir + "/render_with.png";
  const std::string line = voxmorph("render " + test::quote(p.grid) + " --organs " + test::quote(p.organs) + " --pose " + test::quote(p.joint) +
                                    " --size 120x160 --cpu -q -o ");
  ASSERT_EQ(test::runCommand(line + test::quote(without)).exitCode, 0);
  const auto r = test::runCommand(line + test::quote(with) + " --prepared " + test::quote(p.state));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(test::readText(without) == test::readText(with));
}

TEST(PrepareCommand, AStaleStateIsRefusedNamingWhatDiffers) {
  VOX_REQUIRE_VOXMORPH();
  const Prepared& p = prepared();
  const std::string out = p.dir + "/stale.nii.gz";
  const std::string state = " --prepared " + test::quote(p.state);
  // A pose whose separations were not prepared (the left knee's).
  const std::string knee = writeFile(p.dir + "/knee.json", R"({"joints": {"left_knee": {"flexion": 30}}})");
  expectOneLineError(test::runCommand(deformLine(p, knee, out, state)), p.state + ": prepared for other separations");
  // Other cage options.
  expectOneLineError(test::runCommand(deformLine(p, p.arm, out, state + " --dilation 24")), "prepared with other cage options");
  // Another grid: the figure one voxel larger.
  const std::string other = p.dir + "/other.mha";
  ASSERT_EQ(test::runCommand(voxmorph("synth skeleton --size 97 -o " + test::quote(other))).exitCode, 0);
  expectOneLineError(test::runCommand(voxmorph("deform " + test::quote(other) + " --organs " + test::quote(p.organs) + " --pose " +
                                               test::quote(p.joint) + " -o " + test::quote(out) + " --cpu -q" + state)),
                     p.state + ": prepared from another grid (" + p.grid);
  // Another organ table; none.
  const std::string organs = writeFile(p.dir + "/other.dat", test::readText(p.organs) + "\n200 Extra organ 1 1.0\n");
  expectOneLineError(test::runCommand(voxmorph("deform " + test::quote(p.grid) + " --organs " + test::quote(organs) + " --pose " +
                                               test::quote(p.arm) + " -o " + test::quote(out) + " --cpu -q" + state)),
                     "prepared from another organ table");
  const std::string still = writeFile(p.dir + "/still.json", R"({"selections": [{"box": {"min": [-1000, -1000, -1000], "max": [1000, 1000, 1000]}, "fixed": true}]})");
  expectOneLineError(test::runCommand(voxmorph("deform " + test::quote(p.grid) + " --pose " + test::quote(still) + " -o " + test::quote(out) +
                                               " --cpu -q" + state)),
                     "this run has none");
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(PrepareCommand, ACorruptedOrTruncatedStateIsRefused) {
  VOX_REQUIRE_VOXMORPH();
  const Prepared& p = prepared();
  const std::string bytes = test::readText(p.state);
  ASSERT_GT(bytes.size(), 1000u);
  const std::string corrupted = p.dir + "/corrupted.vxprep", truncated = p.dir + "/truncated.vxprep", foreign = p.dir + "/foreign.vxprep";
  std::string flipped = bytes;
  flipped[bytes.size() / 2] = char(flipped[bytes.size() / 2] ^ 1);
  test::writeText(corrupted, flipped);
  test::writeText(truncated, bytes.substr(0, bytes.size() * 2 / 3));
  test::writeText(foreign, test::readText(p.organs));
  const std::string out = p.dir + "/refused.nii.gz";
  expectOneLineError(test::runCommand(deformLine(p, p.joint, out, "--prepared " + test::quote(corrupted))), corrupted + ": corrupted");
  expectOneLineError(test::runCommand(deformLine(p, p.joint, out, "--prepared " + test::quote(truncated))), truncated + ": truncated");
  expectOneLineError(test::runCommand(deformLine(p, p.joint, out, "--prepared " + test::quote(foreign))),
                     foreign + ": not a voxmorph prepared state");
  expectOneLineError(test::runCommand(deformLine(p, p.joint, out, "--prepared " + test::quote(p.dir + "/missing.vxprep"))), "cannot open");
  EXPECT_FALSE(std::filesystem::exists(out));
  // prepare's own output: a .vxprep, else a usage error.
  const auto r = test::runCommand(voxmorph("prepare " + test::quote(p.grid) + " -o " + test::quote(p.dir + "/state.bin")));
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find(".vxprep"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace vox
