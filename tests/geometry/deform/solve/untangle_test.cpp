#include "geometry/deform/solve/untangle.h"
#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/voxel_tetrahedralization.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace vox {
namespace {

std::size_t inverted(const std::vector<Eigen::Vector3d>& p, const std::vector<Tet>& tets) {
  std::size_t n = 0;
  for (const Tet& t : tets) n += signedVolume(p, t) <= 0.0;
  return n;
}

// A bar of 24 x 4 x 4 unit voxels (six tets each); its first and last six
// voxels are bone (fixed), the last turned `degrees` about z through the
// bar's centre line at mid-length; the tissue between is left at rest, so
// the tets next to the turned end are inverted.
struct TurnedBar {
  TetMesh mesh;
  std::vector<std::uint8_t> free;
  std::vector<Eigen::Vector3d> posed;

  explicit TurnedBar(double degrees) {
    GridGeometry g;
    g.dims = {24, 4, 4};
    mesh = tetrahedralizeVoxels(LabelGrid(g, 1), {.includeBackground = false});
    const Eigen::Vector3d hinge(11.5, 1.5, 1.5);
    Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
    turn.translate(hinge);
    turn.rotate(Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()));
    turn.translate(-hinge);
    posed = mesh.positions;
    free.assign(posed.size(), 0);
    for (std::size_t v = 0; v < posed.size(); ++v) {
      const double x = posed[v].x() + 0.5;
      if (x >= 18.0 - 1e-9) posed[v] = turn * posed[v];
      else if (x > 6.0 + 1e-9) free[v] = 1;
    }
  }
};

TEST(Untangle, UnfoldsTheTissueBetweenTurnedBones) {
  TurnedBar bar(90.0);
  const std::size_t before = inverted(bar.posed, bar.mesh.tets);
  ASSERT_GT(before, 20u);
  const UntangleReport r = untangleTets(bar.mesh.positions, bar.mesh.tets, bar.free, {}, bar.posed);
  EXPECT_TRUE(r.untangled);
  EXPECT_EQ(r.invertedBefore, before);
  EXPECT_EQ(r.invertedAfter, 0u);
  EXPECT_EQ(inverted(bar.posed, bar.mesh.tets), 0u);
  EXPECT_GE(r.minRelativeVolumeAfter, UntangleOptions{}.minRelativeVolume);
  // The volume term keeps the bent tissue's volume.
  double restVolume = 0.0, posedVolume = 0.0;
  for (const Tet& t : bar.mesh.tets) {
    restVolume += signedVolume(bar.mesh.positions, t);
    posedVolume += signedVolume(bar.posed, t);
  }
  EXPECT_NEAR(posedVolume / restVolume, 1.0, 0.02);
  // The bones stayed where they were put.
  TurnedBar again(90.0);
  for (std::size_t v = 0; v < bar.posed.size(); ++v) {
    if (!bar.free[v]) {
      EXPECT_EQ(bar.posed[v], again.posed[v]);
    }
  }
}

// Ctrl-C stops the untangling at its next round; the positions are left
// as they were.
TEST(Untangle, CancellationStopsItAndLeavesThePositions) {
  TurnedBar bar(90.0);
  const std::vector<Eigen::Vector3d> before = bar.posed;
  cancellationRequested() = true;
  EXPECT_THROW(untangleTets(bar.mesh.positions, bar.mesh.tets, bar.free, {}, bar.posed), OperationCancelled);
  cancellationRequested() = false;
  EXPECT_EQ(bar.posed, before);
}

TEST(Untangle, SameResultOnOneThreadAndOnSeveral) {
  TurnedBar a(120.0), b(120.0);
  UntangleOptions one, three;
  one.threads = 1;
  three.threads = 3;
  const UntangleReport ra = untangleTets(a.mesh.positions, a.mesh.tets, a.free, {}, a.posed, one);
  const UntangleReport rb = untangleTets(b.mesh.positions, b.mesh.tets, b.free, {}, b.posed, three);
  EXPECT_TRUE(ra.untangled);
  EXPECT_EQ(ra.iterations, rb.iterations);
  EXPECT_EQ(a.posed, b.posed);
}

TEST(Untangle, AnchorsHoldTheirVertices) {
  TurnedBar loose(90.0), held(90.0);
  std::vector<UntangleAnchor> anchors;
  for (std::size_t v = 0; v < held.posed.size(); ++v)
    if (held.free[v] && held.posed[v].x() < 9.0) anchors.push_back({std::int32_t(v), held.posed[v], 100.0});
  ASSERT_FALSE(anchors.empty());
  untangleTets(loose.mesh.positions, loose.mesh.tets, loose.free, {}, loose.posed);
  const UntangleReport r = untangleTets(held.mesh.positions, held.mesh.tets, held.free, anchors, held.posed);
  EXPECT_TRUE(r.untangled);
  double driftLoose = 0.0, driftHeld = 0.0;
  for (const UntangleAnchor& a : anchors) {
    driftLoose += (loose.posed[std::size_t(a.vertex)] - a.target).norm();
    driftHeld += (held.posed[std::size_t(a.vertex)] - a.target).norm();
  }
  EXPECT_LT(driftHeld, 0.5 * driftLoose);
}

// A free vertex between two fixed triangles that the pose puts in the wrong
// order: no place of it makes both its tets positive. The positions stay
// as given.
TEST(Untangle, LeavesAnImpossibleTangleAsItWas) {
  const std::vector<Eigen::Vector3d> rest = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 2}, {1, 0, 2}, {0, 1, 2}, {0.3, 0.3, 1}};
  std::vector<Tet> tets = {{0, 1, 2, 6}, {3, 5, 4, 6}};
  ASSERT_GT(signedVolume(rest, tets[0]), 0.0);
  ASSERT_GT(signedVolume(rest, tets[1]), 0.0);
  std::vector<Eigen::Vector3d> posed = rest;
  for (int v = 3; v < 6; ++v) posed[std::size_t(v)].z() = -1.0;
  const std::vector<Eigen::Vector3d> given = posed;
  const std::vector<std::uint8_t> free = {0, 0, 0, 0, 0, 0, 1};
  const UntangleReport r = untangleTets(rest, tets, free, {}, posed);
  EXPECT_FALSE(r.untangled);
  EXPECT_EQ(r.invertedAfter, r.invertedBefore);
  EXPECT_EQ(posed, given);
}

TEST(Untangle, RefusesAFlatRestTet) {
  const std::vector<Eigen::Vector3d> rest = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  std::vector<Eigen::Vector3d> posed = rest;
  const std::vector<Tet> tets = {{0, 1, 2, 3}};
  const std::vector<std::uint8_t> free = {0, 0, 0, 1};
  EXPECT_THROW(untangleTets(rest, tets, free, {}, posed), InputError);
}

}  // namespace
}  // namespace vox
