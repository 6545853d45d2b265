#include "geometry/io/mesh_io.h"
#include "tests/geometry/io/mesh_test_meshes.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cmath>
#include <random>

namespace vox {
namespace {

using test::expectInputError;
using test::writeText;

// A closed surface (octahedron) with coordinates that need 17 digits.
TriMesh octahedron() {
  TriMesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (std::size_t v = 0; v < m.positions.size(); ++v) m.positions[v] = m.positions[v] * 0.1 + Eigen::Vector3d::Constant(std::sqrt(double(v + 2)));
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

class SurfaceRoundTrip : public ::testing::TestWithParam<const char*> {};

TEST_P(SurfaceRoundTrip, Exact) {
  const std::string dir = test::tempDir();
  const std::string path = dir + "/cage" + GetParam();
  const TriMesh mesh = octahedron();
  EXPECT_TRUE(hasSurfaceExtension(path));
  writeSurface(path, mesh);
  EXPECT_EQ(test::listFiles(dir), "cage" + std::string(GetParam()) + "\n");
  const TriMesh back = readSurface(path);
  EXPECT_EQ(back.positions, mesh.positions);
  EXPECT_EQ(back.triangles, mesh.triangles);
}

INSTANTIATE_TEST_SUITE_P(Formats, SurfaceRoundTrip, ::testing::Values(".obj", ".off", ".ply", ".OBJ"),
                         [](const auto& info) { return std::string(info.param + 1); });

TEST(SurfaceFormats, ObjCornerFormsNegativeIndicesAndPolygons) {
  const std::string path = test::tempDir() + "/poly.obj";
  writeText(path,
            "# square and a triangle\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0 1.0\nv 1 1 0 0.5 0.5 0.5\nv 0 1 0\n"
            "vt 0 0\nvn 0 0 1\ng faces\nusemtl red\ns off\nf 1/1/1 2/1/1 3//1 4/1\nv 2 2 2\nf -1 -4 -3\nl 1 2\n");
  const TriMesh m = readSurface(path);
  ASSERT_EQ(m.vertexCount(), 5u);
  EXPECT_EQ(m.positions[1], Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(m.positions[2], Eigen::Vector3d(1, 1, 0));
  // The quad becomes the fan (0,1,2), (0,2,3); -1 is the latest vertex.
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {4, 1, 2}}));
}

TEST(SurfaceFormats, OffVariants) {
  const std::string path = test::tempDir() + "/poly.off";
  writeText(path, "COFF\n# comment\n5 2 0\n0 0 0 255 0 0 255\n1 0 0 255 0 0 255\n\n1 1 0 0 0 0 0\n0 1 0 1 1 1 1\n2 2 2 0 0 0 0\n"
                  "4 0 1 2 3 255 0 0\n3 4 1 2 # trailing comment\n");
  const TriMesh m = readSurface(path);
  ASSERT_EQ(m.vertexCount(), 5u);
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {4, 1, 2}}));
}

void expectBad(const std::string& name, const std::string& text, const std::string& fault) {
  SCOPED_TRACE(name);
  const std::string path = test::tempDir() + "/" + name;
  writeText(path, text);
  expectInputError([&] { readSurface(path); }, path, fault);
}

TEST(SurfaceFormats, BadInput) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  expectBad("o1.obj", "", "no faces");
  expectBad("o2.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces");
  expectBad("o3.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4: face references vertex 0");
  expectBad("o4.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4: face references vertex 4 (3 vertices defined so far)");
  expectBad("o5.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", "line 4: face references vertex -4");
  expectBad("o6.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\n", "line 4: face repeats vertex 2");
  expectBad("o7.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "line 3: face has 2 vertices");
  expectBad("o8.obj", "v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "line 1: y coordinate is not finite");
  expectBad("o9.obj", "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "line 1: expected z coordinate, found nothing");
  expectBad("o10.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "line 4: expected a vertex index, found 'x'");
  expectBad("o11.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n", "line 4: expected a vertex index");
  const std::string off = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  expectBad("f1.off", "", "not an OFF file");
  expectBad("f2.off", "ply\nformat ascii 1.0\n", "line 1: not an OFF file: expected OFF, found 'ply'");
  expectBad("f3.off", "OFF BINARY\n3 1 0\n", "binary OFF is not supported");
  expectBad("f4.off", "OFF\n99999999999 1 0\n0 0 0\n", "line 2: vertex count 99999999999 is more than the rest of the file can hold");
  expectBad("f5.off", "OFF\n3 99999999999 0\n0 0 0\n", "face count 99999999999 is more");
  expectBad("f6.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "line 6: face references vertex 3 (indices are 0-based");
  expectBad("f7.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 1\n", "line 6: face repeats vertex 1");
  expectBad("f8.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n", "line 4: y coordinate is not finite");
  expectBad("f9.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n\n\n\n\n\n\n\n\n", "file ends after 1 of 2 faces");
  expectBad("f10.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "face vertex count 2 is invalid");
  expectBad("f11.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "no faces");
  expectBad("f12.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1\n3 0 1 2\n", "line 5: expected z coordinate, found nothing");
  const std::string ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                          "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  auto edited = [](std::string text, const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  };
  expectBad("p1.ply", "", "not a PLY file");
  expectBad("p2.ply", edited(ply, "ply\n", "PLY\n"), "line 1: not a PLY file: expected 'ply', found 'PLY'");
  expectBad("p3.ply", ply.substr(0, ply.find("end_header")), "no end_header line");
  expectBad("p3b.ply", edited(ply, "end_header\n", ""), "line 9: unknown header line starting with '0'");
  expectBad("p4.ply", edited(ply, "ascii", "binary_middle_endian"), "line 2: unknown PLY format 'binary_middle_endian'");
  expectBad("p5.ply", edited(ply, "vertex 3", "vertex 99999999999"), "line 3: element vertex count 99999999999 is more than the rest of the file can hold");
  expectBad("p6.ply", edited(ply, "1 0 0\n", "1 nan 0\n"), "line 11: vertex 1 has a non-finite coordinate");
  expectBad("p7.ply", edited(ply, "3 0 1 2", "3 0 1 3"), "face 0 references vertex 3");
  expectBad("p8.ply", edited(ply, "3 0 1 2", "3 0 1 1"), "face 0 repeats vertex 1");
  expectBad("p9.ply", edited(ply, "3 0 1 2", "2 0 1"), "face 0 has 2 vertices");
  expectBad("p10.ply", edited(ply, "property float z\n", ""), "line 3: vertex element lacks an x, y or z property");
  expectBad("p11.ply", edited(ply, "float y", "quad y"), "line 5: unknown property type 'quad'");
  expectBad("p12.ply", edited(ply, "3 0 1 2\n", "3 0 1"), "expected vertex index, found nothing");
  expectBad("p16.ply", edited(ply, "3 0 1 2", "3 0 0.5 2"), "line 13: face 0 has vertex index 0.5, not an integer");
  expectBad("p17.ply", edited(ply, "3 0 1 2", "3 0 1 1e30"), "face 0 references vertex 1e+30 (the file has 3 vertices)");
  expectBad("p13.ply", edited(ply, "list uchar int vertex_indices", "list uchar int corners"), "face element lacks a vertex_indices list");
  {
    // Binary: a list length larger than the rest of the file.
    const std::string dir = test::tempDir();
    writeSurface(dir + "/good.ply", octahedron());
    std::string b = test::readText(dir + "/good.ply");
    b[b.size() - 13] = char(200);
    expectBad("p14.ply", b, "has length 200");
    expectBad("p15.ply", b.substr(0, b.size() - 5), "truncated");
  }
  expectBad("s.stl", tri, "unknown surface format");
  // Writing refuses a broken surface and leaves nothing behind.
  const std::string dir = test::tempDir();
  TriMesh broken = octahedron();
  broken.triangles[3][1] = 6;
  expectInputError([&] { writeSurface(dir + "/b.obj", broken); }, dir + "/b.obj", "triangle 3 references vertex 6");
  EXPECT_EQ(test::listFiles(dir), "");
}

// One face listing every vertex of a 200,000-gon: read in time linear in the
// face's size (a check of repeated vertices by pairs took minutes).
TEST(SurfaceFormats, LargeFacesReadInLinearTime) {
  constexpr int n = 200000;
  std::string obj, offVertices, plyVertices, objFace = "f", offFace = std::to_string(n), plyFace = std::to_string(n);
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    const std::string v = std::to_string(std::cos(a)) + " " + std::to_string(std::sin(a)) + " 0\n";
    obj += "v " + v;
    offVertices += v;
    objFace += " " + std::to_string(i + 1);
    offFace += " " + std::to_string(i);
  }
  plyFace = offFace;
  const std::string dir = test::tempDir();
  writeText(dir + "/big.obj", obj + objFace + "\n");
  writeText(dir + "/big.off", "OFF\n" + std::to_string(n) + " 1 0\n" + offVertices + offFace + "\n");
  writeText(dir + "/big.ply", "ply\nformat ascii 1.0\nelement vertex " + std::to_string(n) +
                                  "\nproperty double x\nproperty double y\nproperty double z\nelement face 1\n"
                                  "property list int int vertex_indices\nend_header\n" + offVertices + plyFace + "\n");
  for (const char* name : {"big.obj", "big.off", "big.ply"}) {
    SCOPED_TRACE(name);
    const auto start = std::chrono::steady_clock::now();
    const TriMesh m = readSurface(dir + "/" + name);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(m.faceCount(), std::size_t(n - 2));
    // About 0.2 s here (1 s under sanitizers); the pairwise check took 30 s.
    EXPECT_LT(seconds, 5.0);
  }
  // A repeat far apart in the face is still found.
  writeText(dir + "/repeat.obj", obj + objFace + " 7\n");
  expectInputError([&] { readSurface(dir + "/repeat.obj"); }, dir + "/repeat.obj", "face repeats vertex 7");
}

// An element of no properties declaring 5.6e17 records (fuzz_ply, 2026-11-25:
// skipping them one by one ran past libFuzzer's 20 s timeout): its records
// take no bytes, so the mesh after it reads at once.
TEST(SurfaceFormats, PlyElementWithoutPropertiesIsSkippedAtOnce) {
  const std::string dir = test::tempDir();
  for (const char* format : {"ascii", "binary_little_endian"}) {
    SCOPED_TRACE(format);
    std::string ply = std::string("ply\nformat ") + format +
                      " 1.0\nelement junk 555555555555555555\nelement vertex 3\n"
                      "property float x\nproperty float y\nproperty float z\nelement face 1\n"
                      "property list uchar int vertex_indices\nend_header\n";
    if (std::string(format) == "ascii") {
      ply += "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    } else {
      const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
      ply.append(reinterpret_cast<const char*>(v), sizeof v);
      const std::int32_t f[3] = {0, 1, 2};
      ply += char(3);
      ply.append(reinterpret_cast<const char*>(f), sizeof f);
    }
    writeText(dir + "/empty_element.ply", ply);
    const auto start = std::chrono::steady_clock::now();
    const TriMesh m = readSurface(dir + "/empty_element.ply");
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
    EXPECT_EQ(m.faceCount(), 1u);
  }
}

// Every prefix and random corruptions of small valid files: an InputError or
// a surface that validates, nothing else (no crash, no other exception).
TEST(SurfaceFormats, TruncatedAndCorruptFiles) {
  const std::string dir = test::tempDir();
  const TriMesh mesh = octahedron();
  std::mt19937 random(777);
  for (const char* name : {"s.obj", "s.off", "s.ply"}) {
    SCOPED_TRACE(name);
    writeSurface(dir + "/w" + name, mesh);
    const std::string text = test::readText(dir + "/w" + name);
    test::MemoryFile file(dir, name);
    std::size_t failures = 0;
    for (std::size_t n = 0; n < text.size(); ++n) {
      try {
        const TriMesh m = readSurface(file.set(text.substr(0, n)));
        m.validate(name);
        EXPECT_LE(m.faceCount(), mesh.faceCount());
      } catch (const InputError&) {
        ++failures;
      }
    }
    // OBJ has no counts: a cut between lines loses faces silently.
    EXPECT_GT(failures, text.size() / 3);
    for (int trial = 0; trial < 300; ++trial) {
      std::string bad = text;
      for (int e = 0; e < 1 + int(random() % 3); ++e) bad[random() % bad.size()] = char(random() % 256);
      try {
        readSurface(file.set(bad)).validate(name);
      } catch (const InputError&) {
      }
    }
  }
}

}  // namespace
}  // namespace vox
