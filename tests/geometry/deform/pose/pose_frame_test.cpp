// World-frame poses on grids stored with axis flips: the pose converted to
// the grid frame selects the points the world pose selects (boxes, spheres,
// picked points) and moves them to the same world positions; "frame": "grid" poses pass unchanged, and an
// oblique grid refuses a world-frame pose.

#include "geometry/deform/pose/pose_frame.h"
#include "geometry/error.h"
#include "geometry/world_frame.h"

#include <gtest/gtest.h>

#include <random>

namespace vox {
namespace {

const char* kPose = R"({
  "selections": [
    {"name": "all", "box": {"min": [-100, -100, -100], "max": [100, 100, 100]}, "fixed": true},
    {"name": "arm", "box": {"min": [5, -20, 10], "max": [40, 30, 35]},
     "transform": {"rotation": {"axis": [0.3, 1, 0.2], "angle_deg": 35, "center": [12, 4, 20]}, "translation": [3, -2, 7]}},
    {"name": "ball", "sphere": {"center": [-10, 5, -8], "radius": 12}, "transform": {"translation": [0, 0, -4]}},
    {"name": "picked", "points": [[7, -3, 11], [-25, 40, 2]], "part": [1, 2, 3], "transform": {"translation": [1, 0, 0]}}
  ]
})";

TEST(PoseFrame, WorldPoseOnFlippedGridsSelectsAndMovesTheSamePoints) {
  const Pose world = parsePose(kPose, "pose.json");
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-60, 60);
  for (const Eigen::Vector3d flips : {Eigen::Vector3d(-1, -1, 1), Eigen::Vector3d(-1, 1, 1), Eigen::Vector3d(1, 1, -1)}) {
    GridGeometry g;
    g.dims = {10, 10, 10};
    g.direction = flips.asDiagonal();
    // A permutation of the axes too.
    g.direction = g.direction * Eigen::Matrix3d(Eigen::PermutationMatrix<3>(Eigen::Vector3i(1, 2, 0)));
    const Pose grid = poseInGridFrame(world, g, "pose.json");
    // Picked points and part seeds name the same places.
    const PoseSelection& picked = grid.selections.back();
    ASSERT_EQ(picked.points.size(), 2u);
    for (std::size_t i = 0; i < picked.points.size(); ++i)
      EXPECT_LT((gridToWorld(g, picked.points[i]) - world.selections.back().points[i]).norm(), 1e-12);
    EXPECT_LT((gridToWorld(g, *picked.part) - *world.selections.back().part).norm(), 1e-12);
    for (int n = 0; n < 2000; ++n) {
      const Eigen::Vector3d p(u(rng), u(rng), u(rng));  // grid frame
      const Eigen::Vector3d w = gridToWorld(g, p);
      for (std::size_t s = 0; s < world.selections.size(); ++s) {
        ASSERT_EQ(world.selections[s].contains(w), grid.selections[s].contains(p)) << s;
        const Eigen::Vector3d moved = gridToWorld(g, grid.selections[s].transform.apply(p));
        EXPECT_LT((moved - world.selections[s].transform.apply(w)).norm(), 1e-9);
      }
    }
  }
}

TEST(PoseFrame, GridFramePosesPassAndObliqueGridsRefuseWorldPoses) {
  Pose pose = parsePose(R"({"frame": "grid", "selections": [{"box": {"min": [0, 0, 0], "max": [1, 1, 1]}, "fixed": true}]})", "p.json");
  EXPECT_EQ(pose.frame, PoseFrame::Grid);
  GridGeometry g;
  g.dims = {4, 4, 4};
  g.direction = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_EQ(poseInGridFrame(pose, g, "p.json").selections[0].boxMax, Eigen::Vector3d(1, 1, 1));
  EXPECT_EQ(parsePose(poseToJson(pose), "again.json").frame, PoseFrame::Grid);
  pose.frame = PoseFrame::World;
  EXPECT_THROW(poseInGridFrame(pose, g, "p.json"), InputError);
  EXPECT_THROW(parsePose(R"({"frame": "ras", "selections": [{"box": {"min": [0, 0, 0], "max": [1, 1, 1]}, "fixed": true}]})", "p.json"),
               InputError);
}

}  // namespace
}  // namespace vox
