#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/remesh/collapse_short_edges.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh.h"
#include "geometry/remesh/remesh_complex.h"
#include "geometry/remesh/split_long_edges.h"
#include "geometry/synth.h"
#include "geometry/voxel_tetrahedralization.h"

#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <thread>

namespace vox::remesh {
namespace {

TEST(RemeshComplex, ExtendedComplexIsClosedAndRoundTrips) {
  const LabelGrid grid = synthesize(SynthKind::NestedSpheres, 10);
  const TetMesh mesh = tetrahedralizeVoxels(grid);
  const RemeshComplex complex(mesh);
  EXPECT_EQ(complex.checkConsistency(true), "");
  // Dummy tets close the 2 * 6 * 10 * 10 triangles of the box.
  EXPECT_EQ(complex.liveTetCount(), mesh.tetCount() + 2 * 6 * 10 * 10);
  const TetMesh domain = complex.toTetMesh();
  std::size_t domainTets = 0;
  for (std::int32_t l : mesh.labels) domainTets += l > 0;
  EXPECT_EQ(domain.tetCount(), domainTets);
  EXPECT_EQ(complex.toTetMesh(true).tetCount(), mesh.tetCount());
}

// Either orientation is accepted (a whole mesh written with the other
// convention, or a mix); a flat tet is the input's fault.
TEST(RemeshComplex, TurnsNegativeTetsOverAndRefusesFlatOnes) {
  const TetMesh mesh = tetrahedralizeVoxels(synthesize(SynthKind::NestedSpheres, 8));
  TetMesh mirrored = mesh;
  for (std::size_t t = 0; t < mirrored.tetCount(); t += 3) std::swap(mirrored.tets[t][0], mirrored.tets[t][1]);
  const RemeshComplex a(mesh), b(mirrored);
  EXPECT_EQ(b.checkConsistency(true), "");
  const TetMesh out = b.toTetMesh(true);
  ASSERT_EQ(out.tetCount(), mesh.tetCount());
  for (std::size_t t = 0; t < out.tetCount(); ++t) EXPECT_GT(signedVolume(out.positions, out.tets[t]), 0.0) << t;
  EXPECT_EQ(a.liveTetCount(), b.liveTetCount());

  TetMesh flat;
  flat.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, 0}};
  flat.tets = {{0, 1, 2, 3}};
  flat.labels = {1};
  try {
    RemeshComplex c(flat, "flat.mesh");
    ADD_FAILURE() << "a flat tet was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tet 0 has zero volume"), std::string::npos) << e.what();
  }
}

// A labeled tet mesh of blocks of `block`^3 voxels: `blocks` lists block
// positions and labels; label 0 blocks are cavities kept as label-0 tets,
// everything else around is left out (no imaginary layer), so parts that
// touch only along an edge or at a point give a non-manifold outer boundary.
struct Block {
  int i, j, k;
  Label label;
};
TetMesh blocksMesh(const std::vector<Block>& blocks, int block) {
  int n = 0;
  for (const Block& b : blocks) n = std::max({n, b.i + 1, b.j + 1, b.k + 1});
  GridGeometry g;
  g.dims = {n * block, n * block, n * block};
  LabelGrid grid(g, 0);
  const Label cavity = 250;
  for (const Block& b : blocks)
    for (int z = 0; z < block; ++z)
      for (int y = 0; y < block; ++y)
        for (int x = 0; x < block; ++x) grid.at(b.i * block + x, b.j * block + y, b.k * block + z) = b.label ? b.label : cavity;
  const TetMesh all = tetrahedralizeVoxels(grid);
  TetMesh mesh;
  mesh.positions = all.positions;  // unused ones stay: dropped by the remesher
  for (std::size_t t = 0; t < all.tetCount(); ++t)
    if (all.labels[t] != 0) {
      mesh.tets.push_back(all.tets[t]);
      mesh.labels.push_back(all.labels[t] == cavity ? 0 : all.labels[t]);
    }
  return mesh;
}

// Meshes users bring have outer boundaries that are not manifold: parts that
// touch along an edge or at a point. They remesh with exact topology, the
// contact kept, every tet positive.
TEST(RemeshComplex, NonManifoldOuterBoundariesRemeshWithTheirTopology) {
  struct Case {
    const char* name;
    std::vector<Block> blocks;
  };
  const std::vector<Case> cases = {
      {"edge contact, one label", {{0, 0, 0, 1}, {1, 1, 0, 1}}},
      {"edge contact, two labels", {{0, 0, 0, 1}, {1, 1, 0, 2}}},
      {"vertex contact", {{0, 0, 0, 1}, {1, 1, 1, 2}}},
      {"vertex contact, one label", {{0, 0, 0, 3}, {1, 1, 1, 3}}},
      // A ring of blocks whose ends touch along an edge: the edge's upper end
      // has one face-connected star, its lower end two.
      {"ring closed along an edge", {{0, 0, 0, 1}, {0, 0, 1, 1}, {0, 1, 1, 2}, {1, 1, 1, 2}, {1, 1, 0, 1}}},
      // Three blocks around one edge, two of them touching the third diagonally,
      // one holding a cavity (label-0 tets inside the domain).
      {"edge fan with a cavity", {{0, 0, 0, 1}, {1, 1, 0, 2}, {2, 0, 0, 1}, {1, 0, 0, 0}, {1, 0, 1, 2}, {2, 2, 2, 1}}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    TetMesh input = blocksMesh(c.blocks, 4);
    // Every third tet in the other orientation, and a vertex no tet uses.
    for (std::size_t t = 0; t < input.tetCount(); t += 3) std::swap(input.tets[t][0], input.tets[t][1]);
    input.positions.push_back({100, 100, 100});
    const RemeshComplex complex(input, c.name);
    EXPECT_EQ(complex.checkConsistency(true), "");
    RemeshOptions options;
    options.targetLength = 2.0;
    options.iterations = 4;
    const TetMesh out = remeshTetMesh(input, options, nullptr, false, c.name);
    EXPECT_NE(out.tetCount(), 0u);
    EXPECT_LT(out.positions.size(), input.positions.size()) << "not remeshed";
    for (std::size_t t = 0; t < out.tetCount(); ++t) ASSERT_GT(signedVolume(out.positions, out.tets[t]), 0.0) << t;
    EXPECT_EQ(test::joinLines(compareTopology(computeMeshTopology(input), computeMeshTopology(out))), "");
    // No two output vertices at one place: the copies were merged.
    std::vector<std::array<double, 3>> points;
    for (const auto& p : out.positions) points.push_back({p.x(), p.y(), p.z()});
    std::sort(points.begin(), points.end());
    EXPECT_EQ(std::adjacent_find(points.begin(), points.end()), points.end());
  }
}

TEST(RemeshComplex, RefusesAFaceInThreeTets) {
  // Three tets on one face: the input's fault, one line naming it.
  TetMesh three;
  three.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, -1}, {0.2, 0.2, 1}};
  three.tets = {{0, 1, 2, 3}, {0, 2, 1, 4}, {0, 1, 2, 5}};
  three.labels = {1, 1, 1};
  try {
    RemeshComplex c(three, "three.mesh");
    ADD_FAILURE() << "a face in three tets was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("shared by more than two tets"), std::string::npos) << e.what();
  }
}

TEST(MeshTopology, GridAndSixTetDecompositionAgree) {
  for (SynthKind kind : {SynthKind::NestedSpheres, SynthKind::JunctionSphere, SynthKind::StickFigure}) {
    const LabelGrid grid = synthesize(kind, 20);
    const MeshTopology fromGrid = computeGridTopology(grid);
    const MeshTopology fromMesh = computeMeshTopology(tetrahedralizeVoxels(grid, {.includeBackground = false}));
    EXPECT_EQ(test::joinLines(compareTopology(fromGrid, fromMesh)), "") << synthKindName(kind);
    EXPECT_EQ(fromGrid.featureEdges, fromMesh.featureEdges) << synthKindName(kind);
  }
}

TEST(MeshTopology, NestedSpheresHaveShellsAndABall) {
  const MeshTopology t = computeGridTopology(synthesize(SynthKind::NestedSpheres, 20));
  ASSERT_EQ(t.labels.size(), 3u);
  EXPECT_EQ(t.labels.at(1).components, 1u);
  EXPECT_EQ(t.labels.at(1).euler, 2);  // closed shell: S^2 x I
  EXPECT_EQ(t.labels.at(2).euler, 2);
  EXPECT_EQ(t.labels.at(3).euler, 1);  // ball
  EXPECT_TRUE(t.junctionCurves.empty());
}

TEST(MeshTopology, JunctionSphereHasCurvesAndCorners) {
  const MeshTopology t = computeGridTopology(synthesize(SynthKind::JunctionSphere, 24));
  EXPECT_FALSE(t.junctionCurves.empty());
  EXPECT_FALSE(t.junctionPoints.empty());
  for (const auto& [label, lt] : t.labels) {
    EXPECT_EQ(lt.components, 1u) << label;
    EXPECT_EQ(lt.euler, 1) << label;
  }
}

TEST(SplitLongEdges, KeepsComplexValidAndTopology) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 12);
  RemeshComplex complex(tetrahedralizeVoxels(grid));
  const std::size_t before = complex.liveTetCount();
  const std::size_t splits = splitLongEdges(complex, EdgeLengthBounds::forTarget(0.9));
  EXPECT_GT(splits, 0u);
  EXPECT_GT(complex.liveTetCount(), before);
  EXPECT_EQ(complex.checkConsistency(true), "");
  EXPECT_EQ(test::joinLines(compareTopology(computeGridTopology(grid), computeMeshTopology(complex.toTetMesh()))), "");
}

// Two tets touching along one edge 10 long, split towards l = 3 (e_max 4).
// The contact edge may not be split, and every triangle at it keeps an edge
// above e_max (its two other edges add up to more than 2 e_max): splitting
// those triangles' edges again and again would add vertices without end,
// each nearer a fixed point, and the contact's end points would gain tets
// without bound (what stalled the whole AM taken from 8 mm to 4 mm).
TEST(SplitLongEdges, EndBesideAContactEdgeTooLongToSplit) {
  TetMesh mesh;
  mesh.positions = {{0, 0, 0}, {0, 0, 10}, {8, 1, 5}, {1, 8, 5}, {-8, -1, 5}, {-1, -8, 5}};
  mesh.tets = {{0, 1, 2, 3}, {0, 1, 4, 5}};
  mesh.labels = {1, 2};
  RemeshComplex complex(mesh);
  ASSERT_TRUE(complex.isPinned(0) && complex.isPinned(1));
  // Splits that never end run until cancelled.
  std::atomic<bool> done = false;
  std::thread watchdog([&] {
    for (int i = 0; i < 300 && !done; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (!done) cancellationRequested() = true;
  });
  std::size_t splits = 0;
  try {
    splits = splitLongEdges(complex, EdgeLengthBounds::forTarget(3.0), 1);
  } catch (const OperationCancelled&) {
    ADD_FAILURE() << "the splits did not end within 30 s (" << complex.liveVertexCount() << " vertices)";
  }
  done = true;
  watchdog.join();
  cancellationRequested() = false;
  // 80 splits: the tets' other edges, and the new ones that are shorter.
  EXPECT_GT(splits, 0u);
  EXPECT_LT(splits, 200u);
  EXPECT_EQ(complex.checkConsistency(true), "");
  EXPECT_GE(complex.findEdgeTet(0, 1), 0) << "the contact edge was split";
  const TetMesh out = complex.toTetMesh();
  EXPECT_EQ(test::joinLines(compareTopology(computeMeshTopology(mesh), computeMeshTopology(out))), "");
}

TEST(CollapseShortEdges, KeepsComplexValidAndTopology) {
  for (SynthKind kind : {SynthKind::NestedSpheres, SynthKind::JunctionSphere, SynthKind::StickFigure}) {
    const LabelGrid grid = synthesize(kind, 16);
    RemeshComplex complex(tetrahedralizeVoxels(grid));
    const HullConstraint hull(complex);
    const std::size_t before = complex.liveTetCount();
    const std::size_t collapses = collapseShortEdges(complex, EdgeLengthBounds::forTarget(3.0 * grid.spacing().maxCoeff()), hull);
    EXPECT_GT(collapses, 0u) << synthKindName(kind);
    EXPECT_LT(complex.liveTetCount(), before) << synthKindName(kind);
    EXPECT_EQ(complex.checkConsistency(true), "") << synthKindName(kind);
    EXPECT_EQ(test::joinLines(compareTopology(computeGridTopology(grid), computeMeshTopology(complex.toTetMesh()))), "")
        << synthKindName(kind);
  }
}

// The same mesh as a set: each tet as its sorted corner positions and label.
std::vector<std::pair<std::array<std::array<double, 3>, 4>, std::int32_t>> tetSet(const TetMesh& mesh) {
  std::vector<std::pair<std::array<std::array<double, 3>, 4>, std::int32_t>> out;
  for (std::size_t t = 0; t < mesh.tetCount(); ++t) {
    std::array<std::array<double, 3>, 4> corners;
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector3d& p = mesh.positions[std::size_t(mesh.tets[t][std::size_t(i)])];
      corners[std::size_t(i)] = {p.x(), p.y(), p.z()};
    }
    std::sort(corners.begin(), corners.end());
    out.push_back({corners, mesh.labels[t]});
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Renumbering changes ids only: the same tets, labels and adjacency, the
// removed slots dropped, the copies of pinched vertices still copies of one
// vertex (written once), and vertex ids ordered along the space.
TEST(RemeshComplex, ReorderingKeepsTheComplex) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 16);
  RemeshComplex complex(tetrahedralizeVoxels(grid));
  collapseShortEdges(complex, EdgeLengthBounds::forTarget(3.0 * grid.spacing().maxCoeff()), HullConstraint(complex));
  ASSERT_LT(complex.liveTetCount(), std::size_t(complex.tetSlots()));
  const TetMesh before = complex.toTetMesh(true);
  const std::size_t liveTets = complex.liveTetCount(), liveVertices = complex.liveVertexCount();
  complex.reorderForLocality();
  EXPECT_EQ(complex.checkConsistency(true), "");
  EXPECT_EQ(std::size_t(complex.tetSlots()), liveTets);
  EXPECT_EQ(std::size_t(complex.vertexSlots()), liveVertices);
  EXPECT_EQ(tetSet(complex.toTetMesh(true)), tetSet(before));
  // Neighbouring ids are near each other: the mean distance between the
  // positions of consecutive vertex ids is far below the mesh's extent.
  double step = 0.0;
  for (std::int32_t v = 1; v < complex.vertexSlots(); ++v)
    if (v != complex.dummyVertex() && v - 1 != complex.dummyVertex())
      step += (complex.position(v) - complex.position(v - 1)).norm();
  EXPECT_LT(step / double(complex.vertexSlots()), 0.2 * 16.0 * grid.spacing().maxCoeff());

  // A vertex contact: two copies of one vertex, merged on output.
  const TetMesh touching = blocksMesh({{0, 0, 0, 1}, {1, 1, 1, 2}}, 4);
  RemeshComplex pinched(touching);
  ASSERT_TRUE(pinched.hasPinches());
  const TetMesh pinchedBefore = pinched.toTetMesh();
  pinched.reorderForLocality();
  EXPECT_EQ(pinched.checkConsistency(true), "");
  const TetMesh pinchedAfter = pinched.toTetMesh();
  EXPECT_EQ(pinchedAfter.positions.size(), pinchedBefore.positions.size());
  EXPECT_EQ(tetSet(pinchedAfter), tetSet(pinchedBefore));
  std::size_t copies = 0, pinnedVertices = 0;
  for (std::int32_t v = 0; v < pinched.vertexSlots(); ++v) {
    copies += pinched.pinchOf(v) >= 0 && pinched.pinchOf(v) != v;
    pinnedVertices += pinched.isPinned(v);
    if (pinched.pinchOf(v) >= 0) {
      EXPECT_EQ(pinched.position(pinched.pinchOf(v)), pinched.position(v));
      EXPECT_TRUE(pinched.isPinned(v));
    }
  }
  EXPECT_EQ(copies, 1u);
  EXPECT_GE(pinnedVertices, 2u);
}

}  // namespace
}  // namespace vox::remesh
