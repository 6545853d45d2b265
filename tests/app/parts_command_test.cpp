// voxmorph parts, and joint poses through deform and render, end to end on
// the synthetic skeleton figure: the parts grid keeps the input's geometry
// and the report lists every part and joint; a corrected parts grid is
// accepted back; a joint pose deforms. Bad input (an organ table without
// bones, a joint pose without an organ table, an angle out of range, a
// joint the skeleton lacks, a parts grid of other dims) is a one-line
// error with exit code 1 and no output file.

#include "geometry/deform/solve/skin_cover.h"
#include "geometry/io/grid_io.h"
#include "geometry/organ_table.h"
#include "geometry/skeleton/bones.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

namespace vox {
namespace {

std::string voxmorph(const std::string& args) { return test::quote(test::voxmorphBinary()) + " " + args; }

struct Figure {
  std::string dir, grid, organs;
};

// Written to `dir` (one per test: test::tempDir() empties it).
Figure figure(const std::string& dir, const std::string& kind, int size) {
  Figure f;
  f.dir = dir;
  f.grid = f.dir + "/" + kind + ".nii.gz";
  f.organs = f.dir + "/" + kind + ".dat";
  const auto r = test::runCommand(voxmorph("synth " + kind + " --size " + std::to_string(size) + " -o " + test::quote(f.grid) +
                                           " --organs " + test::quote(f.organs)));
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return f;
}

std::string writeFile(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

void expectOneLineError(const test::CommandResult& r, const std::string& fault) {
  EXPECT_EQ(r.exitCode, 1) << r.err;
  EXPECT_NE(r.err.find(fault), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
}

TEST(PartsCommand, WritesThePartsGridAndReport) {
  VOX_REQUIRE_VOXMORPH();
  const Figure f = figure(test::tempDir(), "skeleton", 96);
  const std::string out = f.dir + "/parts.nii.gz", report = f.dir + "/parts.json";
  const auto r = test::runCommand(voxmorph("parts " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " -o " + test::quote(out) +
                                           " --report " + test::quote(report) + " -q"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const LabelGrid in = readGrid(f.grid), parts = readGrid(out);
  EXPECT_EQ(parts.dims(), in.dims());
  EXPECT_EQ(parts.spacing(), in.spacing());
  EXPECT_EQ(parts.origin(), in.origin());
  std::int64_t foreground = 0;
  for (std::size_t v = 0; v < in.labels().size(); ++v) {
    foreground += in.labels()[v] != 0;
    ASSERT_EQ(in.labels()[v] != 0, parts.labels()[v] != 0) << v;
    ASSERT_LE(parts.labels()[v], 16);
  }
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(report));
  ASSERT_EQ(j["parts"].size(), 16u);
  std::int64_t sum = 0;
  for (const auto& p : j["parts"]) {
    sum += p["voxels"].get<std::int64_t>();
    EXPECT_GT(p["voxels"].get<std::int64_t>(), 0) << p["name"];
    EXPECT_FALSE(p["bones"].empty()) << p["name"];
  }
  EXPECT_EQ(sum, foreground);
  ASSERT_EQ(j["joints"].size(), 14u);
  EXPECT_EQ(j["joints"][2]["name"], "right_shoulder");
  EXPECT_EQ(j["joints"][2]["center_mm"].size(), 3u);
  EXPECT_EQ(j["joints"][2]["degrees_of_freedom"]["abduction"]["range_deg"][1], 180.0);

  // The grid passed back (a user's corrections) is taken as it is.
  const std::string again = f.dir + "/again.nii.gz";
  const auto back = test::runCommand(voxmorph("parts " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --parts " +
                                              test::quote(out) + " -o " + test::quote(again) + " -q"));
  ASSERT_EQ(back.exitCode, 0) << back.err;
  EXPECT_EQ(readGrid(again).labels(), parts.labels());
}

TEST(PartsCommand, JointPoseDeformsAndRenders) {
  VOX_REQUIRE_VOXMORPH();
  const Figure f = figure(test::tempDir(), "skeleton", 96);
  const std::string pose = writeFile(f.dir + "/pose.json", R"({"joints": {"right_shoulder": {"abduction": 30}, "right_elbow": {"flexion": 40}}})");
  const std::string out = f.dir + "/posed.nii.gz", report = f.dir + "/report.json", mask = f.dir + "/collisions.nii.gz";
  const auto r = test::runCommand(voxmorph("deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " + test::quote(pose) +
                                           " -o " + test::quote(out) + " --report " + test::quote(report) + " --collision-mask " +
                                           test::quote(mask) + " --rigid-bones --cpu --force -q"));
  // (--force: on this coarse figure the rigid humerus's tets change its
  // volume beyond --max-bone-change; the test is about what is reported.)
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(report));
  // Collisions and bone measures are reported for a joint pose; the mask
  // covers the posed extent.
  ASSERT_TRUE(j.contains("collisions"));
  EXPECT_GT(j["collisions"]["body_voxels"].get<std::int64_t>(), 0);
  const LabelGrid collided = readGrid(mask);
  EXPECT_EQ(j["collisions"]["voxels"].get<std::int64_t>(), std::int64_t(std::count(collided.labels().begin(), collided.labels().end(), Label(1))));
  ASSERT_TRUE(j.contains("bones"));
  EXPECT_TRUE(j["bones"].contains("held_rigid"));
  EXPECT_FALSE(j["bones"]["per_bone"].empty());
  // Each part's rigid motion, world mm: the trunk still, the upper arm
  // turned by the shoulder's 30 degrees, the forearm by more.
  ASSERT_TRUE(j.contains("part_transforms"));
  ASSERT_EQ(j["part_transforms"].size(), 16u);
  const auto turn = [&](const std::string& part) {
    for (const auto& t : j["part_transforms"])
      if (t["part"] == part) {
        const auto& m = t["matrix"];
        EXPECT_EQ(m[3], nlohmann::json({0.0, 0.0, 0.0, 1.0}));
        const double trace = m[0][0].get<double>() + m[1][1].get<double>() + m[2][2].get<double>();
        return std::acos(std::clamp((trace - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / std::numbers::pi;
      }
    ADD_FAILURE() << "no transform for " << part;
    return -1.0;
  };
  EXPECT_NEAR(turn("trunk"), 0.0, 1e-6);
  EXPECT_NEAR(turn("right_upper_arm"), 30.0, 1e-6);
  EXPECT_GT(turn("right_forearm"), 40.0);
  std::vector<std::string> names;
  for (const auto& s : j["selections"]) names.push_back(s["name"]);
  ASSERT_GE(names.size(), 3u);
  EXPECT_EQ(names[0], "body parts at rest");
  EXPECT_NE(std::find(names.begin(), names.end(), "right_elbow: right_forearm, right_hand"), names.end());
  EXPECT_TRUE(std::filesystem::exists(out));
  const std::string image = f.dir + "/posed.png";
  const auto rendered = test::runCommand(voxmorph("render " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " +
                                                  test::quote(pose) + " -o " + test::quote(image) + " --size 80x60 --cpu -q"));
  EXPECT_EQ(rendered.exitCode, 0) << rendered.err;
  EXPECT_TRUE(std::filesystem::exists(image));
}

// A result beyond the bounds on bone and body change is refused with one
// line naming the fault and nothing written; --force writes it, warns, and
// the report says "forced".
TEST(PartsCommand, BoneOrBodyChangeBeyondTheBoundsIsRefusedUnlessForced) {
  VOX_REQUIRE_VOXMORPH();
  const Figure f = figure(test::tempDir(), "skeleton", 96);
  const std::string pose = writeFile(f.dir + "/pose.json", R"({"joints": {"right_shoulder": {"abduction": 30}, "right_elbow": {"flexion": 40}}})");
  const std::string out = f.dir + "/posed.nii.gz", report = f.dir + "/report.json", cage = f.dir + "/posed.obj";
  const std::string base = "deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " + test::quote(pose) +
                           " -o " + test::quote(out) + " --report " + test::quote(report) + " --posed-cage " + test::quote(cage) + " --cpu -q";
  // Every bone within 1 %: refused before the rasterization, naming the bone
  // that changes most.
  expectOneLineError(test::runCommand(voxmorph(base + " --max-bone-change 1")), "humerus by ");
  // The bones allowed, the whole body within 0.01 %: refused once G' is
  // measured, before it or the posed cage is committed.
  expectOneLineError(test::runCommand(voxmorph(base + " --max-bone-change 100 --max-body-change 0.01")),
                     "the pose changes the whole body's volume by ");
  EXPECT_EQ(test::listFiles(f.dir), "pose.json\nskeleton.dat\nskeleton.nii.gz\n");
  const auto forced = test::runCommand(voxmorph(base + " --max-bone-change 1 --force"));
  ASSERT_EQ(forced.exitCode, 0) << forced.err;
  EXPECT_NE(forced.err.find("written because of --force"), std::string::npos) << forced.err;
  EXPECT_TRUE(nlohmann::json::parse(std::ifstream(report))["forced"].get<bool>());
  EXPECT_TRUE(std::filesystem::exists(out));
  EXPECT_TRUE(std::filesystem::exists(cage));
  // Within the bounds: written, not forced.
  const auto within = test::runCommand(voxmorph(base + " --max-bone-change 100 --max-body-change 100"));
  ASSERT_EQ(within.exitCode, 0) << within.err;
  EXPECT_FALSE(nlohmann::json::parse(std::ifstream(report))["forced"].get<bool>());
}

TEST(PartsCommand, BadInput) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const Figure f = figure(dir, "skeleton", 96);
  const Figure spheres = figure(dir, "spheres", 16);
  const Figure stick = figure(dir, "stick", 48);
  const std::string out = f.dir + "/out.nii.gz";
  // An organ table that names no bones.
  expectOneLineError(test::runCommand(voxmorph("parts " + test::quote(spheres.grid) + " --organs " + test::quote(spheres.organs) + " -o " +
                                               test::quote(out))),
                     spheres.organs + ": the organ table names no bones");
  const std::string arm = writeFile(f.dir + "/arm.json", R"({"joints": {"right_shoulder": {"abduction": 30}}})");
  const std::string deform = "deform " + test::quote(f.grid) + " -o " + test::quote(out) + " --cpu -q --pose ";
  // A joint pose without the organ table, and with one that names no bones.
  expectOneLineError(test::runCommand(voxmorph(deform + test::quote(arm))), arm + ": a pose with joints or body parts needs the grid's organ table");
  expectOneLineError(test::runCommand(voxmorph(deform + test::quote(arm) + " --organs " + test::quote(spheres.organs))),
                     spheres.organs + ": the organ table names no bones");
  // An angle out of range; a joint or angle that does not exist.
  const std::string bent = writeFile(f.dir + "/bent.json", R"({"joints": {"right_elbow": {"flexion": 170}}})");
  expectOneLineError(test::runCommand(voxmorph(deform + test::quote(bent) + " --organs " + test::quote(f.organs))),
                     bent + ": joint 'right_elbow' flexion 170 is outside its range [0, 150] degrees");
  // Legs crossed through each other: refused before the work, by the cage
  // pipeline and the articulated mesh alike; --force writes it with a warning.
  const std::string crossed = writeFile(f.dir + "/crossed.json", R"({"joints": {"right_hip": {"abduction": -30}}})");
  for (const std::string extra : {"", " --articulated"}) {
    expectOneLineError(test::runCommand(voxmorph(deform + test::quote(crossed) + " --organs " + test::quote(f.organs) + extra)),
                       crossed + ": the bones of the right_lower_leg and the left_lower_leg pass through each other (");
    EXPECT_FALSE(std::filesystem::exists(out)) << extra;
  }
  expectOneLineError(test::runCommand(voxmorph(deform + test::quote(crossed) + " --organs " + test::quote(f.organs) + " --max-bone-overlap 50")),
                     "the pose changes the volume of the ");  // past the overlap check, the bone check of the cage pipeline
  const auto forced = test::runCommand(voxmorph(deform + test::quote(crossed) + " --organs " + test::quote(f.organs) + " --force"));
  EXPECT_EQ(forced.exitCode, 0) << forced.err;
  EXPECT_NE(forced.err.find("pass through each other"), std::string::npos) << forced.err;
  EXPECT_NE(forced.err.find("written because of --force"), std::string::npos) << forced.err;
  std::filesystem::remove(out);
  const std::string wing = writeFile(f.dir + "/wing.json", R"({"joints": {"right_wing": {"flexion": 10}}})");
  expectOneLineError(test::runCommand(voxmorph(deform + test::quote(wing) + " --organs " + test::quote(f.organs))), "unknown joint 'right_wing'");
  // A joint the skeleton lacks: the stick figure's only bones are its humeri.
  expectOneLineError(test::runCommand(voxmorph("deform " + test::quote(stick.grid) + " -o " + test::quote(out) + " --cpu -q --pose " +
                                               test::quote(arm) + " --organs " + test::quote(stick.organs))),
                     arm + ": the grid's skeleton has no joint 'right_shoulder'");
  // A parts grid of other dims.
  expectOneLineError(test::runCommand(voxmorph(deform + test::quote(arm) + " --organs " + test::quote(f.organs) + " --parts " +
                                               test::quote(spheres.grid))),
                     spheres.grid + ": has other dims than the grid");
  // A collision mask needs body parts.
  const std::string still = writeFile(f.dir + "/still.json", R"({"selections": [{"box": {"min": [-1000, -1000, -1000], "max": [1000, 1000, 1000]}, "fixed": true}]})");
  expectOneLineError(test::runCommand(voxmorph(deform + test::quote(still) + " --collision-mask " + test::quote(f.dir + "/mask.nii.gz"))),
                     f.dir + "/mask.nii.gz: collisions are between body parts");
  expectOneLineError(test::runCommand(voxmorph(deform + test::quote(still) + " --organs " + test::quote(spheres.organs) + " --collision-mask " +
                                               test::quote(f.dir + "/mask.nii.gz"))),
                     f.dir + "/mask.nii.gz: collisions are between body parts");
  EXPECT_FALSE(std::filesystem::exists(f.dir + "/mask.nii.gz"));
  // render checks the organ table before reading the grid.
  expectOneLineError(test::runCommand(voxmorph("render " + test::quote(f.grid) + " --pose " + test::quote(arm) + " -o " +
                                               test::quote(f.dir + "/x.png") + " --cpu -q")),
                     "needs the grid's organ table");
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_FALSE(std::filesystem::exists(f.dir + "/x.png"));
}

// --articulated: the joint pose on the transfer mesh that resolves the
// skeleton. The figure's elbow at 90 degrees (its forearm and hand hang
// against the trunk at rest): no tet inverted, the bones on their parts'
// motions, the report's articulated section and transforms; bad requests
// refused with one line.
TEST(PartsCommand, ArticulatedJointPose) {
  VOX_REQUIRE_VOXMORPH();
  const Figure f = figure(test::tempDir(), "skeleton", 96);
  const std::string pose = writeFile(f.dir + "/pose.json", R"({"joints": {"right_elbow": {"flexion": 90}}})");
  const std::string out = f.dir + "/posed.nii.gz", report = f.dir + "/report.json";
  const std::string base = "deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " + test::quote(pose) +
                           " -o " + test::quote(out) + " --articulated --cpu -q";
  const auto r = test::runCommand(voxmorph(base + " --report " + test::quote(report) + " --preserve-volumes"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(report));
  ASSERT_TRUE(j.contains("articulated"));
  const nlohmann::json& a = j["articulated"];
  EXPECT_EQ(a["inverted_tets"].get<int>(), 0);
  EXPECT_TRUE(a["bones_on_their_motions"].get<bool>());
  EXPECT_GT(a["min_relative_volume"].get<double>(), 0.05);
  EXPECT_GT(a["limb_cut_faces"].get<int>(), 0);
  EXPECT_GT(a["articular_bodies"].get<int>(), 0);
  // The contact after the pose: what it found and what it left.
  ASSERT_TRUE(a.contains("contact"));
  EXPECT_LE(a["contact"]["penetrating_vertices_after"].get<int>(), a["contact"]["penetrating_vertices_before"].get<int>());
  EXPECT_LE(a["contact"]["deepest_mm_after"].get<double>(), a["contact"]["deepest_mm_before"].get<double>());
  EXPECT_EQ(j["transfer_mesh"]["tets_inverted_by_deformation"].get<int>(), 0);
  ASSERT_EQ(j["part_transforms"].size(), 16u);
  // Every bone keeps its volume through the mesh: its tets move rigidly.
  // (Not the figure's turned forearm bones: 24 voxels one voxel thin, part
  // of them in the tissue tets beside the elbow's body.)
  for (const auto& b : j["bones"]["per_bone"])
    if (b["voxels"].get<int>() >= 40) {
      EXPECT_LT(std::abs(b["volume_change_percent"].get<double>()), 0.5) << b.dump();
    }
  EXPECT_TRUE(std::filesystem::exists(out));
  // The posed grid keeps every bone label's rest voxels: bones moved rigidly
  // are corrected to their rest volume, each side under a key of its own.
  int boneLabels = 0;
  for (const auto& l : j["labels"])
    if (l["name"].get<std::string>().find(", cortical") != std::string::npos) {
      ++boneLabels;
      EXPECT_LE(std::abs(l["voxels_after"].get<double>() - l["voxels_before"].get<double>()), 1.0) << l.dump();
    }
  EXPECT_GE(boneLabels, 10);
  // The skin laid over what the pose bared: no more bare tissue than at
  // rest; without the cover the elbow's turn leaves more, and the report
  // counts what the cover relabelled.
  {
    const LabelGrid rest = readGrid(f.grid), posed = readGrid(out);
    const std::vector<std::uint8_t> skin = skeleton::skinOfLabels(OrganTable::read(f.organs), rest.maxLabel());
    const auto bare = [&skin](const LabelGrid& g) {
      const std::vector<std::uint8_t> flags = bareVoxels(g, skin);
      return std::count(flags.begin(), flags.end(), std::uint8_t(1));
    };
    ASSERT_TRUE(j.contains("skin_cover"));
    EXPECT_LE(bare(posed), bare(rest));
    const std::string bareOut = f.dir + "/bare.nii.gz", bareReport = f.dir + "/bare.json";
    const auto uncovered = test::runCommand(voxmorph("deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " +
                                                     test::quote(pose) + " -o " + test::quote(bareOut) + " --articulated --cpu -q" +
                                                     " --report " + test::quote(bareReport) + " --preserve-volumes --no-skin-cover"));
    ASSERT_EQ(uncovered.exitCode, 0) << uncovered.err;
    EXPECT_FALSE(nlohmann::json::parse(std::ifstream(bareReport)).contains("skin_cover"));
    const std::int64_t covered = j["skin_cover"]["covered_voxels"].get<std::int64_t>();
    EXPECT_GT(covered, 0);
    EXPECT_GT(bare(readGrid(bareOut)), bare(posed));
  }

  // Prepared once with the articulated transfer mesh: the same pose from
  // the state writes the same bytes, and its report says the mesh took no
  // building.
  const std::string state = f.dir + "/figure.vxprep", fromState = f.dir + "/from_state.nii.gz";
  const auto prepared = test::runCommand(voxmorph("prepare " + test::quote(f.grid) + " --organs " + test::quote(f.organs) +
                                                  " --articulated -q -o " + test::quote(state)));
  ASSERT_EQ(prepared.exitCode, 0) << prepared.err;
  const std::string withState = "deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " + test::quote(pose) +
                                " -o " + test::quote(fromState) + " --articulated --cpu -q --preserve-volumes --prepared " + test::quote(state);
  const auto fromStateRun = test::runCommand(voxmorph(withState + " --report " + test::quote(f.dir + "/from_state.json")));
  ASSERT_EQ(fromStateRun.exitCode, 0) << fromStateRun.err;
  EXPECT_EQ(fromStateRun.err.find("holds no articulated transfer mesh"), std::string::npos) << fromStateRun.err;
  EXPECT_FALSE(test::readText(out).empty());
  EXPECT_TRUE(test::readText(fromState) == test::readText(out));
  const auto meshSeconds = [](const nlohmann::json& report) {
    for (const auto& stage : report["stages"])
      if (stage["stage"] == "articulated transfer mesh") return stage["seconds"].get<double>();
    return -1.0;
  };
  const double built = meshSeconds(j), taken = meshSeconds(nlohmann::json::parse(std::ifstream(f.dir + "/from_state.json")));
  EXPECT_GT(built, 0.0);
  EXPECT_GE(taken, 0.0);
  EXPECT_LT(taken, 0.5 * built);
  // A pose file that says "articulated": true takes the same way without
  // the flag, and `prepare --pose` with it stores the articulated mesh.
  {
    const std::string marked = writeFile(f.dir + "/marked.json", R"({"articulated": true, "joints": {"right_elbow": {"flexion": 90}}})");
    const std::string markedOut = f.dir + "/marked.nii.gz", markedState = f.dir + "/marked.vxprep";
    const auto markedRun = test::runCommand(voxmorph("deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " +
                                                     test::quote(marked) + " -o " + test::quote(markedOut) + " --cpu -q --preserve-volumes"));
    ASSERT_EQ(markedRun.exitCode, 0) << markedRun.err;
    EXPECT_TRUE(test::readText(markedOut) == test::readText(out));
    const auto markedPrepare = test::runCommand(voxmorph("prepare " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " +
                                                         test::quote(marked) + " -q -o " + test::quote(markedState)));
    ASSERT_EQ(markedPrepare.exitCode, 0) << markedPrepare.err;
    const auto markedFromState = test::runCommand(voxmorph("deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " +
                                                           test::quote(marked) + " -o " + test::quote(markedOut) +
                                                           " --cpu -q --preserve-volumes --prepared " + test::quote(markedState)));
    ASSERT_EQ(markedFromState.exitCode, 0) << markedFromState.err;
    EXPECT_EQ(markedFromState.err.find("holds no articulated transfer mesh"), std::string::npos) << markedFromState.err;
    EXPECT_TRUE(test::readText(markedOut) == test::readText(out));
    // It has no cage: a cage option is a usage error naming the file.
    const auto markedCage = test::runCommand(voxmorph("deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " +
                                                      test::quote(marked) + " -o " + test::quote(f.dir + "/x.nii.gz") + " --cpu -q --rigid-bones"));
    EXPECT_EQ(markedCage.exitCode, 2);
    EXPECT_NE(markedCage.err.find("marked.json (\"articulated\")"), std::string::npos) << markedCage.err;
  }
  // The bone-gap cut is one of the mesh's options: a state prepared with the
  // default holds no mesh for a run without the cut (built, with a
  // warning; the report counts no cut face); without --articulated the
  // option is a usage error.
  ASSERT_TRUE(a.contains("bone_gap_cut_faces"));
  const std::string gapOut = f.dir + "/gap.nii.gz", gapReport = f.dir + "/gap.json";
  const auto gapFromState = test::runCommand(voxmorph("deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " +
                                                      test::quote(pose) + " -o " + test::quote(gapOut) + " --report " + test::quote(gapReport) +
                                                      " --articulated --cpu -q --bone-gap 0 --prepared " + test::quote(state)));
  ASSERT_EQ(gapFromState.exitCode, 0) << gapFromState.err;
  EXPECT_NE(gapFromState.err.find("holds no articulated transfer mesh"), std::string::npos) << gapFromState.err;
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(gapReport))["articulated"]["bone_gap_cut_faces"].get<int>(), 0);
  const auto gapAlone = test::runCommand(voxmorph("deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " +
                                                  test::quote(pose) + " -o " + test::quote(f.dir + "/x.nii.gz") + " --cpu -q --bone-gap 2"));
  EXPECT_EQ(gapAlone.exitCode, 2);
  EXPECT_NE(gapAlone.err.find("--bone-gap"), std::string::npos) << gapAlone.err;

  const std::string selections = writeFile(f.dir + "/box.json", R"({"selections": [{"name": "b", "box": {"min": [0, 0, 0], "max": [10, 10, 10]}, "fixed": true}]})");
  const auto noJoints = test::runCommand(voxmorph("deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " +
                                                  test::quote(selections) + " -o " + test::quote(f.dir + "/x.nii.gz") + " --articulated --cpu -q"));
  EXPECT_EQ(noJoints.exitCode, 1);
  EXPECT_NE(noJoints.err.find("--articulated poses joints"), std::string::npos) << noJoints.err;
  const auto outOfCore = test::runCommand(voxmorph(base + " --max-memory 512"));
  EXPECT_EQ(outOfCore.exitCode, 2);
  EXPECT_NE(outOfCore.err.find("--max-memory"), std::string::npos) << outOfCore.err;
  EXPECT_FALSE(std::filesystem::exists(f.dir + "/x.nii.gz"));

  // The hip flexed 120 degrees and abducted 45 presses this figure's thigh
  // into its pelvis (over 1 % of the body overlaps; flexed alone 0.13 %,
  // the hip's bone-gap cut parting the femoral neck's tissue from the
  // acetabulum's): more than contact holds. Refused as physically wrong,
  // naming the two parts and the hip, nothing written.
  const std::string flexed = writeFile(f.dir + "/flexed.json", R"({"joints": {"right_hip": {"flexion": 120, "abduction": 45}}})");
  const std::string refusedOut = f.dir + "/flexed.nii.gz";
  const auto refused = test::runCommand(voxmorph("deform " + test::quote(f.grid) + " --organs " + test::quote(f.organs) + " --pose " +
                                                 test::quote(flexed) + " -o " + test::quote(refusedOut) + " --articulated --cpu -q"));
  expectOneLineError(refused, flexed + ": the pose presses the tissue of the pelvis and the right_thigh through each other at the right_hip (");
  EXPECT_NE(refused.err.find("of the body overlaps, more than --max-tissue-overlap 0.5 %); nothing written (--force writes it)"), std::string::npos)
      << refused.err;
  EXPECT_FALSE(std::filesystem::exists(refusedOut));
}

}  // namespace
}  // namespace vox
