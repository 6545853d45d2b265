#include "geometry/error.h"
#include "geometry/remesh/collapse_short_edges.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh_complex.h"
#include "geometry/remesh/split_long_edges.h"
#include "geometry/synth.h"
#include "geometry/voxel_tetrahedralization.h"

#include <gtest/gtest.h>

namespace vox::remesh {
namespace {

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

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

TEST(RemeshComplex, RejectsNonManifoldInput) {
  TetMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  // Two tets touching at one vertex only: the vertex is pinched.
  mesh.positions.push_back({-1, 0, 0});
  mesh.positions.push_back({0, -1, 0});
  mesh.positions.push_back({0, 0, -1});
  mesh.tets = {{0, 1, 2, 3}, {0, 5, 4, 6}};
  mesh.labels = {1, 1};
  ASSERT_GT(signedVolume(mesh.positions, mesh.tets[1]), 0.0);
  EXPECT_THROW(RemeshComplex(mesh, "pinched.mesh"), InputError);
}

TEST(MeshTopology, GridAndSixTetDecompositionAgree) {
  for (SynthKind kind : {SynthKind::NestedSpheres, SynthKind::JunctionSphere, SynthKind::StickFigure}) {
    const LabelGrid grid = synthesize(kind, 20);
    const MeshTopology fromGrid = computeGridTopology(grid);
    const MeshTopology fromMesh = computeMeshTopology(tetrahedralizeVoxels(grid, {.includeBackground = false}));
    EXPECT_EQ(joined(compareTopology(fromGrid, fromMesh)), "") << synthKindName(kind);
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
  EXPECT_EQ(joined(compareTopology(computeGridTopology(grid), computeMeshTopology(complex.toTetMesh()))), "");
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
    EXPECT_EQ(joined(compareTopology(computeGridTopology(grid), computeMeshTopology(complex.toTetMesh()))), "")
        << synthKindName(kind);
  }
}

}  // namespace
}  // namespace vox::remesh
