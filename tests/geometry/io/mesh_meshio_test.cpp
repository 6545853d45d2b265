// Our tet mesh files against a real client, python3-meshio: meshio reads what
// we write, and we read what meshio writes, coordinates compared bit for bit.
#include "geometry/io/mesh_io.h"
#include "tests/geometry/io/mesh_test_meshes.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <sstream>

namespace vox {
namespace {

// Prints the points (hex floats), the tet connectivity and the per-tet labels
// of argv[1] as meshio reads them, labels from cell data argv[2].
constexpr const char* kMeshioRead = R"(
import sys
import meshio
import numpy as np
m = meshio.read(sys.argv[1])
tets, labels = [], []
for i, block in enumerate(m.cells):
    if block.type == "tetra":
        tets.append(block.data)
        labels.append(m.cell_data[sys.argv[2]][i])
print(len(m.points))
print(" ".join(float(x).hex() for x in m.points.ravel()))
print(" ".join(map(str, np.concatenate(tets).ravel().tolist())))
print(" ".join(map(str, np.concatenate(labels).ravel().tolist())))
)";

// Reads our .mesh (argv[1]) and writes it back with meshio into argv[2]: Medit
// ASCII and binary, VTU in four encodings with the labels under different cell data
// names, and Gmsh 4.1 binary and ASCII with one entity per label.
constexpr const char* kMeshioWrite = R"(
import sys
import meshio
import numpy as np
src, out = sys.argv[1], sys.argv[2]
m = meshio.read(src)
pts = m.points
tets = m.cells_dict["tetra"]
ref = m.cell_data_dict["medit:ref"]["tetra"]
def mesh(**cell_data):
    return meshio.Mesh(pts, [("tetra", tets)], cell_data={k: [v] for k, v in cell_data.items()})
meshio.write(out + "/meshio.mesh", mesh(**{"medit:ref": ref}))
meshio.write(out + "/meshio.meshb", mesh(**{"medit:ref": ref}))
meshio.write(out + "/zlib.vtu", mesh(**{"medit:ref": ref}))
meshio.vtu.write(out + "/zlib_u64.vtu", mesh(label=ref.astype(np.int32)), header_type="UInt64")
meshio.vtu.write(out + "/base64.vtu", mesh(**{"gmsh:physical": ref}), binary=True, compression=None)
meshio.vtu.write(out + "/ascii.vtu", mesh(quality=np.ones(len(ref)), material=ref.astype(np.int32)), binary=False)
# Gmsh: one cell block per label on its own volume entity; every entity needs
# nodes classified on it for meshio to write it, so nodes are dealt out.
labels = np.unique(ref)
blocks = [("tetra", tets[ref == l]) for l in labels]
entity = np.arange(1, len(labels) + 1)
dim_tags = np.column_stack([np.full(len(pts), 3), 1 + np.arange(len(pts)) % len(labels)])
g = meshio.Mesh(pts, blocks,
                cell_data={"gmsh:physical": [np.full(len(b[1]), l) for b, l in zip(blocks, labels)],
                           "gmsh:geometrical": [np.full(len(b[1]), e) for b, e in zip(blocks, entity)]},
                point_data={"gmsh:dim_tags": dim_tags})
meshio.write(out + "/binary.msh", g, file_format="gmsh", binary=True)
meshio.write(out + "/ascii.msh", g, file_format="gmsh", binary=False)
print("ok")
)";

struct MeshioView {
  std::vector<Eigen::Vector3d> points;
  std::vector<Tet> tets;
  std::vector<std::int32_t> labels;
};

std::string runPython(const std::string& dir, const std::string& script, const std::vector<std::string>& args) {
  const std::string file = dir + "/script.py";
  test::writeText(file, script);
  std::string cmd = test::quote(test::python()) + " " + test::quote(file);
  for (const std::string& a : args) cmd += " " + test::quote(a);
  const test::CommandResult r = test::runCommand(cmd);
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return r.out;
}

MeshioView meshioRead(const std::string& dir, const std::string& path, const std::string& labelKey) {
  std::istringstream out(runPython(dir, kMeshioRead, {path, labelKey}));
  MeshioView view;
  std::size_t n = 0;
  std::string line;
  out >> n;
  std::getline(out, line);
  std::getline(out, line);
  {
    std::istringstream values(line);
    std::string hex;
    std::vector<double> xyz;
    while (values >> hex) xyz.push_back(std::strtod(hex.c_str(), nullptr));
    EXPECT_EQ(xyz.size(), 3 * n);
    for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) view.points.emplace_back(xyz[i], xyz[i + 1], xyz[i + 2]);
  }
  std::getline(out, line);
  {
    std::istringstream values(line);
    Tet t;
    while (values >> t[0] >> t[1] >> t[2] >> t[3]) view.tets.push_back(t);
  }
  std::getline(out, line);
  {
    std::istringstream values(line);
    std::int64_t l;
    while (values >> l) view.labels.push_back(std::int32_t(l));
  }
  return view;
}

void expectSameView(const TetMesh& expected, const MeshioView& actual) {
  ASSERT_EQ(expected.positions.size(), actual.points.size());
  for (std::size_t v = 0; v < expected.vertexCount(); ++v) ASSERT_EQ(expected.positions[v], actual.points[v]) << "vertex " << v;
  ASSERT_EQ(expected.tets.size(), actual.tets.size());
  ASSERT_EQ(expected.labels.size(), actual.labels.size());
  for (std::size_t t = 0; t < expected.tetCount(); ++t) {
    ASSERT_EQ(expected.tets[t], actual.tets[t]) << "tet " << t;
    ASSERT_EQ(expected.labels[t], actual.labels[t]) << "tet " << t;
  }
}

// Gmsh files hold one block per label: meshio lists the tets grouped by
// label (ascending), in mesh order within a label.
TetMesh groupedByLabel(const TetMesh& mesh) {
  std::vector<std::size_t> order(mesh.tetCount());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return mesh.labels[a] < mesh.labels[b]; });
  TetMesh grouped = mesh;
  for (std::size_t i = 0; i < order.size(); ++i) {
    grouped.tets[i] = mesh.tets[order[i]];
    grouped.labels[i] = mesh.labels[order[i]];
  }
  return grouped;
}

class MeshioReadsOurs : public ::testing::TestWithParam<std::pair<const char*, const char*>> {};

TEST_P(MeshioReadsOurs, PointsTetsAndLabels) {
  if (test::python().empty()) GTEST_SKIP() << "python3 not found";
  const auto [extension, labelKey] = GetParam();
  const std::string dir = test::tempDir();
  const std::string path = dir + "/ours" + extension;
  const TetMesh mesh = test::labeledMesh();
  writeTetMesh(path, mesh);
  const MeshioView view = meshioRead(dir, path, labelKey);
  expectSameView(std::string(extension) == ".msh" ? groupedByLabel(mesh) : mesh, view);
}

INSTANTIATE_TEST_SUITE_P(Formats, MeshioReadsOurs,
                         ::testing::Values(std::pair{".mesh", "medit:ref"}, std::pair{".meshb", "medit:ref"}, std::pair{".vtu", "label"},
                                           std::pair{".msh", "gmsh:physical"}),
                         [](const auto& info) { return std::string(info.param.first + 1); });

TEST(MeshioWritesWeRead, EveryEncoding) {
  if (test::python().empty()) GTEST_SKIP() << "python3 not found";
  const std::string dir = test::tempDir();
  const TetMesh mesh = test::labeledMesh();
  writeMedit(dir + "/source.mesh", mesh);
  ASSERT_EQ(runPython(dir, kMeshioWrite, {dir + "/source.mesh", dir}), "ok\n");

  // meshio writes .meshb as GMF version 4 (64-bit integers).
  EXPECT_EQ(test::readText(dir + "/meshio.meshb").substr(4, 4), std::string("\x04\0\0\0", 4));
  for (const char* name : {"meshio.mesh", "meshio.meshb", "zlib.vtu", "zlib_u64.vtu", "base64.vtu"}) {
    SCOPED_TRACE(name);
    test::expectSameMesh(mesh, readTetMesh(dir + "/" + name));
  }
  // meshio's ASCII VTU keeps 12 significant digits ("{:.11e}").
  {
    SCOPED_TRACE("ascii.vtu");
    TetMesh rounded = mesh;
    for (Eigen::Vector3d& p : rounded.positions)
      for (int c = 0; c < 3; ++c) {
        char text[64];
        std::snprintf(text, sizeof(text), "%.11e", p[c]);
        p[c] = std::strtod(text, nullptr);
      }
    test::expectSameMesh(rounded, readTetMesh(dir + "/ascii.vtu"));
  }
  for (const char* name : {"binary.msh", "ascii.msh"}) {
    SCOPED_TRACE(name);
    test::expectSameMesh(groupedByLabel(mesh), readTetMesh(dir + "/" + name));
  }
  // The binary Gmsh file really is binary.
  EXPECT_EQ(test::readText(dir + "/binary.msh").rfind("$MeshFormat\n4.1 1 8\n", 0), 0u);
}

// Label names as meshio sees them: field_data {name: [label, 3]} from our
// .vtu and .msh, the physical groups of a Gmsh file; and a .msh that meshio
// converts from our .vtu keeps them as physical names we read back.
TEST(MeshioReadsOurs, LabelNames) {
  if (test::python().empty()) GTEST_SKIP() << "python3 not found";
  const std::string dir = test::tempDir();
  const TetMesh mesh = test::namedMesh();
  writeTetMesh(dir + "/ours.vtu", mesh);
  writeTetMesh(dir + "/ours.msh", mesh);
  const std::string out = runPython(dir, R"(
import sys
import meshio
for name in sys.argv[1:3]:
    m = meshio.read(name)
    for key in sorted(m.field_data):
        print(key, "|", " ".join(str(int(v)) for v in m.field_data[key]))
m = meshio.read(sys.argv[1])
meshio.write(sys.argv[3], m, file_format="gmsh", binary=False)
)", {dir + "/ours.vtu", dir + "/ours.msh", dir + "/converted.msh"});
  const std::string vtu =
      "Adrenal, left | 1 3\nBrain <grey> & \"white\" | 2 3\nLiver | 3 3\nSkin | 2147483647 3\n";
  // Our .msh names every label (label_<n> where the mesh has no name); meshio lists them all.
  EXPECT_EQ(out.substr(0, vtu.size()), vtu);
  EXPECT_NE(out.find("Brain <grey> & 'white' | 2 3\nLiver | 3 3\nSkin | 2147483647 3\nlabel_-1 | -1 3\n", vtu.size()),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("label_4 | 4 3\n", vtu.size()), std::string::npos) << out;
  // meshio writes the physical names of the converted file from the .vtu's field data.
  const std::string converted = test::readText(dir + "/converted.msh");
  EXPECT_NE(converted.find("3 1 \"Adrenal, left\""), std::string::npos) << converted.substr(0, 400);
  EXPECT_NE(converted.find("3 3 \"Liver\""), std::string::npos);
}

}  // namespace
}  // namespace vox
