// The remesher on tet meshes made by another mesher: CGAL Mesh_3 (the
// restricted Delaunay volume mesher of geometry/deform) on a crop of the
// adult male phantom and on synthetic label images whose parts touch along
// edges and at points. Mesh_3 keeps only the domain's tets, so such contacts
// give outer boundaries that are not manifold; the input travels through the
// writers and readers first (.mesh, .vtu, .msh), as a user's file would.

#include "geometry/deform/cage/restricted_delaunay.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/mesh_io.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh.h"
#include "geometry/remesh/remesh_complex.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <map>
#include <set>

namespace vox::remesh {
namespace {

// Mesh_3 volume mesh of `grid` (nearest-voxel labels, 0 beyond the grid; the
// border voxels must be 0) with tets of about `sizeMm`.
TetMesh mesh3(const LabelGrid& grid, double sizeMm) {
  SampledDomain domain;
  domain.labels = &grid;
  domain.labelAt = [&grid](const Eigen::Vector3d& p) {
    Index3 c;
    return grid.geometry().voxelAt(p, c) ? int(grid.at(c[0], c[1], c[2])) : 0;
  };
  const ScalarGrid sizing(grid.geometry(), float(sizeMm));
  VolumeCriteria criteria;
  criteria.sizing = &sizing;
  criteria.facetDistanceMm = 0.25 * grid.geometry().spacing.minCoeff();
  return restrictedDelaunayVolume(domain, criteria);
}

std::size_t pinnedVertices(const RemeshComplex& complex) {
  std::size_t n = 0;
  for (std::int32_t v = 0; v < complex.vertexSlots(); ++v) n += complex.vertexAlive(v) && complex.isPinned(v);
  return n;
}

// Writes `mesh` in each format, reads it back and remeshes it: every label's
// topology and every junction as in the file, no inverted tet.
void remeshThroughFormats(const TetMesh& mesh, double targetLength, const std::string& name,
                          std::initializer_list<const char*> formats) {
  const std::string dir = test::tempDir();
  for (const char* ext : formats) {
    SCOPED_TRACE(ext);
    const std::string path = dir + "/" + name + ext;
    writeTetMesh(path, mesh);
    const TetMesh input = readTetMesh(path);
    ASSERT_EQ(input.tetCount(), mesh.tetCount());
    RemeshOptions options;
    options.targetLength = targetLength;
    options.iterations = 4;
    const TetMesh out = remeshTetMesh(input, options, nullptr, false, path);
    ASSERT_GT(out.tetCount(), 0u);
    std::size_t inverted = 0;
    for (std::size_t t = 0; t < out.tetCount(); ++t) inverted += !(signedVolume(out.positions, out.tets[t]) > 0.0);
    EXPECT_EQ(inverted, 0u);
    EXPECT_EQ(test::joinLines(compareTopology(computeMeshTopology(input), computeMeshTopology(out))), "");
  }
}

// Blocks of 6^3 voxels touching along edges and at corners, in three labels,
// one of them touching another along a face as well.
TEST(RemeshInputs, Mesh3OfTouchingBlocksHasANonManifoldBoundaryAndRemeshes) {
  GridGeometry g;
  g.dims = {26, 26, 20};
  LabelGrid grid(g, 0);
  auto block = [&](int i, int j, int k, Label l) {
    for (int z = 0; z < 6; ++z)
      for (int y = 0; y < 6; ++y)
        for (int x = 0; x < 6; ++x) grid.at(1 + 6 * i + x, 1 + 6 * j + y, 1 + 6 * k + z) = l;
  };
  block(0, 0, 0, 1);
  block(1, 1, 0, 2);  // edge contact with the first
  block(2, 2, 1, 3);  // corner contact with the second
  block(2, 1, 0, 1);  // face contact with the second
  block(3, 0, 0, 3);  // edge contact with the fourth
  block(0, 2, 2, 2);  // corner contact with nothing: a separate part
  const TetMesh mesh = mesh3(grid, 2.0);
  ASSERT_GT(mesh.tetCount(), 1000u);
  const RemeshComplex complex(mesh, "mesh3 blocks");
  EXPECT_GT(pinnedVertices(complex), 0u) << "Mesh_3 gave a manifold boundary: the test no longer covers contacts";
  EXPECT_EQ(complex.checkConsistency(true), "");
  remeshThroughFormats(mesh, 1.5, "blocks", {".mesh", ".vtu", ".msh"});
}

// A crop of the adult male through the upper abdomen: a dozen organs, thin
// walls and vessels, as Mesh_3 meshes them.
TEST(RemeshInputs, Mesh3OfAnAdultMaleCropRemeshes) {
  const LabelGrid am = readGrid(test::assetPath("icrp110_am.nii.gz"));
  const Index3 lo{70, 40, 140}, n{48, 40, 12};
  GridGeometry g = am.geometry();
  g.dims = {n[0] + 2, n[1] + 2, n[2] + 2};
  g.origin = am.geometry().voxelCenter(lo[0] - 1, lo[1] - 1, lo[2] - 1);
  LabelGrid crop(g, 0);
  for (std::int64_t k = 0; k < n[2]; ++k)
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i) crop.at(i + 1, j + 1, k + 1) = am.at(lo[0] + i, lo[1] + j, lo[2] + k);
  const TetMesh mesh = mesh3(crop, 8.0);
  ASSERT_GT(mesh.tetCount(), 1000u);
  EXPECT_GT(pinnedVertices(RemeshComplex(mesh, "mesh3 crop")), 0u) << "no contact left in the crop's mesh";
  remeshThroughFormats(mesh, 8.0, "am_crop", {".msh"});
}

// The tools' own output, made in the test: they must be installed (./run
// installs gmsh and tetgen); without them the test is skipped.
bool installed(const std::string& tool) { return test::runCommand("command -v " + tool).exitCode == 0; }

// Gmsh (OpenCASCADE): unit boxes touching along an edge, at a corner and on
// a face, one holding a ball: six volumes, one label each (entity tags).
TEST(RemeshInputs, GmshVolumesTouchingAlongAnEdgeAndAtACorner) {
  if (!installed("gmsh")) GTEST_SKIP() << "gmsh not installed";
  const std::string dir = test::tempDir();
  test::writeText(dir + "/parts.geo", R"(SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 1, 0, 1, 1, 1};
Box(3) = {0, -1, 0, 1, 1, 1};
Box(4) = {-1, 1, 1, 1, 1, 1};
Sphere(5) = {0.5, 0.5, 0.5, 0.25};
BooleanFragments{ Volume{1, 2, 3, 4, 5}; Delete; }{}
Mesh.MeshSizeMax = 0.15;
Mesh.SaveAll = 1;
)");
  const auto run = test::runCommand("gmsh -3 -format msh41 -o " + dir + "/parts.msh " + dir + "/parts.geo");
  ASSERT_EQ(run.exitCode, 0) << run.out << run.err;
  const TetMesh mesh = readTetMesh(dir + "/parts.msh");
  EXPECT_GT(pinnedVertices(RemeshComplex(mesh, "input")), 0u);
  remeshThroughFormats(mesh, 0.12, "gmsh_parts", {".msh"});
}

// TetGen: a PLC of unit boxes (regions 1-4 by attribute) touching along an
// edge, at a corner and on a face.
TEST(RemeshInputs, TetGenRegionsTouchingAlongAnEdgeAndAtACorner) {
  if (!installed("tetgen")) GTEST_SKIP() << "tetgen not installed";
  const std::vector<std::array<int, 3>> boxes = {{0, 0, 0}, {1, 1, 0}, {0, -1, 0}, {-1, 1, 1}};
  std::map<std::array<int, 3>, int> nodes;
  std::set<std::array<int, 4>> facets;
  std::vector<std::array<int, 4>> facetList;
  auto node = [&](int x, int y, int z) { return nodes.try_emplace({x, y, z}, int(nodes.size()) + 1).first->second; };
  for (const auto& b : boxes) {
    int c[2][2][2];
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j)
        for (int k = 0; k < 2; ++k) c[i][j][k] = node(b[0] + i, b[1] + j, b[2] + k);
    const std::array<int, 4> quads[6] = {{c[0][0][0], c[1][0][0], c[1][1][0], c[0][1][0]}, {c[0][0][1], c[1][0][1], c[1][1][1], c[0][1][1]},
                                          {c[0][0][0], c[1][0][0], c[1][0][1], c[0][0][1]}, {c[0][1][0], c[1][1][0], c[1][1][1], c[0][1][1]},
                                          {c[0][0][0], c[0][1][0], c[0][1][1], c[0][0][1]}, {c[1][0][0], c[1][1][0], c[1][1][1], c[1][0][1]}};
    for (const auto& q : quads) {
      std::array<int, 4> key = q;
      std::sort(key.begin(), key.end());
      if (facets.insert(key).second) facetList.push_back(q);
    }
  }
  std::string poly = std::to_string(nodes.size()) + " 3 0 0\n";
  std::vector<std::pair<int, std::array<int, 3>>> byIndex;
  for (const auto& [p, i] : nodes) byIndex.push_back({i, p});
  std::sort(byIndex.begin(), byIndex.end());
  for (const auto& [i, p] : byIndex)
    poly += std::to_string(i) + " " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
  poly += std::to_string(facetList.size()) + " 0\n";
  for (const auto& q : facetList)
    poly += "1\n4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) + " " + std::to_string(q[3]) + "\n";
  poly += "0\n" + std::to_string(boxes.size()) + "\n";
  for (std::size_t r = 0; r < boxes.size(); ++r)
    poly += std::to_string(r + 1) + " " + std::to_string(boxes[r][0] + 0.5) + " " + std::to_string(boxes[r][1] + 0.5) + " " +
            std::to_string(boxes[r][2] + 0.5) + " " + std::to_string(r + 1) + " 0\n";
  const std::string dir = test::tempDir();
  test::writeText(dir + "/boxes.poly", poly);
  // -p PLC, -q quality, -A region attributes, -a volume bound, -g Medit output, -Q quiet.
  const auto run = test::runCommand("tetgen -pqAa0.002gQ " + dir + "/boxes.poly");
  ASSERT_EQ(run.exitCode, 0) << run.out << run.err;
  const TetMesh mesh = readTetMesh(dir + "/boxes.1.mesh");
  ASSERT_GT(mesh.tetCount(), 1000u);
  for (std::int32_t l = 1; l <= 4; ++l) EXPECT_NE(std::find(mesh.labels.begin(), mesh.labels.end(), l), mesh.labels.end()) << l;
  EXPECT_GT(pinnedVertices(RemeshComplex(mesh, "input")), 0u);
  remeshThroughFormats(mesh, 0.15, "tetgen_boxes", {".mesh"});
}

}  // namespace
}  // namespace vox::remesh
