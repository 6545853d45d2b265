// What a new user meets first, end to end through the CLI: outputs checked
// before any work (a missing directory, an unknown extension, a bad report
// path), one style of range message and exit code 2 for every usage error,
// the memory estimate that refuses a target length far below the voxel
// size, organ tables that name every label of their phantom, and the
// deformation's printed organ table, CSV, warnings and histogram plot, and
// renders that show shape, fill the frame and carry a legend and a scale bar.

#include "geometry/io/grid_io.h"
#include "geometry/io/png_io.h"
#include "geometry/label_stats.h"
#include "geometry/organ_table.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <tuple>

namespace vox {
namespace {

namespace fs = std::filesystem;

test::CommandResult voxmorph(const std::string& args) { return test::runCommand(test::quote(test::voxmorphBinary()) + " " + args); }

void expectOneLine(const test::CommandResult& r, int exitCode, const std::string& fault) {
  EXPECT_EQ(r.exitCode, exitCode) << r.err;
  EXPECT_NE(r.err.find(fault), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

std::string spheres(const std::string& dir, int size = 16) {
  const std::string grid = dir + "/spheres.nii.gz";
  EXPECT_EQ(voxmorph("synth spheres --size " + std::to_string(size) + " -o " + test::quote(grid)).exitCode, 0);
  return grid;
}

const char* kArmPose = R"({
  "selections": [
    {"name": "body", "box": {"min": [-1000, -1000, -1000], "max": [1000, 1000, 1000]}, "fixed": true},
    {"name": "right arm", "box": {"min": [-1000, -1000, 40], "max": [10, 1000, 80]}, "group": "right_arm",
     "transform": {"rotation": {"axis": [0, 1, 0], "angle_deg": 30, "center": [12, 14, 80]}}}
  ],
  "separations": [{"groups": ["right_arm", "trunk"]}]
})";

TEST(NewUser, OutputsAreCheckedBeforeAnyWork) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = spheres(dir);
  const std::string missing = test::quote(dir + "/no/such/dir/out.vtu");
  expectOneLine(voxmorph("mesh " + test::quote(grid) + " -l 2 -o " + missing), 1, "does not exist");
  expectOneLine(voxmorph("mesh " + test::quote(grid) + " -l 2 -o " + test::quote(dir + "/out.vtu") + " --report " +
                         test::quote(dir + "/absent/r.json")),
                1, "absent/r.json");
  expectOneLine(voxmorph("mesh " + test::quote(grid) + " -l 2 -o " + test::quote(dir + "/out.vtu") + " --report " +
                         test::quote(dir + "/r.txt")),
                2, "use .json");
  expectOneLine(voxmorph("synth spheres -o " + test::quote(dir + "/none/s.nii.gz")), 1, "does not exist");
  expectOneLine(voxmorph("cage " + test::quote(grid) + " -o " + test::quote(dir + "/c.obj") + " --report " +
                         test::quote(dir + "/none/c.json")),
                1, "does not exist");
  expectOneLine(voxmorph("render " + test::quote(grid) + " -o " + test::quote(dir + "/image.jpg")), 2, "use .png");
  // deform: a bad report path fails before the posed grid is written.
  std::ofstream(dir + "/arm.json") << kArmPose;
  const std::string stick = dir + "/stick.mha", organs = dir + "/stick.dat";
  ASSERT_EQ(voxmorph("synth stick --size 48 -o " + test::quote(stick) + " --organs " + test::quote(organs)).exitCode, 0);
  expectOneLine(voxmorph("deform " + test::quote(stick) + " --organs " + test::quote(organs) + " --pose " + test::quote(dir + "/arm.json") +
                         " -o " + test::quote(dir + "/posed.nii.gz") + " --report " + test::quote(dir + "/none/r.json")),
                1, "does not exist");
  expectOneLine(voxmorph("deform " + test::quote(stick) + " --organs " + test::quote(organs) + " --pose " + test::quote(dir + "/arm.json") +
                         " -o " + test::quote(dir + "/posed.nii.gz") + " --plots " + test::quote(dir + "/none/p.png")),
                1, "does not exist");
  EXPECT_EQ(test::listFiles(dir), "arm.json\nspheres.nii.gz\nstick.dat\nstick.mha\n");
}

TEST(NewUser, UsageErrorsShareOneRangeMessageAndExitTwo) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = spheres(dir);
  const std::string mesh = "mesh " + test::quote(grid) + " -o " + test::quote(dir + "/out.vtu") + " -l ";
  for (const char* bad : {"nan", "inf", "abc", "0", "-1"}) {
    const auto r = voxmorph(mesh + bad);
    EXPECT_EQ(r.exitCode, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find("--length: must be a number in (0, 100000] mm, got '" + std::string(bad) + "'"), std::string::npos) << r.err;
    EXPECT_LT(r.err.size(), 200u) << r.err;
  }
  const auto iterations = voxmorph(mesh + "2 --iterations 1000");
  EXPECT_EQ(iterations.exitCode, 2);
  EXPECT_NE(iterations.err.find("--iterations: must be an integer in [0, 100], got '1000'"), std::string::npos) << iterations.err;
  // A length longer than the labelled region; one far below the voxel size
  // over the memory budget: refused with the estimate, before any work.
  expectOneLine(voxmorph(mesh + "700"), 2, "longer than the labelled region");
  const auto r = voxmorph(mesh + "0.05 --max-memory 64");
  expectOneLine(r, 2, "over the 64 MB budget");
  EXPECT_NE(r.err.find("M tets"), std::string::npos) << r.err;
  const auto ok = voxmorph(mesh + "4");
  EXPECT_EQ(ok.exitCode, 0) << ok.err;
  EXPECT_NE(ok.err.find("estimate: about "), std::string::npos) << ok.err;
  EXPECT_FALSE(fs::exists(dir + "/none.vtu"));
}

// Every label of the ICRP 110 phantoms is named by its organ table (the AM's
// label 141 is the skin of its first and last slices), and a label a table
// lacks is flagged by info.
TEST(NewUser, OrganTablesNameEveryLabelOfTheirPhantom) {
  for (const char* phantom : {"am", "af"}) {
    const LabelGrid grid = readGrid(test::assetPath(std::string("icrp110_") + phantom + ".nii.gz"));
    const OrganTable organs = OrganTable::read(test::assetPath(std::string("icrp110_") + phantom + "_organs.dat"));
    const LabelStats stats = computeLabelStats(grid);
    EXPECT_TRUE(organs.unnamedLabels(stats.counts).empty()) << phantom << ": " << unnamedLabelsNote(organs, stats.counts);
  }
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = spheres(dir);
  std::ofstream(dir + "/two.dat") << "ID name tissue density\n1 Core 1 1.0\n2 Shell 1 1.0\n";
  const auto r = voxmorph("info " + test::quote(grid) + " --cpu --organs " + test::quote(dir + "/two.dat"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("labels without a name in the organ table: 3 ("), std::string::npos) << r.out;
  const auto j = voxmorph("info " + test::quote(grid) + " --cpu --json --organs " + test::quote(dir + "/two.dat"));
  EXPECT_EQ(nlohmann::json::parse(j.out)["unnamed_labels"], nlohmann::json::array({3})) << j.out;
}

TEST(NewUser, DeformPrintsTheOrganTableWritesItsCsvAndPlots) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string stick = dir + "/stick.mha", organs = dir + "/stick.dat";
  ASSERT_EQ(voxmorph("synth stick --size 48 -o " + test::quote(stick) + " --organs " + test::quote(organs)).exitCode, 0);
  // The table without its heart: label 7 is flagged everywhere.
  {
    std::ifstream in(organs);
    std::ofstream out(dir + "/no_heart.dat");
    for (std::string line; std::getline(in, line);)
      if (line.rfind("7 ", 0) != 0) out << line << "\n";
  }
  std::ofstream(dir + "/arm.json") << kArmPose;
  const auto r = voxmorph("deform " + test::quote(stick) + " --organs " + test::quote(dir + "/no_heart.dat") + " --pose " +
                          test::quote(dir + "/arm.json") + " -o " + test::quote(dir + "/posed.nii.gz") + " --report " +
                          test::quote(dir + "/r.json") + " --plots " + test::quote(dir + "/plots.png") + " --flag 1 --force");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  // The printed table: a row per label with its name, masses and flag.
  EXPECT_NE(r.out.find("label  organ"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Muscle, arms, right"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(not in organ table)"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("warning: labels without a name in the organ table: 7 (31 voxels)"), std::string::npos) << r.err;
  // The CSV beside the JSON: a header and one row per label of the JSON.
  std::ifstream csv(dir + "/r.csv");
  ASSERT_TRUE(csv.good());
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "label,name,voxels_before,voxels_after,volume_before_mm3,volume_after_mm3,mass_before_g,mass_after_g,change_pct,flag");
  const nlohmann::json report = nlohmann::json::parse(std::ifstream(dir + "/r.json"));
  std::size_t rows = 0, flagged = 0;
  for (std::string line; std::getline(csv, line); ++rows) {
    const nlohmann::json& j = report["labels"][rows];
    EXPECT_EQ(line.substr(0, line.find(',')), std::to_string(j["label"].get<int>()));
    const double change = j["volume_change_pct"].get<double>();
    const bool unnamed = j.contains("unnamed");
    const std::string flag = line.substr(line.rfind(',') + 1);
    EXPECT_EQ(flag, unnamed ? "unnamed" : std::abs(change) <= 1.0 ? "" : j["voxels_before"].get<int>() < 1000 ? "small" : "*") << line;
    flagged += flag == "*";
  }
  EXPECT_EQ(rows, report["labels"].size());
  EXPECT_EQ(report["warnings"].size(), 1u) << report["warnings"];
  // The plot: three histograms on white.
  const RgbImage plot = readPng(dir + "/plots.png");
  EXPECT_GT(plot.width, 1000);
  EXPECT_GT(countNotBackground(plot, Rgb{255, 255, 255}), 5000u);
  EXPECT_GT(std::count(plot.pixels.begin(), plot.pixels.end(), Rgb{52, 101, 164}), 100);
}

// mesh --organs: the organ names in the printed and JSON reports, the .msh
// physical names and the .vtu field data; labels the table lacks flagged.
TEST(NewUser, MeshNamesItsLabelsFromTheOrganTable) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = spheres(dir);
  std::ofstream(dir + "/organs.dat") << "ID  Organ  Tissue  Density\n1  Outer shell, left  1  1.05\n2  Middle \"core\"  2  1.92\n";
  // A missing organ table fails before any work, naming the file.
  expectOneLine(voxmorph("mesh " + test::quote(grid) + " -l 3 --organs " + test::quote(dir + "/absent.dat") + " -o " +
                         test::quote(dir + "/m.msh")),
                1, "absent.dat");
  const test::CommandResult r = voxmorph("mesh " + test::quote(grid) + " -l 3 -q --no-distance --organs " +
                                         test::quote(dir + "/organs.dat") + " -o " + test::quote(dir + "/m.msh") + " --report " +
                                         test::quote(dir + "/m.json"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("Outer shell, left"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("unnamed labels"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(unnamed)"), std::string::npos) << r.out;
  const nlohmann::json report = nlohmann::json::parse(test::readText(dir + "/m.json"));
  std::set<int> unnamed;
  for (const auto& l : report.at("labels")) {
    const int label = l.at("label");
    if (label == 1) EXPECT_EQ(l.at("name"), "Outer shell, left");
    else if (label == 2) EXPECT_EQ(l.at("name"), "Middle \"core\"");
    else {
      EXPECT_TRUE(l.at("name").is_null()) << label;
      unnamed.insert(label);
    }
  }
  EXPECT_FALSE(unnamed.empty());
  EXPECT_EQ(report.at("unnamed_labels").get<std::set<int>>(), unnamed);
  const std::string msh = test::readText(dir + "/m.msh");
  EXPECT_NE(msh.find("3 1 \"Outer shell, left\"\n3 2 \"Middle 'core'\"\n"), std::string::npos) << msh.substr(0, 300);
  // remesh keeps the names of its input, and .vtu carries them as field data.
  ASSERT_EQ(voxmorph("remesh " + test::quote(dir + "/m.msh") + " -l 3 -q --no-distance --iterations 1 -o " +
                     test::quote(dir + "/r.vtu"))
                .exitCode,
            0);
  const std::string vtu = test::readText(dir + "/r.vtu");
  EXPECT_NE(vtu.find("<FieldData>"), std::string::npos);
  // (the .msh held the name in one pair of double quotes, so its own became single quotes)
  EXPECT_NE(vtu.find("Name=\"Middle 'core'\" NumberOfTuples=\"2\" format=\"ascii\">2 3<"), std::string::npos)
      << vtu.substr(0, 600);
}

TEST(NewUser, RendersShowShapeFillTheFrameAndCarryALegendAndAScaleBar) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = spheres(dir, 48);
  const std::string base = "render " + test::quote(grid) + " --size 160x120 -q --cpu -o ";
  ASSERT_EQ(voxmorph(base + test::quote(dir + "/plain.png")).exitCode, 0);
  const RgbImage plain = readPng(dir + "/plain.png");
  // A sphere's faces seen head-on: the headlight, fill light and depth cue
  // give it many tones, not three flat ones.
  std::set<std::tuple<int, int, int>> tones;
  for (const Rgb& p : plain.pixels) tones.insert({p.r, p.g, p.b});
  EXPECT_GT(tones.size(), 12u);
  // The framing fits the foreground box's corners, not a sphere around the
  // box: the ball spans over 70 % of the rows (58 % with the sphere's fit).
  const Rgb background{22, 24, 29};
  int top = plain.height, bottom = -1;
  for (int y = 0; y < plain.height; ++y)
    for (int x = 0; x < plain.width; ++x)
      if (!(plain.at(x, y) == background)) {
        top = std::min(top, y);
        bottom = std::max(bottom, y);
      }
  EXPECT_GE(bottom - top + 1, int(0.7 * plain.height)) << top << " " << bottom;
  // Legend and scale bar: light text over the image, a bar at the bottom right.
  std::ofstream(dir + "/organs.dat") << "ID name tissue density\n1 Core 1 1.0\n2 Shell 1 1.0\n3 Skin 1 1.0\n";
  ASSERT_EQ(voxmorph(base + test::quote(dir + "/annotated.png") + " --legend --scale-bar --organs " + test::quote(dir + "/organs.dat")).exitCode, 0);
  const RgbImage annotated = readPng(dir + "/annotated.png");
  const Rgb text{235, 235, 235};
  std::size_t legendText = 0, barText = 0;
  for (int y = 0; y < annotated.height; ++y)
    for (int x = 0; x < annotated.width; ++x)
      if (annotated.at(x, y) == text) (x < annotated.width / 2 && y < annotated.height / 2 ? legendText : barText) += 1;
  EXPECT_GT(legendText, 40u);
  EXPECT_GT(barText, 60u);
}

}  // namespace
}  // namespace vox
