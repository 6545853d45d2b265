// Every report voxmorph writes carries its provenance (version, command
// line, SHA-256 of each input, checked against coreutils' sha256sum): deform,
// cage, mesh and remesh; --version names the build. Deform's body projection
// at rest and posed equals the silhouettes counted here, column by column,
// on the source and on the posed grid it wrote.

#include "geometry/io/grid_io.h"
#include "geometry/provenance.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <set>

namespace vox {
namespace {

std::string voxmorph(const std::string& args) { return test::quote(test::voxmorphBinary()) + " " + args; }

std::string sha256sum(const std::string& path) {
  const auto r = test::runCommand("sha256sum " + test::quote(path));
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return r.out.substr(0, 64);
}

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// role -> sha256 of the report's inputs.
std::map<std::string, std::string> digests(const nlohmann::json& report) {
  std::map<std::string, std::string> d;
  for (const auto& input : report.at("provenance").at("inputs")) d[input.at("role")] = input.at("sha256");
  return d;
}

// Silhouette areas of an axis-aligned RAS grid, counted directly: the
// distinct (x, z), (y, z) and (x, y) columns holding foreground.
struct Silhouettes {
  double front = 0, side = 0, top = 0, height = 0;
};
Silhouettes countSilhouettes(const LabelGrid& g) {
  std::set<std::pair<std::int64_t, std::int64_t>> xz, yz, xy;
  std::int64_t kLo = g.dims()[2], kHi = -1;
  for (std::int64_t k = 0; k < g.dims()[2]; ++k)
    for (std::int64_t j = 0; j < g.dims()[1]; ++j)
      for (std::int64_t i = 0; i < g.dims()[0]; ++i)
        if (g.at(i, j, k)) {
          xz.insert({i, k});
          yz.insert({j, k});
          xy.insert({i, j});
          kLo = std::min(kLo, k);
          kHi = std::max(kHi, k);
        }
  const Eigen::Vector3d& s = g.spacing();
  return {double(xz.size()) * s.x() * s.z(), double(yz.size()) * s.y() * s.z(), double(xy.size()) * s.x() * s.y(),
          double(kHi - kLo + 1) * s.z()};
}

void expectSilhouettes(const nlohmann::json& p, const LabelGrid& grid) {
  const Silhouettes s = countSilhouettes(grid);
  EXPECT_DOUBLE_EQ(p.at("front_area_mm2").get<double>(), s.front);
  EXPECT_DOUBLE_EQ(p.at("side_area_mm2").get<double>(), s.side);
  EXPECT_DOUBLE_EQ(p.at("top_area_mm2").get<double>(), s.top);
  EXPECT_DOUBLE_EQ(p.at("height_mm").get<double>(), s.height);
  EXPECT_TRUE(p.at("exact").get<bool>());
}

TEST(ReportProvenance, DeformRecordsItsInputsAndTheBodysSilhouettes) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = dir + "/stick.mhd", organs = dir + "/stick.dat", pose = dir + "/arm.json";
  ASSERT_EQ(test::runCommand(voxmorph("synth stick --size 48 -o " + test::quote(grid) + " --organs " + test::quote(organs))).exitCode, 0);
  std::ofstream(pose) << R"({"name": "right arm out", "selections": [
    {"box": {"min": [-1000, -1000, -1000], "max": [1000, 1000, 1000]}, "fixed": true},
    {"box": {"min": [-1000, -1000, 40], "max": [10, 1000, 80]}, "group": "right_arm",
     "transform": {"rotation": {"axis": [0, 1, 0], "angle_deg": 30, "center": [12, 14, 80]}}}],
    "separations": [{"groups": ["right_arm", "trunk"]}]})";
  const std::string args = "deform " + test::quote(grid) + " --organs " + test::quote(organs) + " --pose " + test::quote(pose) + " -o " +
                           test::quote(dir + "/posed.nii.gz") + " --report " + test::quote(dir + "/r.json") + " --force -q";
  const auto r = test::runCommand(voxmorph(args));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const nlohmann::json report = readJson(dir + "/r.json");
  const nlohmann::json& p = report.at("provenance");
  EXPECT_EQ(p.at("voxmorph_version"), voxmorphVersion());
  // The recorded line, run through the shell, gives the arguments it ran with.
  const auto words = [](const std::string& line) { return test::runCommand("printf '%s\\n' " + line).out; };
  EXPECT_EQ(words(p.at("command_line").get<std::string>()), words(voxmorph(args)));
  const auto d = digests(report);
  EXPECT_EQ(d.at("grid"), sha256sum(grid));
  EXPECT_EQ(d.at("grid data"), sha256sum(dir + "/stick.raw"));
  EXPECT_EQ(d.at("organs"), sha256sum(organs));
  EXPECT_EQ(d.at("pose"), sha256sum(pose));

  const nlohmann::json& projection = report.at("body_projection");
  expectSilhouettes(projection.at("rest"), readGrid(grid));
  expectSilhouettes(projection.at("posed"), readGrid(dir + "/posed.nii.gz"));
  // The arm swung out from the side widens the body seen from above.
  EXPECT_GT(projection["posed"]["top_area_mm2"].get<double>(), projection["rest"]["top_area_mm2"].get<double>());
}

TEST(ReportProvenance, CageMeshAndRemeshReportsCarryIt) {
  VOX_REQUIRE_VOXMORPH();
  const std::string dir = test::tempDir();
  const std::string grid = dir + "/s.nii.gz";
  ASSERT_EQ(test::runCommand(voxmorph("synth spheres --size 16 -o " + test::quote(grid))).exitCode, 0);
  const auto cage = test::runCommand(voxmorph("cage " + test::quote(grid) + " -o " + test::quote(dir + "/c.obj") + " --report " +
                                              test::quote(dir + "/c.json") + " -q"));
  ASSERT_EQ(cage.exitCode, 0) << cage.err;
  EXPECT_EQ(digests(readJson(dir + "/c.json")).at("grid"), sha256sum(grid));
  const auto mesh = test::runCommand(voxmorph("mesh " + test::quote(grid) + " -l 4 -o " + test::quote(dir + "/m.mesh") + " --report " +
                                              test::quote(dir + "/m.json") + " -q"));
  ASSERT_EQ(mesh.exitCode, 0) << mesh.err;
  EXPECT_EQ(digests(readJson(dir + "/m.json")).at("grid"), sha256sum(grid));
  const auto remesh = test::runCommand(voxmorph("remesh " + test::quote(dir + "/m.mesh") + " -l 5 -o " + test::quote(dir + "/r.mesh") +
                                                " --report " + test::quote(dir + "/r.json") + " -q"));
  ASSERT_EQ(remesh.exitCode, 0) << remesh.err;
  const nlohmann::json r = readJson(dir + "/r.json");
  EXPECT_EQ(digests(r).at("mesh"), sha256sum(dir + "/m.mesh"));
  EXPECT_NE(r["provenance"]["command_line"].get<std::string>().find(" remesh "), std::string::npos);
}

TEST(ReportProvenance, VersionNamesTheBuild) {
  VOX_REQUIRE_VOXMORPH();
  const auto r = test::runCommand(voxmorph("--version"));
  EXPECT_EQ(r.exitCode, 0);
  EXPECT_EQ(r.out, voxmorphVersionLine() + "\n");
  EXPECT_EQ(r.out.rfind("voxmorph " + voxmorphVersion(), 0), 0u) << r.out;
}

}  // namespace
}  // namespace vox
