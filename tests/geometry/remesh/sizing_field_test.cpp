// The adaptive sizing field (thesis 2.3.7, eq. 2.2): l_B on the interfaces,
// l_I at the deepest point, bad lengths refused; the adaptive remesher makes
// fewer tets than the uniform one at l_B with the same topology and
// interface bound, and a constant field reproduces the uniform remesher.

#include "geometry/error.h"
#include "geometry/mesh_quality.h"
#include "geometry/remesh/adaptive_voxel_tetrahedralization.h"
#include "geometry/remesh/edge_length_bounds.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh.h"
#include "geometry/remesh/remesh_report.h"
#include "geometry/remesh/sizing_field.h"
#include "geometry/synth.h"

#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <cmath>

namespace vox::remesh {
namespace {

// A cube of label 1 (voxels 4..27) in a 32^3 grid of 1 mm voxels, with a
// cube of label 2 (voxels 8..11) inside it near one corner.
LabelGrid cubeWithInclusion() {
  GridGeometry g;
  g.dims = {32, 32, 32};
  LabelGrid grid(g, 0);
  for (int k = 4; k < 28; ++k)
    for (int j = 4; j < 28; ++j)
      for (int i = 4; i < 28; ++i) grid.at(i, j, k) = (i >= 8 && i < 12 && j >= 8 && j < 12 && k >= 8 && k < 12) ? 2 : 1;
  return grid;
}

TEST(SizingField, BoundaryLengthOnInterfacesInteriorLengthDeepest) {
  const LabelGrid grid = cubeWithInclusion();
  const ScalarGrid d = normalizedInterfaceDistance(grid);
  float largest = 0.0f;
  for (std::size_t v = 0; v < d.values.size(); ++v) {
    EXPECT_GE(d.values[v], 0.0f);
    EXPECT_LE(d.values[v], 1.0f);
    if (grid.labels()[v] > 0) largest = std::max(largest, d.values[v]);
  }
  EXPECT_EQ(largest, 1.0f);

  const SizingField field = interfaceSizingField(grid, 2.0, 8.0);
  EXPECT_DOUBLE_EQ(field.minimum(), 2.0);
  EXPECT_DOUBLE_EQ(field.maximum(), 8.0);
  // On the outer interface (the face between voxels 3 and 4 along x, at
  // x = 3.5 mm) and on the inclusion's (between voxels 11 and 12): l_B.
  EXPECT_DOUBLE_EQ(field.at({3.5, 16.0, 16.0}), 2.0);
  EXPECT_DOUBLE_EQ(field.at({16.0, 3.5, 20.0}), 2.0);
  EXPECT_DOUBLE_EQ(field.at({11.5, 9.0, 10.0}), 2.0);
  // Deepest in label 1 (away from both interfaces): l_I.
  double deepest = 0.0;
  for (int k = 4; k < 28; ++k)
    for (int j = 4; j < 28; ++j)
      for (int i = 4; i < 28; ++i) deepest = std::max(deepest, field.at(grid.geometry().voxelCenter(i, j, k)));
  EXPECT_DOUBLE_EQ(deepest, 8.0);
  // Growing from the outer interface inwards, along a line that misses the
  // inclusion, until the opposite faces (7 voxels away) are nearer.
  double previous = 0.0;
  for (int i = 4; i <= 11; ++i) {
    const double l = field.at({double(i), 20.0, 20.0});
    EXPECT_GT(l, previous) << i;
    previous = l;
  }
  // A field of lengths, sampled in a rotated frame: the grid's frame is the
  // mesh frame turned by 90 degrees about z.
  Eigen::Matrix3d turn;
  turn << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const SizingField turned(field.lengths(), turn);
  EXPECT_DOUBLE_EQ(turned.at(turn.transpose() * Eigen::Vector3d(3.5, 16.0, 16.0)), 2.0);
}

TEST(SizingField, RefusesBadLengths) {
  const LabelGrid grid = cubeWithInclusion();
  EXPECT_THROW(interfaceSizingField(grid, 4.0, 2.0), InputError);   // l_B > l_I
  EXPECT_THROW(interfaceSizingField(grid, 0.0, 2.0), InputError);   // l_B not positive
  EXPECT_THROW(interfaceSizingField(grid, -1.0, 2.0), InputError);
  EXPECT_THROW(interfaceSizingField(grid, 1.0, std::nan("")), InputError);
  ScalarGrid lengths(grid.geometry(), 2.0f);
  lengths.at(5, 6, 7) = 0.0f;
  try {
    checkSizingGrid(lengths, "size.nii.gz");
    ADD_FAILURE() << "a zero length was accepted";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "size.nii.gz: voxel 7365 (5, 6, 7) holds 0: sizes must be finite and positive (mm)");
  }
  lengths.at(5, 6, 7) = -1.0f;
  EXPECT_THROW(SizingField{lengths}, InputError);
}

TEST(SizingField, MeshFieldMatchesTheGridField) {
  // The field of a tet mesh (voxmorph remesh) from its interface facets:
  // l_B at the interfaces, l_I somewhere deep inside.
  const LabelGrid grid = cubeWithInclusion();
  const TetMesh mesh = tetrahedralizeVoxelsAdaptive(grid, adaptiveOptionsForTarget(grid.geometry(), 2.0));
  const SizingField field = interfaceSizingField(mesh, 2.0, 8.0);
  EXPECT_NEAR(field.at({3.5, 16.0, 16.0}), 2.0, 0.5);
  EXPECT_NEAR(field.at({11.5, 9.0, 10.0}), 2.0, 0.5);
  EXPECT_GT(field.at({18.0, 18.0, 18.0}), 6.0);
  EXPECT_THROW(interfaceSizingField(mesh, 3.0, 2.0), InputError);
}

struct Meshed {
  TetMesh initial, output;
  RemeshReport report;
};

Meshed remeshCube(const LabelGrid& grid, double l, const SizingField* sizing) {
  Meshed m;
  AdaptiveTetrahedralizationOptions decomposition = adaptiveOptionsForTarget(grid.geometry(), l);
  if (sizing) decomposition.coarsestLevel = adaptiveOptionsForTarget(grid.geometry(), sizing->maximum()).coarsestLevel;
  m.initial = tetrahedralizeVoxelsAdaptive(grid, decomposition);
  RemeshOptions options;
  options.targetLength = l;
  options.sizing = sizing;
  options.iterations = 5;
  options.flipSmoothCycles = 2;
  RemeshStats stats;
  m.output = remeshTetMesh(m.initial, options, &stats);
  m.report = buildRemeshReport(m.initial, computeGridTopology(grid), m.output, l, stats);
  return m;
}

TEST(SizingField, AdaptiveMakesFewerTetsWithExactTopology) {
  const LabelGrid grid = cubeWithInclusion();
  const double lB = 2.0, lI = 8.0;
  const SizingField field = interfaceSizingField(grid, lB, lI);
  const Meshed uniform = remeshCube(grid, lB, nullptr);
  const Meshed adaptive = remeshCube(grid, lB, &field);
  EXPECT_TRUE(uniform.report.topologyDifferences.empty()) << test::joinLines(uniform.report.topologyDifferences);
  EXPECT_TRUE(adaptive.report.topologyDifferences.empty()) << test::joinLines(adaptive.report.topologyDifferences);
  EXPECT_EQ(adaptive.report.quality.inverted, 0u);
  EXPECT_GT(adaptive.report.quality.minDihedral, 5.0);
  // At least 1.5 times fewer tets here (the cube is 24 voxels across, l_I
  // 8: little room for large tets).
  EXPECT_LT(1.5 * double(adaptive.output.tetCount()), double(uniform.output.tetCount()))
      << adaptive.output.tetCount() << " adaptive, " << uniform.output.tetCount() << " uniform";
  // Interfaces within the uniform mesh's bound: at most a voxel and a half,
  // as the uniform remesher's tests ask.
  for (const LabelReport& l : adaptive.report.labels) EXPECT_LT(l.distance.hausdorff(), 1.5) << l.label;
}

TEST(SizingField, ConstantFieldReproducesTheUniformRemesher) {
  // The split and collapse tests read l at each edge's mid-point; a field
  // holding l everywhere must give the uniform result bit for bit.
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 16);
  const double l = 2.5;
  const SizingField constant(ScalarGrid(grid.geometry(), float(l)));
  const Meshed uniform = remeshCube(grid, l, nullptr);
  RemeshOptions options;
  options.targetLength = l;
  options.sizing = &constant;
  options.iterations = 5;
  options.flipSmoothCycles = 2;
  const TetMesh sized = remeshTetMesh(uniform.initial, options);
  ASSERT_EQ(sized.tetCount(), uniform.output.tetCount());
  EXPECT_EQ(sized.tets, uniform.output.tets);
  EXPECT_EQ(sized.positions, uniform.output.positions);
  EXPECT_EQ(sized.labels, uniform.output.labels);
}

TEST(SizingField, EdgeBoundsReadTheFieldAtTheMidpoint) {
  const LabelGrid grid = cubeWithInclusion();
  const SizingField field = interfaceSizingField(grid, 2.0, 8.0);
  const EdgeLengthBounds uniform = EdgeLengthBounds::forTarget(2.0);
  const EdgeLengthBounds sized = EdgeLengthBounds::forSizing(2.0, &field);
  const Eigen::Vector3d a(3.0, 16.0, 16.0), b(4.0, 16.0, 16.0);
  EXPECT_DOUBLE_EQ(uniform.emax2(a, b), sized.emax2(a, b));  // mid-point on the interface
  EXPECT_DOUBLE_EQ(uniform.emin2(a, b), sized.emin2(a, b));
  const double l = field.at({18.5, 18.5, 18.5});
  EXPECT_GT(l, 6.0);
  EXPECT_DOUBLE_EQ(sized.emax2({18.0, 18.0, 18.0}, {19.0, 19.0, 19.0}), std::pow(4.0 * l / 3.0, 2));
  EXPECT_DOUBLE_EQ(sized.emin2({18.0, 18.0, 18.0}, {19.0, 19.0, 19.0}), std::pow(4.0 * l / 5.0, 2));
  // The tests that skip the field outside its range agree with it, for
  // edges of every length across the field.
  int decidedByTheField = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d a(4.0 + (i * 7 % 24), 4.0 + (i * 11 % 24), 4.0 + (i * 13 % 24));
    const Eigen::Vector3d b = a + Eigen::Vector3d(0.37 * (i % 5), 0.21 * (i % 31), 0.05 * (i % 17));
    const double l2 = (a - b).squaredNorm();
    EXPECT_EQ(sized.aboveEmax(a, b, l2), l2 > sized.emax2(a, b)) << i;
    EXPECT_EQ(sized.reachesEmax(a, b, l2), l2 >= sized.emax2(a, b)) << i;
    EXPECT_EQ(sized.belowEmin(a, b, l2), l2 < sized.emin2(a, b)) << i;
    EXPECT_EQ(uniform.aboveEmax(a, b, l2), l2 > uniform.emax * uniform.emax) << i;
    EXPECT_EQ(uniform.belowEmin(a, b, l2), l2 < uniform.emin * uniform.emin) << i;
    if (l2 > std::pow(4.0 * 2.0 / 5.0, 2) && l2 < std::pow(4.0 * 8.0 / 3.0, 2)) ++decidedByTheField;
  }
  EXPECT_GT(decidedByTheField, 500);
}

}  // namespace
}  // namespace vox::remesh
