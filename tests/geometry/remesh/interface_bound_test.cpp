// The interface bound's distances and its two one-sided tests, on a block of
// two labels whose interface is the plane x = 3.

#include "geometry/remesh/interface_bound.h"
#include "geometry/voxel_tetrahedralization.h"

#include <gtest/gtest.h>

#include <random>

namespace vox::remesh {
namespace {

TEST(InterfaceBound, PointTriangleDistanceMatchesDenseSampling) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  auto point = [&] { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d a = point(), b = point(), c = point(), p = point();
    double sampled = std::numeric_limits<double>::infinity();
    const int n = 200;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const Eigen::Vector3d x = a + (b - a) * (double(i) / n) + (c - a) * (double(j) / n);
        sampled = std::min(sampled, (x - p).norm());
      }
    const double exact = std::sqrt(pointTriangleDistance2(p, a, b, c));
    const double spacing = std::max({(b - a).norm(), (c - a).norm(), (c - b).norm()}) / n;
    EXPECT_LE(exact, sampled + 1e-12) << trial;
    EXPECT_GE(exact, sampled - spacing) << trial;
  }
}

struct TwoLabels {
  RemeshComplex complex;
  std::int32_t center = -1;  // the vertex at (3, 3, 3), inside the interface
  TwoLabels() {
    GridGeometry g;
    g.dims = {6, 6, 6};
    g.origin = Eigen::Vector3d::Constant(0.5);  // voxel corners at integers
    LabelGrid grid(g, 0);
    for (int k = 0; k < 6; ++k)
      for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 6; ++i) grid.at(i, j, k) = i < 3 ? 1 : 2;
    complex = RemeshComplex(tetrahedralizeVoxels(grid, {.includeBackground = false}));
    for (std::int32_t v = 0; v < complex.vertexSlots(); ++v)
      if (v != complex.dummyVertex() && complex.vertexAlive(v) &&
          (complex.position(v) - Eigen::Vector3d(3.0, 3.0, 3.0)).norm() < 1e-9)
        center = v;
  }
};

TEST(InterfaceBound, DistancesAreToTheInterfaceOfTheSameLabels) {
  const TwoLabels block;
  const InterfaceBound bound(block.complex, 1.0);
  const std::int32_t pair = bound.pairIndex(2, 1);
  ASSERT_GE(pair, 0);
  EXPECT_EQ(bound.pairIndex(1, 2), pair);
  EXPECT_EQ(bound.pairIndex(1, 3), -1);
  ASSERT_GE(bound.pairIndex(0, 1), 0);  // the outside
  EXPECT_TRUE(bound.within(pair, Eigen::Vector3d(3.9, 2.5, 1.0), 1.0));
  EXPECT_FALSE(bound.within(pair, Eigen::Vector3d(4.1, 2.5, 1.0), 1.0));
  EXPECT_FALSE(bound.within(-1, Eigen::Vector3d(3.0, 2.5, 1.0), 1.0));
  // The 1|2 interface ends at the block's faces: off its rim, the distance is to its edge.
  EXPECT_TRUE(bound.within(pair, Eigen::Vector3d(3.5, 6.5, 3.0), 0.75));
  EXPECT_FALSE(bound.within(pair, Eigen::Vector3d(3.5, 6.6, 3.0), 0.75));
}

TEST(InterfaceBound, MovesAreKeptWithinTheBoundBothWays) {
  const TwoLabels block;
  ASSERT_GE(block.center, 0);
  const InterfaceBound bound(block.complex, 0.5);
  std::vector<std::int32_t> tets;
  block.complex.incidentTets(block.center, tets);
  const Eigen::Vector3d c(3.0, 3.0, 3.0);
  EXPECT_TRUE(bound.keepsMove(block.complex, block.center, tets, c + Eigen::Vector3d(0.0, 0.3, -0.2)));  // in the plane
  EXPECT_TRUE(bound.keepsMove(block.complex, block.center, tets, c + Eigen::Vector3d(0.4, 0.0, 0.0)));
  EXPECT_FALSE(bound.keepsMove(block.complex, block.center, tets, c + Eigen::Vector3d(0.6, 0.0, 0.0)));

  // Output to input holds (the new facet lies on the interface), input to
  // output does not: the input the replaced facet covered is far from it.
  const std::int32_t pair = bound.pairIndex(1, 2);
  InterfaceFacet large{pair, {Eigen::Vector3d(3, 1, 1), Eigen::Vector3d(3, 5, 1), Eigen::Vector3d(3, 1, 5)}};
  InterfaceFacet small{pair, {Eigen::Vector3d(3, 1, 1), Eigen::Vector3d(3, 1.5, 1), Eigen::Vector3d(3, 1, 1.5)}};
  EXPECT_FALSE(bound.keeps({large}, {small}));
  EXPECT_TRUE(bound.keeps({small}, {large}));
  // A facet of labels the input never had next to each other is refused.
  InterfaceFacet unknown = large;
  unknown.pair = -1;
  EXPECT_FALSE(bound.keeps({large}, {large, unknown}));
  // An unchanged facet is not tested against the input, only covers it.
  InterfaceFacet far = large;
  for (Eigen::Vector3d& p : far.corners) p.x() += 2.0;
  EXPECT_FALSE(bound.keeps({large}, {large, far}));
  far.changed = false;
  EXPECT_TRUE(bound.keeps({large}, {large, far}));
}

}  // namespace
}  // namespace vox::remesh
