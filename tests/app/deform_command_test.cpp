// voxmorph deform and voxmorph cage end to end on the synthetic stick figure:
// an identity pose reproduces the grid, a rotated arm writes a posed grid and
// a complete report, and bad input (a pose that selects nothing, an open
// cage, a selection by label group without the organ table, unknown
// formats: exit code 2) is a one-line error with exit code 1 and no output file; a cage
// that leaves foreground outside without limb separation is a warning;
// --preserve-volumes brings every label to its deformed volume.

#include "geometry/io/grid_io.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace vox {
namespace {

std::string voxmorph(const std::string& args) { return test::quote(test::voxmorphBinary()) + " " + args; }

struct Stick {
  std::string dir, grid, organs;
};

Stick stick() {
  Stick s;
  s.dir = test::tempDir();
  s.grid = s.dir + "/stick.mha";
  s.organs = s.dir + "/stick.dat";
  const auto r = test::runCommand(voxmorph("synth stick --size 48 -o " + test::quote(s.grid) + " --organs " + test::quote(s.organs)));
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return s;
}

std::string writeFile(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

const char* kIdentityPose = R"({"selections": [{"box": {"min": [-1000, -1000, -1000], "max": [1000, 1000, 1000]}, "fixed": true}]})";

// The stick figure (28 x 14 x 48 voxels of 2 mm): its right arm (low x)
// swung 30 degrees about the y axis at the shoulder, the rest fixed.
const char* kArmPose = R"({
  "name": "right arm out",
  "selections": [
    {"name": "body", "box": {"min": [-1000, -1000, -1000], "max": [1000, 1000, 1000]}, "fixed": true},
    {"name": "right arm", "box": {"min": [-1000, -1000, 40], "max": [10, 1000, 80]}, "group": "right_arm",
     "transform": {"rotation": {"axis": [0, 1, 0], "angle_deg": 30, "center": [12, 14, 80]}}}
  ],
  "separations": [{"groups": ["right_arm", "trunk"]}]
})";

void expectOneLineError(const test::CommandResult& r, const std::string& fault, int exitCode = 1) {
  EXPECT_EQ(r.exitCode, exitCode) << r.err;
  EXPECT_NE(r.err.find(fault), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
}

TEST(DeformCommand, IdentityPoseReproducesTheGrid) {
  VOX_REQUIRE_VOXMORPH();
  const Stick s = stick();
  const std::string pose = writeFile(s.dir + "/identity.json", kIdentityPose);
  const std::string out = s.dir + "/posed.nii.gz";
  const auto r = test::runCommand(voxmorph("deform " + test::quote(s.grid) + " --pose " + test::quote(pose) + " -o " + test::quote(out) + " -q"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const LabelGrid in = readGrid(s.grid), posed = readGrid(out);
  const Eigen::Vector3d offset = in.geometry().continuousIndex(posed.geometry().origin);
  std::int64_t differing = 0;
  for (std::int64_t k = 0; k < posed.dims()[2]; ++k)
    for (std::int64_t j = 0; j < posed.dims()[1]; ++j)
      for (std::int64_t i = 0; i < posed.dims()[0]; ++i)
        differing += posed.at(i, j, k) != in.atOr(i + std::lround(offset.x()), j + std::lround(offset.y()), k + std::lround(offset.z()));
  EXPECT_EQ(differing, 0);
}

TEST(DeformCommand, PosesTheArmAndWritesTheReport) {
  VOX_REQUIRE_VOXMORPH();
  const Stick s = stick();
  const std::string pose = writeFile(s.dir + "/arm.json", kArmPose);
  const std::string out = s.dir + "/posed.mha", report = s.dir + "/report.json", cage = s.dir + "/cage.obj";
  const auto r = test::runCommand(voxmorph("deform " + test::quote(s.grid) + " --pose " + test::quote(pose) + " --organs " +
                                           test::quote(s.organs) + " -o " + test::quote(out) + " --report " + test::quote(report) +
                                           " --samples 3 --posed-cage " + test::quote(cage) + " --force"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("whole body"), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::exists(cage));
  const LabelGrid in = readGrid(s.grid), posed = readGrid(out);
  // The arm reaches out beyond the foreground's x extent at rest.
  std::int64_t xmin = in.dims()[0], xmax = -1;
  for (std::int64_t v = 0; v < in.voxelCount(); ++v)
    if (in.labels()[std::size_t(v)] != 0) {
      xmin = std::min(xmin, in.geometry().ijk(v)[0]);
      xmax = std::max(xmax, in.geometry().ijk(v)[0]);
    }
  EXPECT_GT(posed.dims()[0], xmax - xmin + 1);
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(report));
  for (const char* key : {"stages", "cage", "envelope", "transfer_mesh", "outliers", "labels", "whole_body", "distortion", "refinement",
                          "selections", "small_labels"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["samples"], 3);
  EXPECT_EQ(j["cage"]["valid"], true);
  EXPECT_GT(j["selections"][1]["cage_vertices"].get<int>(), 0);
  EXPECT_EQ(j["transfer_mesh"]["cuts"].size(), 1u);
  // The arm swings clear of the cut trunk: no transfer-mesh tet folds.
  EXPECT_EQ(j["transfer_mesh"]["tets_inverted_by_deformation"], 0);
  EXPECT_EQ(j["transfer_mesh"]["inverted_rest_volume_fraction"], 0.0);
  EXPECT_LT(std::abs(j["whole_body"]["volume_change_pct"].get<double>()), 10.0);
}

// --preserve-volumes: the report's correction brings every label to within
// about a voxel of its deformed volume, and the written grid holds the
// counts the report gives.
// The stick figure's arm pose deformed on the CPU with `preserveOption`: the
// report and the posed grid.
struct PosedArm {
  test::CommandResult run;
  nlohmann::json report;
  LabelGrid posed;
};
// (--force: the coarse stick figure's humerus changes its volume beyond
// --max-bone-change under this pose; the tests are about the volume
// correction.)
PosedArm posedArm(const Stick& s, const std::string& preserveOption) {
  PosedArm a;
  const std::string pose = writeFile(s.dir + "/arm.json", kArmPose);
  const std::string out = s.dir + "/posed.nii.gz", report = s.dir + "/report.json";
  a.run = test::runCommand(voxmorph("deform " + test::quote(s.grid) + " --pose " + test::quote(pose) + " --organs " +
                                    test::quote(s.organs) + " -o " + test::quote(out) + " --report " + test::quote(report) +
                                    " " + preserveOption + " --cpu --force -q"));
  if (a.run.exitCode != 0) return a;
  a.report = nlohmann::json::parse(std::ifstream(report));
  a.posed = readGrid(out);
  return a;
}

// deform starts itself again with malloc asking for huge pages where the
// kernel gives them on request; with VOXMORPH_SMALL_PAGES=1 it does not. The
// same arguments reach the run and the same bytes come out.
TEST(DeformCommand, HugePagesOrNotTheSameBytes) {
  VOX_REQUIRE_VOXMORPH();
  const Stick s = stick();
  const std::string pose = writeFile(s.dir + "/arm.json", kArmPose);
  std::string bytes[2];
  for (int small = 0; small < 2; ++small) {
    const std::string out = s.dir + "/posed" + std::to_string(small) + ".nii.gz";
    const auto r = test::runCommand(std::string(small ? "VOXMORPH_SMALL_PAGES=1 " : "") +
                                    voxmorph("deform " + test::quote(s.grid) + " --pose " + test::quote(pose) + " --organs " +
                                             test::quote(s.organs) + " -o " + test::quote(out) + " -q --force --cpu --preserve-volumes"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    std::ifstream in(out, std::ios::binary);
    bytes[small].assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  EXPECT_FALSE(bytes[0].empty());
  EXPECT_EQ(bytes[0], bytes[1]);
}

TEST(DeformCommand, PreserveVolumesKeepsEachLabelNearItsDeformedVolume) {
  VOX_REQUIRE_VOXMORPH();
  const Stick s = stick();
  const PosedArm a = posedArm(s, "--preserve-volumes");
  ASSERT_EQ(a.run.exitCode, 0) << a.run.err;
  const nlohmann::json& j = a.report;
  const LabelGrid& posed = a.posed;
  ASSERT_TRUE(j.contains("volume_correction"));
  const nlohmann::json& c = j["volume_correction"];
  EXPECT_LE(c["deviation_after_voxels"].get<double>(), c["deviation_before_voxels"].get<double>());
  EXPECT_LE(c["relabelled_voxels"].get<double>(), c["boundary_voxels"].get<double>());
  EXPECT_LT(c["deviation_after_voxels"].get<double>(), 0.1 * c["deviation_before_voxels"].get<double>()) << c.dump();
  for (const nlohmann::json& l : j["labels"]) {
    const auto label = l["label"].get<Label>();
    const auto n = std::count(posed.labels().begin(), posed.labels().end(), label);
    EXPECT_EQ(n, l["voxels_after"].get<std::int64_t>()) << "label " << label;
    EXPECT_LE(std::abs(double(n) - l["deformed_volume_voxels"].get<double>()), 1.0) << l.dump();
  }
}

// --preserve-volumes=rest: every label keeps its rest voxel count (organ
// masses), whatever volume the deformation gives it; the report names the
// targets and still gives the deformation's own volume per label.
TEST(DeformCommand, PreserveVolumesAtRestKeepsEachLabelsVoxels) {
  VOX_REQUIRE_VOXMORPH();
  const Stick s = stick();
  const PosedArm a = posedArm(s, "--preserve-volumes=rest");
  ASSERT_EQ(a.run.exitCode, 0) << a.run.err;
  const nlohmann::json& j = a.report;
  const LabelGrid& posed = a.posed;
  EXPECT_EQ(j["volume_correction"]["targets"], "rest");
  double moved = 0.0;
  for (const nlohmann::json& l : j["labels"]) {
    const auto label = l["label"].get<Label>();
    if (label == 0) continue;
    const auto n = std::count(posed.labels().begin(), posed.labels().end(), label);
    const double rest = l["voxels_before"].get<double>();
    EXPECT_EQ(n, l["voxels_after"].get<std::int64_t>()) << "label " << label;
    EXPECT_LE(std::abs(double(n) - rest), 1.0) << l.dump();
    moved = std::max(moved, std::abs(l["deformed_volume_voxels"].get<double>() - rest));
  }
  EXPECT_GT(moved, 2.0) << "the deformation changed no label's volume: the test shows nothing";
  // A value other than deformed / rest is a usage error.
  const auto bad = test::runCommand(voxmorph("deform " + test::quote(s.grid) + " --pose " + test::quote(s.dir + "/arm.json") + " -o " +
                                             test::quote(s.dir + "/x.nii.gz") + " --preserve-volumes=mass"));
  EXPECT_EQ(bad.exitCode, 2) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(s.dir + "/x.nii.gz"));
}

// A cage of one 300,000-vertex polygon (the OBJ reader fans it from its
// first vertex): refused as not closed. The manifold check once cleared a map
// as large as the fan's centre valence at every vertex, quadratic in the
// polygon's size (8 CPU seconds for this file, minutes for larger ones);
// under a 5 CPU-second limit the command is killed unless the check is
// linear.
TEST(DeformCommand, AHugePolygonCageIsRefusedInLinearTime) {
  VOX_REQUIRE_VOXMORPH();
  const Stick s = stick();
  std::string obj;
  const int n = 300000;
  obj.reserve(std::size_t(n) * 24);
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * 3.141592653589793 * i / n;
    obj += "v " + std::to_string(50.0 * std::cos(a)) + " " + std::to_string(50.0 * std::sin(a)) + " 0\n";
  }
  obj += "f";
  for (int i = 1; i <= n; ++i) obj += " " + std::to_string(i);
  obj += "\n";
  const std::string cage = writeFile(s.dir + "/polygon.obj", obj);
  const std::string identity = writeFile(s.dir + "/identity.json", kIdentityPose);
  const std::string out = s.dir + "/posed.nii.gz";
  expectOneLineError(test::runCommand("ulimit -t 5; " + voxmorph("deform " + test::quote(s.grid) + " -o " + test::quote(out) + " --pose " +
                                                                   test::quote(identity) + " --cage " + test::quote(cage))),
                     "not closed");
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(DeformCommand, BadInputIsAOneLineErrorWithoutOutput) {
  VOX_REQUIRE_VOXMORPH();
  const Stick s = stick();
  const std::string out = s.dir + "/posed.nii.gz";
  const std::string base = "deform " + test::quote(s.grid) + " -o " + test::quote(out) + " --pose ";
  const std::string nothing = writeFile(
      s.dir + "/nothing.json", R"({"selections": [{"name": "far away", "box": {"min": [5000, 5000, 5000], "max": [6000, 6000, 6000]}, "fixed": true}]})");
  expectOneLineError(test::runCommand(voxmorph(base + test::quote(nothing))), "selection 'far away' selects no cage vertex");
  const std::string identity = writeFile(s.dir + "/identity.json", kIdentityPose);
  const std::string open = writeFile(s.dir + "/open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 1 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 5\n");
  expectOneLineError(test::runCommand(voxmorph(base + test::quote(identity) + " --cage " + test::quote(open))), "not closed");
  const std::string arm = writeFile(s.dir + "/arm.json", kArmPose);
  expectOneLineError(test::runCommand(voxmorph(base + test::quote(arm))), "organ table");
  expectOneLineError(test::runCommand(voxmorph(base + test::quote(s.dir + "/missing.json"))), "missing.json");
  expectOneLineError(test::runCommand(voxmorph("deform " + test::quote(s.grid) + " -o " + test::quote(s.dir + "/posed.xyz") +
                                               " --pose " + test::quote(identity))),
                     "posed.xyz", 2);
  expectOneLineError(test::runCommand(voxmorph(base + test::quote(identity) + " --preserve-volumes --max-memory 512")),
                     "--preserve-volumes", 2);
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_EQ(test::listFiles(s.dir).find("posed"), std::string::npos) << test::listFiles(s.dir);
}

// The stick figure's top (z above 70 mm) moved by `translation`, the rest fixed.
std::string topMovedPose(const std::string& translation) {
  return R"({"selections": [
    {"name": "body", "box": {"min": [-1000, -1000, -1000], "max": [1000, 1000, 1000]}, "fixed": true},
    {"name": "top", "box": {"min": [-1000, -1000, 70], "max": [1000, 1000, 1000]},
     "transform": {"translation": )" + translation + "}}]}";
}

TEST(DeformCommand, PoseFarOffIsAOneLineErrorNamingTheSelection) {
  VOX_REQUIRE_VOXMORPH();
  const Stick s = stick();
  const std::string out = s.dir + "/posed.nii.gz";
  const std::string base = "deform " + test::quote(s.grid) + " -o " + test::quote(out) + " -q --cpu --pose ";
  // Far beyond any grid: no integer conversion may wrap or collapse the extent.
  for (const char* far : {"[1e30, 0, 0]", "[1e20, 0, 0]", "[0, 0, -1e15]"}) {
    const std::string pose = writeFile(s.dir + "/far.json", topMovedPose(far));
    const auto r = test::runCommand(voxmorph(base + test::quote(pose)));
    expectOneLineError(r, "far.json: selection 'top' (translation");
    // (After the file name, which may hold '-' itself: build/asan-all.)
    const std::string fault = r.err.substr(std::min(r.err.size(), r.err.find("far.json:")));
    EXPECT_EQ(fault.find("-"), fault.find("-1e+15")) << "a wrapped (negative) dimension: " << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << far;
  }
  // Within the supported size but far larger than the source: refused unless
  // --allow-growth.
  const std::string pose = writeFile(s.dir + "/grow.json", topMovedPose("[400, 400, 0]"));
  const auto refused = test::runCommand(voxmorph(base + test::quote(pose)));
  expectOneLineError(refused, "grow.json: selection 'top' (translation (400, 400, 0) mm) makes a posed grid of ");
  EXPECT_NE(refused.err.find("--allow-growth"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  // (--force as well: stretching the figure's top 400 mm away changes its
  // volume far beyond --max-body-change.)
  const auto allowed = test::runCommand(voxmorph(base + test::quote(pose) + " --allow-growth --force"));
  ASSERT_EQ(allowed.exitCode, 0) << allowed.err;
  EXPECT_GT(readGrid(out).voxelCount(), 8 * readGrid(s.grid).voxelCount());
}

TEST(DeformCommand, WarnsWhenTheCageLeavesForegroundOutside) {
  VOX_REQUIRE_VOXMORPH();
  const Stick s = stick();
  const std::string identity = writeFile(s.dir + "/identity.json", kIdentityPose);
  const auto r = test::runCommand(voxmorph("deform " + test::quote(s.grid) + " --pose " + test::quote(identity) + " -o " +
                                           test::quote(s.dir + "/posed.nii.gz") + " --vertices 12 --dilation 1 -q"));
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("warning: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("foreground voxels lie outside the cage"), std::string::npos) << r.err;
}

TEST(CageCommand, WritesAValidCageAndItsReport) {
  VOX_REQUIRE_VOXMORPH();
  const Stick s = stick();
  const std::string cage = s.dir + "/cage.obj", report = s.dir + "/cage.json";
  auto r = test::runCommand(voxmorph("cage " + test::quote(s.grid) + " -o " + test::quote(cage) + " --vertices 60 --report " + test::quote(report)));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(report));
  EXPECT_EQ(j["valid"], true);
  EXPECT_EQ(j["vertices"], 60);
  EXPECT_EQ(j["foreground_voxels_outside"], 0);
  // An inset cage between the arms and the trunk.
  r = test::runCommand(voxmorph("cage " + test::quote(s.grid) + " -o " + test::quote(s.dir + "/inset.obj") + " --organs " +
                                test::quote(s.organs) + " --separate right_arm:trunk --separate left_arm:trunk -q --report -"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_GT(nlohmann::json::parse(r.out)["eroded_voxels"].get<int>(), 0);
  expectOneLineError(test::runCommand(voxmorph("cage " + test::quote(s.grid) + " -o " + test::quote(s.dir + "/x.obj") + " --separate right_arm:trunk")),
                     "organ table", 2);
  expectOneLineError(test::runCommand(voxmorph("cage " + test::quote(s.grid) + " -o " + test::quote(s.dir + "/x.stl"))), "x.stl", 2);
  EXPECT_FALSE(std::filesystem::exists(s.dir + "/x.obj"));
}

}  // namespace
}  // namespace vox
