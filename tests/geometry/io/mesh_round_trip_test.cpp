#include "geometry/io/mesh_io.h"
#include "tests/geometry/io/mesh_test_meshes.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>

namespace vox {
namespace {

using test::expectSameMesh;
using test::labeledMesh;
using test::readText;
using test::tempDir;
using test::writeText;

class MeshRoundTrip : public ::testing::TestWithParam<const char*> {};

TEST_P(MeshRoundTrip, PositionsTetsAndLabelsExact) {
  const std::string dir = tempDir();
  const std::string path = dir + "/labeled" + GetParam();
  const TetMesh mesh = labeledMesh();
  writeTetMesh(path, mesh);
  // Atomic write: the target and nothing else (no temporary left behind).
  EXPECT_EQ(test::listFiles(dir), "labeled" + std::string(GetParam()) + "\n");
  expectSameMesh(mesh, readTetMesh(path));
}

TEST_P(MeshRoundTrip, FailedWriteKeepsThePreviousFile) {
  const std::string dir = tempDir();
  const std::string path = dir + "/mesh" + std::string(GetParam());
  const TetMesh mesh = labeledMesh();
  writeTetMesh(path, mesh);
  const std::string before = readText(path);
  TetMesh broken = mesh;
  broken.tets.back()[2] = std::int32_t(mesh.vertexCount());
  EXPECT_THROW(writeTetMesh(path, broken), InputError);
  EXPECT_EQ(readText(path), before);
  EXPECT_EQ(test::listFiles(dir), "mesh" + std::string(GetParam()) + "\n");
}

// Label names travel in .vtu (field data) and .msh (physical names); Medit
// files have no place for them.
TEST_P(MeshRoundTrip, LabelNames) {
  const std::string path = tempDir() + "/named" + GetParam();
  const TetMesh mesh = test::namedMesh();
  writeTetMesh(path, mesh);
  const TetMesh back = readTetMesh(path);
  expectSameMesh(mesh, back);
  const std::string format = GetParam();
  if (format == ".mesh" || format == ".meshb") {
    EXPECT_TRUE(back.labelNames.empty());
    return;
  }
  std::map<std::int32_t, std::string> expected = mesh.labelNames;
  if (format == ".msh") expected[2] = "Brain <grey> & 'white'";  // one quoted string per name
  EXPECT_EQ(back.labelNames, expected);
  // Names of labels the mesh does not hold are not kept; unnamed labels stay unnamed.
  TetMesh fewer = mesh;
  fewer.labelNames[99] = "Not in the mesh";
  writeTetMesh(path, fewer);
  EXPECT_EQ(readTetMesh(path).labelNames.count(99), 0u);
  EXPECT_EQ(readTetMesh(path).labelNames.count(4), 0u);
}

INSTANTIATE_TEST_SUITE_P(Formats, MeshRoundTrip, ::testing::Values(".mesh", ".meshb", ".vtu", ".msh"),
                         [](const auto& info) { return std::string(info.param + 1); });

TEST(MeshFormat, ExtensionDispatch) {
  EXPECT_EQ(meshFormatFromPath("a/b.MESH"), MeshFormat::Medit);
  EXPECT_EQ(meshFormatFromPath("b.meshb"), MeshFormat::Medit);
  EXPECT_EQ(meshFormatFromPath("b.vtu"), MeshFormat::Vtu);
  EXPECT_EQ(meshFormatFromPath("b.msh"), MeshFormat::Gmsh);
  EXPECT_TRUE(hasTetMeshExtension("x.Msh"));
  EXPECT_FALSE(hasTetMeshExtension("x.stl"));
  test::expectInputError([] { readTetMesh("mesh.stl"); }, "mesh.stl", "unknown mesh format");
}

TEST(MeshFormat, MeditSkipsBlocksItDoesNotUse) {
  const std::string path = tempDir() + "/extras.mesh";
  writeText(path,
            "# written by hand\nMeshVersionFormatted 1\n\nDimension\n3\n"
            "Vertices\n5\n0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n1 1 1 2 # trailing comment\n"
            "Edges 1\n1 2 0\nTriangles\n2\n1 2 3 7\n2 3 4 7\nCorners 2\n1 2\nRidges\n1\n1\n"
            "RequiredVertices 1\n3\nTetrahedra\n2\n1 2 3 4 11\n2 3 4 5 -1\nNormals 1\n0 0 1\n"
            "SomeFutureKeyword 2\n1 2 3\n4 5 6\nEnd\n");
  const TetMesh mesh = readMedit(path);
  ASSERT_EQ(mesh.vertexCount(), 5u);
  EXPECT_EQ(mesh.positions[4], Eigen::Vector3d(1, 1, 1));
  ASSERT_EQ(mesh.tetCount(), 2u);
  EXPECT_EQ(mesh.tets[1], (Tet{1, 2, 3, 4}));
  EXPECT_EQ(mesh.labels, (std::vector<std::int32_t>{11, -1}));
}

TEST(MeshFormat, MeditWritesVersionTwoAndOneBasedIndices) {
  const std::string path = tempDir() + "/small.mesh";
  TetMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.1, 0.2, 1e-300}};
  mesh.tets = {{0, 1, 2, 3}};
  mesh.labels = {42};
  writeMedit(path, mesh);
  const std::string text = readText(path);
  EXPECT_EQ(text.rfind("MeshVersionFormatted 2\nDimension 3\n", 0), 0u) << text;
  EXPECT_NE(text.find("0.1 0.2 1e-300 0\n"), std::string::npos) << text;
  EXPECT_NE(text.find("Tetrahedra\n1\n1 2 3 4 42\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\nEnd\n"), std::string::npos);
}

TEST(MeshFormat, VtuAsciiPiecesAndLabelFallbacks) {
  // Two pieces; the second one's indices are piece-local. Cells that are not
  // VTK_TETRA (a triangle, type 5) are dropped. Labels from "medit:ref"
  // (no "label" array), then from the first integer array.
  const std::string path = tempDir() + "/pieces.vtu";
  const std::string piece1 =
      "<Piece NumberOfPoints=\"5\" NumberOfCells=\"3\"><Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" "
      "format=\"ascii\">0 0 0 1 0 0 0 1 0 0 0 1 0.5 0.5 0.5</DataArray></Points><Cells>"
      "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3 0 1 2 1 2 3 4</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4 7 11</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10 5 10</DataArray></Cells>"
      "<CellData><DataArray type=\"Float64\" Name=\"quality\" format=\"ascii\">1 2 3</DataArray>"
      "<DataArray type=\"Int64\" Name=\"medit:ref\" format=\"ascii\">7 8 9</DataArray></CellData></Piece>";
  const std::string piece2 =
      "<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\"><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" "
      "format=\"ascii\">10 0 0 11 0 0 10 1 0 10 0 1</DataArray></Points><Cells>"
      "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>"
      "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
      "<DataArray type=\"Int64\" Name=\"types\" format=\"ascii\">10</DataArray></Cells>"
      "<CellData><DataArray type=\"UInt16\" Name=\"region\" format=\"ascii\">3</DataArray></CellData></Piece>";
  writeText(path, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\">\n<UnstructuredGrid>" +
                      piece1 + piece2 + "</UnstructuredGrid></VTKFile>\n");
  const TetMesh mesh = readVtu(path);
  ASSERT_EQ(mesh.vertexCount(), 9u);
  EXPECT_EQ(mesh.positions[4], Eigen::Vector3d(0.5, 0.5, 0.5));
  EXPECT_EQ(mesh.positions[6], Eigen::Vector3d(11, 0, 0));
  ASSERT_EQ(mesh.tetCount(), 3u);
  EXPECT_EQ(mesh.tets[0], (Tet{0, 1, 2, 3}));
  EXPECT_EQ(mesh.tets[1], (Tet{1, 2, 3, 4}));
  EXPECT_EQ(mesh.tets[2], (Tet{5, 6, 7, 8}));
  EXPECT_EQ(mesh.labels, (std::vector<std::int32_t>{7, 9, 3}));
}

TEST(MeshFormat, VtuWritesAppendedRawData) {
  const std::string path = tempDir() + "/raw.vtu";
  writeVtu(path, labeledMesh());
  const std::string text = readText(path);
  EXPECT_NE(text.find("<AppendedData encoding=\"raw\">"), std::string::npos);
  EXPECT_NE(text.find("header_type=\"UInt64\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"label\""), std::string::npos);
  // Points (24 bytes each), connectivity (16), offsets (8), types (1) and
  // labels (4) with a UInt64 byte count each: nothing else is appended.
  const TetMesh mesh = labeledMesh();
  const std::size_t data = text.find('_', text.find("<AppendedData")) + 1;
  const std::size_t close = text.rfind("\n  </AppendedData>");
  EXPECT_EQ(close - data, 5 * 8 + 24 * mesh.vertexCount() + (16 + 8 + 1 + 4) * mesh.tetCount());
}

TEST(MeshFormat, GmshWritesOnePhysicalGroupPerLabel) {
  const std::string path = tempDir() + "/groups.msh";
  writeGmsh(path, test::junctionSphereMesh());
  const std::string text = readText(path);
  EXPECT_EQ(text.rfind("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n6\n", 0), 0u);
  for (int l = 0; l <= 5; ++l)
    EXPECT_NE(text.find("3 " + std::to_string(l) + " \"label_" + std::to_string(l) + "\"\n"), std::string::npos) << l;
  EXPECT_NE(text.find("$Entities\n0 0 0 6\n"), std::string::npos);
}

// A binary MSH 4.1 file built value by value: sparse and unordered node tags,
// a triangle block to skip, an entity with a physical tag and one without,
// element tags out of order.
std::string binaryMsh() {
  std::string b = "$MeshFormat\n4.1 1 8\n";
  auto put = [&b](const auto& v) { b.append(reinterpret_cast<const char*>(&v), sizeof(v)); };
  auto size = [&put](std::uint64_t v) { put(v); };
  auto i32 = [&put](std::int32_t v) { put(v); };
  i32(1);
  b += "\n$EndMeshFormat\n$Entities\n";
  size(0), size(0), size(1), size(2);
  i32(4);  // surface 4: bounding box, no physical, no bounding curves
  for (int k = 0; k < 6; ++k) put(0.0);
  size(0), size(0);
  i32(1);  // volume 1: physical 17 and 3 (the first wins), bounded by surface 4
  for (int k = 0; k < 6; ++k) put(0.0);
  size(2), i32(17), i32(3), size(1), i32(4);
  i32(2);  // volume 2: no physical tag
  for (int k = 0; k < 6; ++k) put(0.0);
  size(0), size(0);
  b += "\n$EndEntities\n$Nodes\n";
  size(2), size(5), size(10), size(50);
  i32(3), i32(1), i32(0), size(3);
  size(50), size(10), size(30);
  for (double x : {0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0}) put(x);  // nodes 50, 10, 30
  i32(3), i32(2), i32(0), size(2);
  size(20), size(40);
  for (double x : {0.0, 1.0, 0.0, 0.25, 0.5, 0.75}) put(x);  // nodes 20, 40
  b += "\n$EndNodes\n$Elements\n";
  size(3), size(4), size(1), size(9);
  i32(2), i32(4), i32(2), size(1);  // one triangle on surface 4
  size(1), size(10), size(20), size(30);
  i32(3), i32(2), i32(4), size(1);  // tet with tag 9 on volume 2
  size(9), size(20), size(30), size(40), size(50);
  i32(3), i32(1), i32(4), size(2);  // tets with tags 5 and 3 on volume 1
  size(5), size(10), size(20), size(30), size(50);
  size(3), size(10), size(20), size(40), size(30);
  b += "\n$EndElements\n$Comments\nanything\n$EndComments\n";
  return b;
}

TEST(MeshFormat, GmshBinaryEntitiesAndTags) {
  const std::string path = tempDir() + "/hand.msh";
  writeText(path, binaryMsh());
  const TetMesh mesh = readGmsh(path);
  // Vertices in ascending tag order: 10, 20, 30, 40, 50.
  ASSERT_EQ(mesh.vertexCount(), 5u);
  EXPECT_EQ(mesh.positions[0], Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(mesh.positions[3], Eigen::Vector3d(0.25, 0.5, 0.75));
  EXPECT_EQ(mesh.positions[4], Eigen::Vector3d(0, 0, 1));
  // Tets in ascending element tag order: 3, 5, 9.
  ASSERT_EQ(mesh.tetCount(), 3u);
  EXPECT_EQ(mesh.tets[0], (Tet{0, 1, 3, 2}));
  EXPECT_EQ(mesh.tets[1], (Tet{0, 1, 2, 4}));
  EXPECT_EQ(mesh.tets[2], (Tet{1, 2, 3, 4}));
  EXPECT_EQ(mesh.labels, (std::vector<std::int32_t>{17, 17, 2}));
}

}  // namespace
}  // namespace vox
