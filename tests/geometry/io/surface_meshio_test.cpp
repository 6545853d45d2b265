// Surfaces against python3-meshio: it reads our OBJ, OFF and PLY files, and
// we read the ones it writes, coordinates compared bit for bit.
#include "geometry/io/mesh_io.h"
#include "tests/geometry/io/mesh_test_meshes.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

namespace vox {
namespace {

constexpr const char* kRead = R"(
import sys
import meshio
m = meshio.read(sys.argv[1])
print(" ".join(float(x).hex() for x in m.points.ravel()))
print(" ".join(map(str, m.cells_dict["triangle"].ravel().tolist())))
)";

constexpr const char* kWrite = R"(
import sys
import meshio
m = meshio.read(sys.argv[1])
m = meshio.Mesh(m.points, [("triangle", m.cells_dict["triangle"])])
out = sys.argv[2]
meshio.write(out + "/meshio.obj", m)
meshio.write(out + "/meshio.off", m)
meshio.write(out + "/binary.ply", m, binary=True)
meshio.write(out + "/ascii.ply", m, binary=False)
print("ok")
)";

// A sphere-like surface: an octahedron refined once (32 triangles) with
// coordinates that need 17 digits.
TriMesh surface() {
  TriMesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<Tri> coarse = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (const Tri& t : coarse) {
    std::int32_t mid[3];
    for (int k = 0; k < 3; ++k) {
      mid[k] = std::int32_t(m.positions.size());
      m.positions.push_back((m.positions[t[k]] + m.positions[t[(k + 1) % 3]]).normalized());
    }
    m.triangles.push_back({t[0], mid[0], mid[2]});
    m.triangles.push_back({mid[0], t[1], mid[1]});
    m.triangles.push_back({mid[2], mid[1], t[2]});
    m.triangles.push_back({mid[0], mid[1], mid[2]});
  }
  for (Eigen::Vector3d& p : m.positions) p = p * std::sqrt(2.0) + Eigen::Vector3d(0.1, 0.2, 0.3);
  return m;
}

std::string runPython(const std::string& dir, const std::string& script, const std::vector<std::string>& args) {
  const std::string file = dir + "/script.py";
  test::writeText(file, script);
  std::string cmd = test::quote(test::python()) + " " + test::quote(file);
  for (const std::string& a : args) cmd += " " + test::quote(a);
  const test::CommandResult r = test::runCommand(cmd);
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return r.out;
}

class MeshioReadsOurSurface : public ::testing::TestWithParam<const char*> {};

TEST_P(MeshioReadsOurSurface, PointsAndTriangles) {
  if (test::python().empty()) GTEST_SKIP() << "python3 not found";
  const std::string dir = test::tempDir();
  const std::string path = dir + "/ours" + GetParam();
  const TriMesh mesh = surface();
  writeSurface(path, mesh);
  std::istringstream out(runPython(dir, kRead, {path}));
  std::string line;
  std::getline(out, line);
  std::istringstream points(line);
  std::vector<Eigen::Vector3d> positions;
  for (std::string x, y, z; points >> x >> y >> z;)
    positions.emplace_back(std::strtod(x.c_str(), nullptr), std::strtod(y.c_str(), nullptr), std::strtod(z.c_str(), nullptr));
  std::getline(out, line);
  std::istringstream indices(line);
  std::vector<Tri> triangles;
  for (Tri t; indices >> t[0] >> t[1] >> t[2];) triangles.push_back(t);
  EXPECT_EQ(positions, mesh.positions);
  EXPECT_EQ(triangles, mesh.triangles);
}

INSTANTIATE_TEST_SUITE_P(Formats, MeshioReadsOurSurface, ::testing::Values(".obj", ".off", ".ply"),
                         [](const auto& info) { return std::string(info.param + 1); });

TEST(MeshioWritesWeReadSurface, ObjOffPly) {
  if (test::python().empty()) GTEST_SKIP() << "python3 not found";
  const std::string dir = test::tempDir();
  const TriMesh mesh = surface();
  writeSurface(dir + "/source.off", mesh);
  ASSERT_EQ(runPython(dir, kWrite, {dir + "/source.off", dir}), "ok\n");
  for (const char* name : {"meshio.obj", "meshio.off", "binary.ply", "ascii.ply"}) {
    SCOPED_TRACE(name);
    const TriMesh back = readSurface(dir + "/" + name);
    EXPECT_EQ(back.positions, mesh.positions);
    EXPECT_EQ(back.triangles, mesh.triangles);
  }
  EXPECT_NE(test::readText(dir + "/binary.ply").find("format binary_little_endian 1.0\n"), std::string::npos);
}

}  // namespace
}  // namespace vox
