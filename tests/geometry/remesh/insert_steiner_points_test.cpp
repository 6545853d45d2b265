// Vertex insertion at slivers whose vertices no operation may move: a sliver
// (a, b, c, d) between a roof (a, b, d, T), (b, c, d, T) and a floor
// (a, b, c, B), (a, c, d, B), every vertex on the outer boundary and where
// three or more labels meet, so the polish cannot move them.
#include "geometry/mesh_quality.h"
#include "geometry/remesh/insert_steiner_points.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh_complex.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <array>
#include <cmath>

namespace vox::remesh {
namespace {

// Labels of the sliver, the two roof tets and the two floor tets.
TetMesh sliverBetweenCorners(const std::array<std::int32_t, 5>& labels) {
  TetMesh m;
  const double h = 0.1;  // the sliver's thickness: its diagonals ac and bd are 2 long
  m.positions = {{1, 0, 0}, {0, 1, h}, {-1, 0, 0}, {0, -1, h}, {0, 0, 2}, {0, 0, -2}};
  m.tets = {{0, 1, 2, 3}, {0, 1, 3, 4}, {1, 2, 3, 4}, {0, 1, 2, 5}, {0, 2, 3, 5}};
  m.labels.assign(labels.begin(), labels.end());
  return m;
}

double minDihedral(const TetMesh& m) { return summarizeTetQuality(m).minDihedral; }

struct Inserted {
  TetMesh before, after;
  std::size_t count = 0;
};

Inserted insertInto(const TetMesh& mesh) {
  RemeshComplex complex(mesh);
  Inserted r;
  r.before = complex.toTetMesh();
  r.count = insertSteinerPoints(complex, SteinerOptions{});
  EXPECT_EQ(complex.checkConsistency(true), "");
  r.after = complex.toTetMesh();
  return r;
}

TEST(InsertSteinerPoints, LiftsASliverInsideOneLabel) {
  // bd runs inside label 1 (roof and sliver); ac is a 1-junction (labels 1, 2, 3).
  const Inserted r = insertInto(sliverBetweenCorners({1, 1, 1, 2, 3}));
  ASSERT_LT(minDihedral(r.before), 10.0);
  EXPECT_EQ(r.count, 1u);
  EXPECT_EQ(r.after.vertexCount(), r.before.vertexCount() + 1);
  EXPECT_GT(minDihedral(r.after), 20.0);
  EXPECT_TRUE(compareTopology(computeMeshTopology(r.before), computeMeshTopology(r.after)).empty());
  // The new vertex lies inside label 1: every label keeps its volume.
  const auto vb = summarizeTetQuality(r.before).volumePerLabel, va = summarizeTetQuality(r.after).volumePerLabel;
  for (const auto& [label, v] : vb) EXPECT_NEAR(va.at(label), v, 1e-12) << label;
}

TEST(InsertSteinerPoints, KeepsTheNewVertexOnTheInterfaceTheSliverMeets) {
  // bd lies on the 1|2 interface (facets b d c and b d T): the new vertex
  // stays in the plane of one of them.
  const Inserted r = insertInto(sliverBetweenCorners({1, 1, 2, 3, 4}));
  ASSERT_LT(minDihedral(r.before), 10.0);
  ASSERT_EQ(r.count, 1u);
  EXPECT_GT(minDihedral(r.after), minDihedral(r.before) + 5.0);
  EXPECT_TRUE(compareTopology(computeMeshTopology(r.before), computeMeshTopology(r.after)).empty());
  const Eigen::Vector3d p = r.after.positions.back();
  const auto& P = r.before.positions;
  auto offPlane = [&](int i, int j, int k) {
    const Eigen::Vector3d n = (P[std::size_t(j)] - P[std::size_t(i)]).cross(P[std::size_t(k)] - P[std::size_t(i)]).normalized();
    return std::abs(n.dot(p - P[std::size_t(i)]));
  };
  EXPECT_LT(std::min(offPlane(1, 3, 2), offPlane(1, 3, 4)), 1e-12) << p.transpose();
}

TEST(InsertSteinerPoints, LeavesThe1JunctionsOnlyWhenNothingOnThemHelps) {
  // Five labels: ac and bd are 1-junctions, the other edges lie on the outer
  // boundary. On the junctions a new vertex only slides along ac or bd,
  // which cannot lift the sliver; allowed off them, it can.
  const TetMesh mesh = sliverBetweenCorners({1, 2, 3, 4, 5});
  {
    RemeshComplex complex(mesh);
    const TetMesh before = complex.toTetMesh();
    SteinerOptions kept;
    kept.interfaceOffset = 0.0;
    EXPECT_EQ(insertSteinerPoints(complex, kept), 0u);
    EXPECT_EQ(complex.toTetMesh().positions, before.positions);
  }
  const Inserted r = insertInto(mesh);
  ASSERT_EQ(r.count, 1u);
  EXPECT_GT(minDihedral(r.after), minDihedral(r.before) + 5.0);
  EXPECT_TRUE(compareTopology(computeMeshTopology(r.before), computeMeshTopology(r.after)).empty());
  // Within a fifth of the split edge's length (2) of the 1-junction it split.
  const Eigen::Vector3d p = r.after.positions.back();
  const auto& P = r.before.positions;
  auto offLine = [&](int i, int j) {
    const Eigen::Vector3d e = (P[std::size_t(j)] - P[std::size_t(i)]).normalized();
    const Eigen::Vector3d x = p - P[std::size_t(i)];
    return (x - x.dot(e) * e).norm();
  };
  EXPECT_LE(std::min(offLine(0, 2), offLine(1, 3)), 0.4 + 1e-12) << p.transpose();
}

}  // namespace
}  // namespace vox::remesh
