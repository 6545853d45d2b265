// Corrupt, truncated and hostile tet mesh files: every reader answers with an
// InputError naming the file and the fault, never a crash, a huge allocation
// or a half-read mesh.
#include "geometry/io/mesh_io.h"
#include "tests/geometry/io/mesh_test_meshes.h"
#include "tests/geometry/io/mesh_vtu_builder.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

namespace vox {
namespace {

using test::expectInputError;
using test::writeText;

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// Writes `text` to a fresh file and expects `read` of it to fail with `fault`.
void expectBad(TetMesh (*read)(const std::string&), const std::string& name, const std::string& text, const std::string& fault) {
  SCOPED_TRACE(name);
  const std::string path = test::tempDir() + "/" + name;
  writeText(path, text);
  expectInputError([&] { read(path); }, path, fault);
}

TetMesh twoTets() {
  TetMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  m.tets = {{0, 1, 2, 3}, {1, 2, 3, 4}};
  m.labels = {7, 8};
  return m;
}

const std::string kMedit =
    "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"
    "Tetrahedra\n1\n1 2 3 4 7\nEnd\n";

TEST(MeshBadInput, Medit) {
  const auto read = &readMedit;
  expectBad(read, "m1.mesh", "", "expected MeshVersionFormatted");
  expectBad(read, "m2.mesh", "solid cube\nfacet normal 0 0 1\n", "not a Medit mesh");
  expectBad(read, "m3.mesh", replaced(kMedit, "Version", "Versoin"), "not a Medit mesh");
  expectBad(read, "m4.mesh", replaced(kMedit, "Formatted 2", "Formatted 7"), "MeshVersionFormatted 7");
  expectBad(read, "m5.mesh", replaced(kMedit, "Dimension 3", "Dimension 2"), "line 2: Dimension 2 is not supported");
  expectBad(read, "m6.mesh", replaced(kMedit, "Vertices\n4", "Vertices\n99999999999"),
            "line 4: vertex count 99999999999 is more than the rest of the file can hold");
  expectBad(read, "m7.mesh", replaced(kMedit, "Vertices\n4", "Vertices\n99999999999999999999999"), "line 4: vertex count");
  expectBad(read, "m8.mesh", replaced(kMedit, "Vertices\n4", "Vertices\n-4"), "vertex count -4 is negative");
  expectBad(read, "m9.mesh", replaced(kMedit, "Tetrahedra\n1", "Tetrahedra\n4000000000"), "tetrahedron count 4000000000 is more");
  expectBad(read, "m10.mesh", replaced(kMedit, "1 0 0 0\n", "nan 0 0 0\n"), "line 6: x coordinate is not finite");
  expectBad(read, "m11.mesh", replaced(kMedit, "0 1 0 0\n", "0 inf 0 0\n"), "line 7: y coordinate is not finite");
  expectBad(read, "m12.mesh", replaced(kMedit, "0 0 1 0\n", "0 0 1e999 0\n"), "line 8: z coordinate '1e999' is out of the double range");
  expectBad(read, "m13.mesh", replaced(kMedit, "0 0 1 0\n", "0 0 x 0\n"), "line 8: expected z coordinate, found 'x'");
  expectBad(read, "m14.mesh", replaced(kMedit, "1 2 3 4 7", "0 2 3 4 7"), "line 11: tetrahedron 1 references vertex 0 (indices are 1-based");
  expectBad(read, "m15.mesh", replaced(kMedit, "1 2 3 4 7", "1 2 3 5 7"), "line 11: tetrahedron 1 references vertex 5");
  expectBad(read, "m16.mesh", replaced(kMedit, "1 2 3 4 7", "1 2 3 2 7"), "line 11: tetrahedron 1 repeats vertex 2");
  expectBad(read, "m17.mesh", replaced(kMedit, "1 2 3 4 7", "1 2 3 4 3000000000"), "does not fit a 32-bit label");
  expectBad(read, "m18.mesh", kMedit.substr(0, kMedit.find("3 4 7")), "line 10: tetrahedron count 1 is more than the rest of the file can hold");
  expectBad(read, "m19.mesh", kMedit.substr(0, kMedit.find("0 1 0 0")), "line 4: vertex count 4 is more than the rest of the file can hold");
  expectBad(read, "m19b.mesh", replaced(kMedit, "1 2 3 4 7\nEnd\n", "1 2 3\n\n\n\n\n\n\n\n"), "line 19: expected vertex index, found nothing");
  expectBad(read, "m19c.mesh", replaced(kMedit, "0 1 0 0\n0 0 1 0\n", "0 1 0 0\n0 0 1\n\n\n\n\n"), "expected vertex reference, found 'Tetrahedra'");
  expectBad(read, "m20.mesh", replaced(kMedit, "Tetrahedra\n1\n1 2 3 4 7\n", "Triangles\n1\n1 2 3 7\n"), "no tetrahedra");
  expectBad(read, "m21.mesh", replaced(kMedit, "Tetrahedra\n1\n1 2 3 4 7", "Tetrahedra\n0"), "no tetrahedra");
  expectBad(read, "m22.mesh", "MeshVersionFormatted 2\nDimension 3\nEnd\n", "no Vertices block");
  expectBad(read, "m23.mesh", replaced(kMedit, "Dimension 3\n", ""), "Vertices before Dimension");
  expectBad(read, "m24.mesh", replaced(kMedit, "End", "17 End"), "expected a keyword, found '17'");
  expectBad(read, "m25.mesh", replaced(kMedit, "Tetrahedra\n1\n1 2 3 4 7", "Tetrahedra\n1\n1 2 3 4 7\nTetrahedra\n1\n1 2 3 4 7"),
            "a second Tetrahedra block");
  const std::string missing = test::tempDir() + "/missing.mesh";
  expectInputError([&] { readMedit(missing); }, missing, "cannot open file");
  const std::string directory = test::tempDir() + "/directory.mesh";
  std::filesystem::create_directory(directory);
  expectInputError([&] { readMedit(directory); }, directory, "not a regular file");
}

TEST(MeshBadInput, MeditBinary) {
  const auto read = &readMedit;
  const std::string dir = test::tempDir();
  writeMedit(dir + "/good.meshb", twoTets());
  const std::string good = test::readText(dir + "/good.meshb");
  ASSERT_EQ(good.size(), 8 + 16 + (16 + 5 * 28) + (16 + 2 * 20) + 12u);
  auto patched = [&good](std::size_t at, const auto& value) {
    std::string b = good;
    std::memcpy(b.data() + at, &value, sizeof(value));
    return b;
  };
  const std::size_t vertices = 8 + 16, tets = vertices + 16 + 5 * 28;
  expectBad(read, "b1.meshb", "MeshVersionFormatted 2\n", "not a binary Medit mesh (bad magic number)");
  expectBad(read, "b2.meshb", patched(4, std::int32_t(9)), "version 9 is not 1, 2, 3 or 4");
  expectBad(read, "b3.meshb", patched(vertices + 12, std::int32_t(2000000000)), "vertex count 2000000000 at byte 40 is more than the rest of the file can hold");
  expectBad(read, "b4.meshb", patched(vertices + 16 + 28 + 8, std::nan("")), "vertex 2 has a non-finite coordinate");
  expectBad(read, "b5.meshb", patched(tets + 16 + 4, std::int32_t(0)), "tetrahedron 1 references vertex 0");
  expectBad(read, "b6.meshb", patched(tets + 16 + 4, std::int32_t(6)), "tet 0 references vertex 5 (mesh has 5 vertices)");
  expectBad(read, "b7.meshb", patched(tets + 16 + 4, std::int32_t(1)), "tet 0 repeats vertex 0");
  expectBad(read, "b8.meshb", good.substr(0, tets + 30), "tetrahedron count 2 at byte 196 is more than the rest of the file can hold");
  {
    // An unknown keyword is skipped through its next-keyword position, which
    // must point forward and into the file.
    std::string unknown = patched(tets, std::int32_t(77));
    const std::int64_t back = 100;
    std::memcpy(unknown.data() + tets + 4, &back, 8);
    expectBad(read, "b9.meshb", unknown, "keyword 77 at byte 180 points to byte 100");
  }
  expectBad(read, "b10.meshb", patched(8 + 12, std::int32_t(2)), "dimension 2 is not supported");
}

const std::string kGmsh =
    "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n1 0 0 0 1 1 1 1 7 0\n$EndEntities\n"
    "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n"
    "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";

TEST(MeshBadInput, Gmsh) {
  const auto read = &readGmsh;
  {
    const std::string path = test::tempDir() + "/good.msh";
    writeText(path, kGmsh);
    const TetMesh m = readGmsh(path);
    EXPECT_EQ(m.labels, std::vector<std::int32_t>{7});
  }
  expectBad(read, "g1.msh", "", "expected $MeshFormat");
  expectBad(read, "g2.msh", "MeshVersionFormatted 2\n", "not a Gmsh mesh");
  expectBad(read, "g3.msh", replaced(kGmsh, "4.1 0 8", "2.2 0 8"), "MSH version 2.2 is not supported");
  expectBad(read, "g4.msh", replaced(kGmsh, "4.1 0 8", "4.1 0 3"), "data size 3");
  expectBad(read, "g5.msh", replaced(kGmsh, "1 4 1 4\n", "1 99999999999 1 4\n"),
            "line 9: $Nodes: node count 99999999999 is more than the rest of the file can hold");
  expectBad(read, "g6.msh", replaced(kGmsh, "3 1 0 4\n", "3 1 0 99999999999\n"), "$Nodes: block node count 99999999999");
  expectBad(read, "g7.msh", replaced(kGmsh, "1 4 1 4\n", "1 5 1 5\n"), "the node blocks hold 4 nodes, 5 announced");
  expectBad(read, "g8.msh", replaced(kGmsh, "0 1 0\n", "0 nan 0\n"), "line 17: y coordinate is not finite");
  expectBad(read, "g9.msh", replaced(kGmsh, "1 1 2 3 4\n", "1 1 2 3 9\n"), "element 1 references node 9, which is not in $Nodes");
  expectBad(read, "g10.msh", replaced(kGmsh, "1 1 2 3 4\n", "1 1 2 3 3\n"), "element 1 repeats node 3");
  expectBad(read, "g11.msh", replaced(kGmsh, "\n2\n3\n", "\n2\n2\n"), "node tag 2 is repeated");
  expectBad(read, "g12.msh", replaced(kGmsh, "3 1 4 1\n1 1 2 3 4", "2 1 2 1\n1 1 2 3"), "no tetrahedra");
  expectBad(read, "g13.msh", kGmsh.substr(0, kGmsh.find("0 1 0\n")), "line 10: $Nodes: block node count 4 is more than the rest of the file can hold");
  expectBad(read, "g14.msh", kGmsh.substr(0, kGmsh.find("$EndElements")), "expected $EndElements, found nothing");
  expectBad(read, "g15.msh", replaced(kGmsh, "1 1 1 1\n3 1 4 1", "1 2 1 2\n3 1 4 1"), "the element blocks hold 1 elements, 2 announced");
  expectBad(read, "g16.msh", kGmsh + "$Comments\nno end\n", "line 25: $Comments: section is not closed by $EndComments");
  expectBad(read, "g17.msh", replaced(kGmsh, "3 1 4 1\n", "2 1 4 1\n"), "tetrahedra on an entity of dimension 2");
  expectBad(read, "g18.msh", replaced(kGmsh, "$Elements", "Elements"), "expected a $Section line");
  expectBad(read, "g19.msh", replaced(kGmsh, "\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements", ""), "no tetrahedra");
  expectBad(read, "g20.msh", replaced(kGmsh, "$Nodes", "$Nodez"), "not closed");
}

std::string binaryGmsh() {
  // The writer's ASCII file, re-encoded as MSH 4.1 binary.
  std::string b = "$MeshFormat\n4.1 1 8\n";
  auto put = [&b](const auto& v) { b.append(reinterpret_cast<const char*>(&v), sizeof(v)); };
  put(std::int32_t(1));
  b += "\n$EndMeshFormat\n$Nodes\n";
  for (std::uint64_t v : {1, 4, 1, 4}) put(v);
  put(std::int32_t(3)), put(std::int32_t(1)), put(std::int32_t(0)), put(std::uint64_t(4));
  for (std::uint64_t v : {1, 2, 3, 4}) put(v);
  for (double v : {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}) put(v);
  b += "\n$EndNodes\n$Elements\n";
  for (std::uint64_t v : {1, 1, 1, 1}) put(v);
  put(std::int32_t(3)), put(std::int32_t(6)), put(std::int32_t(4)), put(std::uint64_t(1));
  for (std::uint64_t v : {1, 1, 2, 3, 4}) put(v);
  b += "\n$EndElements\n";
  return b;
}

TEST(MeshBadInput, GmshBinary) {
  const auto read = &readGmsh;
  const std::string good = binaryGmsh();
  {
    const std::string path = test::tempDir() + "/good.msh";
    writeText(path, good);
    const TetMesh m = readGmsh(path);
    EXPECT_EQ(m.labels, std::vector<std::int32_t>{6});  // no $Entities: the entity tag
  }
  const std::size_t nodes = good.find("$Nodes\n") + 7;
  std::string hugeCount = good;
  const std::uint64_t huge = std::uint64_t(1) << 60;
  std::memcpy(hugeCount.data() + nodes + 8, &huge, 8);
  expectBad(read, "b1.msh", hugeCount, "$Nodes: node count 1152921504606846976 is more than the rest of the file can hold");
  std::string nanCoordinate = good;
  const double nan = std::nan("");
  std::memcpy(nanCoordinate.data() + nodes + 32 + 20 + 32 + 8, &nan, 8);
  expectBad(read, "b2.msh", nanCoordinate, "$Nodes: y coordinate is not finite");
  expectBad(read, "b3.msh", good.substr(0, nodes + 40), "$Nodes: node count 4 is more than the rest of the file can hold");
  std::string badMark = good;
  badMark[good.find("4.1 1 8\n") + 8] = 7;
  expectBad(read, "b4.msh", badMark, "bad byte order mark");
  std::string unknownType = good;
  const std::size_t elements = good.find("$Elements\n") + 10;
  const std::int32_t type = 12345;
  std::memcpy(unknownType.data() + elements + 32 + 8, &type, 4);
  expectBad(read, "b5.msh", unknownType, "unknown element type 12345");
}

TEST(MeshBadInput, Vtu) {
  const auto read = &readVtu;
  const TetMesh mesh = twoTets();
  const std::string ascii = test::vtuFile(mesh, {test::VtuEncoding::Ascii});
  expectBad(read, "v1.vtu", "", "not a valid XML file");
  expectBad(read, "v2.vtu", "MeshVersionFormatted 2\n", "not a valid XML file");
  expectBad(read, "v3.vtu", "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\"><PolyData/></VTKFile>", "line 2: VTK file of type 'PolyData', expected UnstructuredGrid");
  expectBad(read, "v4.vtu", "<?xml version=\"1.0\"?>\n<Mesh/>", "not a VTK XML file");
  expectBad(read, "v5.vtu", ascii.substr(0, ascii.size() / 2), "not a valid XML file");
  expectBad(read, "v6.vtu", replaced(ascii, "0 0 0 1 0 0", "0 0 0 nan 0 0"), "line 6: a finite number is not finite");
  expectBad(read, "v7.vtu", replaced(ascii, "NumberOfPoints=\"5\"", "NumberOfPoints=\"99999999999\""), "more than supported");
  expectBad(read, "v8.vtu", replaced(ascii, "NumberOfPoints=\"5\"", "NumberOfPoints=\"3000\""), "'Points' holds 15 values, expected 9000");
  expectBad(read, "v9.vtu", replaced(ascii, "NumberOfPoints=\"5\"", "NumberOfPoints=\"-5\""), "is not a non-negative integer");
  expectBad(read, "v10.vtu", replaced(ascii, ">0 1 2 3 1 2 3 4 <", ">0 1 2 3 1 2 3 5 <"), "cell 1 references point 5 (the piece has 5 points)");
  expectBad(read, "v11.vtu", replaced(ascii, ">0 1 2 3 1 2 3 4 <", ">0 1 2 3 1 2 3 3 <"), "tet 1 repeats vertex 3");
  expectBad(read, "v12.vtu", replaced(ascii, ">10 10 <", ">5 5 <"), "no tetrahedra");
  expectBad(read, "v13.vtu", replaced(ascii, ">4 8 <", ">3 8 <"), "cell 0 is a VTK_TETRA with 3 points");
  expectBad(read, "v14.vtu", replaced(ascii, ">4 8 <", ">8 4 <"), "offsets decrease at cell 1");
  expectBad(read, "v15.vtu", replaced(ascii, ">7 8 <", ">7 3000000000 <"), "cell 1 has label 3000000000, out of the 32-bit range");
  expectBad(read, "v16.vtu", replaced(ascii, "type=\"Float64\"", "type=\"Float128\""), "unsupported type 'Float128'");
  expectBad(read, "v17.vtu", replaced(ascii, "type=\"Int32\" Name=\"label\"", "type=\"Float32\" Name=\"label\""), "integers are needed");
  expectBad(read, "v18.vtu", replaced(ascii, "Name=\"connectivity\"", "Name=\"conn\""), "lacks a connectivity, offsets or types");
  expectBad(read, "v19.vtu", replaced(ascii, ">0 1 2 3 1 2 3 4 <", ">0 1 2 3 1 2 x 4 <"), "expected an integer, found 'x'");

  // Binary encodings.
  const std::string raw = test::vtuFile(mesh, {test::VtuEncoding::AppendedRaw});
  expectBad(read, "v20.vtu", raw.substr(0, raw.size() - 40), "<AppendedData> is not closed");
  {
    // The points' byte count claims a terabyte.
    std::string text = raw;
    const std::uint32_t size = 0xFFFFFFF0u;
    std::memcpy(text.data() + text.find("\n_") + 2, &size, 4);
    expectBad(read, "v21.vtu", text, "'Points' announces 4294967280 bytes but the file holds fewer");
  }
  expectBad(read, "v22.vtu", replaced(raw, "offset=\"0\"", "offset=\"999999\""), "offset 999999 past the end of the appended data");
  expectBad(read, "v23.vtu", replaced(raw, "encoding=\"raw\"", "encoding=\"hex\""), "unknown AppendedData encoding 'hex'");
  expectBad(read, "v24.vtu", replaced(raw, "\n_", "\n"), "does not start with '_'");
  {
    std::string text = test::vtuFile(mesh, {test::VtuEncoding::AppendedRaw, true});
    const std::size_t data = text.find("\n_") + 2 + 4 * 4;  // first compressed block of the points
    text[data + 5] = char(text[data + 5] ^ 0x55);
    text[data + 6] = char(text[data + 6] ^ 0x55);
    expectBad(read, "v25.vtu", text, "'Points': compressed block 0 is corrupt");
  }
  {
    std::string text = test::vtuFile(mesh, {test::VtuEncoding::Binary});
    const std::size_t at = text.find("format=\"binary\">\n") + 17;
    text[at + 10] = '*';
    expectBad(read, "v26.vtu", text, "invalid base64");
  }
  expectBad(read, "v28.vtu", replaced(test::vtuFile(mesh, {test::VtuEncoding::AppendedRaw, true}), "vtkZLibDataCompressor", "vtkLZ4DataCompressor"),
            "unsupported compressor 'vtkLZ4DataCompressor'");
  {
    // NaN point in binary data.
    std::string text = raw;
    const double nan = std::nan("");
    std::memcpy(text.data() + text.find("\n_") + 2 + 4 + 8 * 4, &nan, 8);
    expectBad(read, "v29.vtu", text, "point 1 has a non-finite coordinate");
  }
}

// Every prefix of a valid file either fails with an InputError or, when the
// cut only lost optional trailing text, reads as the whole mesh.
void expectPrefixesFailCleanly(test::MemoryFile& file, TetMesh (*read)(const std::string&), const std::string& text, const TetMesh& mesh) {
  std::size_t failures = 0;
  for (std::size_t n = 0; n < text.size(); ++n) {
    const std::string& path = file.set(text.substr(0, n));
    try {
      const TetMesh m = read(path);
      ASSERT_EQ(m.positions, mesh.positions) << "prefix " << n;
      ASSERT_EQ(m.tets, mesh.tets) << "prefix " << n;
      ASSERT_EQ(m.labels, mesh.labels) << "prefix " << n;
    } catch (const InputError&) {
      ++failures;
    }
  }
  EXPECT_GT(failures, text.size() * 9 / 10);
}

// Random byte corruption: an InputError or a mesh that validates, nothing else.
void expectCorruptionFailsCleanly(test::MemoryFile& file, TetMesh (*read)(const std::string&), const std::string& text) {
  std::mt19937 random(12345);
  for (int trial = 0; trial < 500; ++trial) {
    std::string bad = text;
    const int edits = 1 + int(random() % 3);
    for (int e = 0; e < edits; ++e) bad[random() % bad.size()] = char(random() % 256);
    const std::string& path = file.set(bad);
    try {
      read(path).validate(path);
    } catch (const InputError&) {
    }
  }
}

TEST(MeshBadInput, TruncatedAndCorruptFiles) {
  const std::string dir = test::tempDir();
  const TetMesh mesh = twoTets();
  writeMedit(dir + "/w.mesh", mesh);
  writeMedit(dir + "/w.meshb", mesh);
  writeVtu(dir + "/w.vtu", mesh);
  writeGmsh(dir + "/w.msh", mesh);
  TetMesh oneTet;
  oneTet.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  oneTet.tets = {{0, 1, 2, 3}};
  oneTet.labels = {6};
  struct Case {
    const char* name;
    std::string text;
    TetMesh (*read)(const std::string&);
    TetMesh mesh;
  };
  const Case cases[] = {
      {"ours.mesh", test::readText(dir + "/w.mesh"), &readMedit, mesh},
      {"ours.vtu", test::readText(dir + "/w.vtu"), &readVtu, mesh},
      {"ours.meshb", test::readText(dir + "/w.meshb"), &readMedit, mesh},
      {"ours.msh", test::readText(dir + "/w.msh"), &readGmsh, mesh},
      {"binary.msh", binaryGmsh(), &readGmsh, oneTet},
      {"appended base64 zlib u64.vtu", test::vtuFile(mesh, {test::VtuEncoding::AppendedBase64, true, true}), &readVtu, mesh},
      {"inline zlib.vtu", test::vtuFile(mesh, {test::VtuEncoding::Binary, true}), &readVtu, mesh},
      {"inline big-endian.vtu", test::vtuFile(mesh, {test::VtuEncoding::Binary, false, false, true}), &readVtu, mesh},
      {"ascii.vtu", test::vtuFile(mesh, {test::VtuEncoding::Ascii}), &readVtu, mesh},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    test::MemoryFile file(dir, c.name);
    test::expectSameMesh(c.mesh, c.read(file.set(c.text)));  // valid before it is cut
    expectPrefixesFailCleanly(file, c.read, c.text, c.mesh);
    expectCorruptionFailsCleanly(file, c.read, c.text);
  }
}

}  // namespace
}  // namespace vox
