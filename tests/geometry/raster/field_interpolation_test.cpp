// CPU field interpolation: linear fields are reproduced exactly, voxels
// outside the mesh get the fill value, slab boundaries do not show.

#include "geometry/raster/field_interpolation.h"
#include "geometry/error.h"
#include "geometry/synth.h"
#include "tests/support/deformation_fixtures.h"

#include <gtest/gtest.h>

#include <limits>

namespace vox {
namespace {

TEST(FieldInterpolationCpu, LinearFieldIsReproducedInsideAndFillOutside) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 30);
  TetMesh mesh = test::coveringTransferMesh(grid, 3);
  // A non-rigid map so tets are irregular; the field is linear in the
  // deformed positions, hence reproduced exactly by barycentric interpolation.
  mesh.positions = test::deformPositions(mesh.positions, test::twist(test::gridCentre(grid.geometry()), 2.0));
  const Eigen::Vector3d gradient(0.3, -1.2, 0.7);
  std::vector<double> values;
  for (const auto& p : mesh.positions) values.push_back(gradient.dot(p) + 4.0);

  GridGeometry target = grid.geometry();
  target.spacing = {0.7, 0.8, 0.9};
  target.dims = {60, 50, 45};
  target.origin = grid.geometry().origin - Eigen::Vector3d(3, 2, 1);
  const float fill = -1000.0f;
  const ScalarGrid field = interpolateVertexField(mesh, values, target, {.fill = fill});
  ASSERT_EQ(field.values.size(), std::size_t(target.voxelCount()));
  std::int64_t inside = 0;
  for (std::int64_t v = 0; v < target.voxelCount(); ++v) {
    const Index3 q = target.ijk(v);
    const float got = field.values[std::size_t(v)];
    if (got == fill) continue;
    ++inside;
    const double expect = gradient.dot(target.voxelCenter(q[0], q[1], q[2])) + 4.0;
    ASSERT_NEAR(got, expect, 1e-4 * (1.0 + std::abs(expect))) << v;
  }
  // The sphere occupies about half of the bounding cube of the mesh.
  EXPECT_GT(inside, target.voxelCount() / 20);
  EXPECT_LT(inside, target.voxelCount());
}

TEST(FieldInterpolationCpu, ConstantPerTetGroupsFollowTheTieRule) {
  // Vertices duplicated per voxel cube: values jump across cube faces, and a
  // voxel centre on a shared face takes the lower tet's value.
  GridGeometry g;
  g.dims = {2, 1, 1};
  const TetMesh shared = tetrahedralizeVoxels(LabelGrid(g, 1));
  TetMesh split;
  std::vector<double> values;
  for (std::size_t t = 0; t < shared.tetCount(); ++t) {
    Tet tet;
    for (int k = 0; k < 4; ++k) {
      tet[std::size_t(k)] = std::int32_t(split.positions.size());
      split.positions.push_back(shared.positions[std::size_t(shared.tets[t][std::size_t(k)])]);
      values.push_back(double(t / 6 + 1));  // 1 in the first cube, 2 in the second
    }
    split.tets.push_back(tet);
    split.labels.push_back(1);
  }
  GridGeometry target;
  target.dims = {5, 1, 1};
  target.spacing = {0.5, 1, 1};
  target.origin = {-0.5, 0, 0};  // x = -0.5, 0, 0.5, 1, 1.5: 0.5 lies on the shared face
  const ScalarGrid field = interpolateVertexField(split, values, target, {.fill = 0.0f});
  EXPECT_EQ(field.values, (std::vector<float>{1, 1, 1, 2, 2}));
}

TEST(FieldInterpolationCpu, BadInputIsReported) {
  const TetMesh mesh = test::coveringTransferMesh(synthesize(SynthKind::NestedSpheres, 12), 3);
  GridGeometry target;
  target.dims = {4, 4, 4};
  std::vector<double> values(mesh.positions.size(), 1.0);
  EXPECT_THROW(interpolateVertexField(mesh, std::vector<double>(3, 1.0), target), InputError);
  values[1] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(interpolateVertexField(mesh, values, target), InputError);
}

}  // namespace
}  // namespace vox
