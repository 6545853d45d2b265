// The posing session (the viewer's PoseEditor) opened with a joint pose on
// the synthetic skeleton figure: the joints are compiled against the
// figure's skeleton into selections the session edits (and saves), the
// first frame turns the hand as the kinematics do, another joint pose with
// the same separations loads into the session, and a joint pose without an
// organ table is a one-line InputError.

#include "geometry/deform/pose/pose_editor.h"
#include "geometry/error.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/synth.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace vox::skeleton {
namespace {

TEST(PoseSession, OpensAndLoadsJointPoses) {
  const LabelGrid grid = synthesize(SynthKind::SkeletonFigure, 128);
  const OrganTable organs = synthOrganTable(SynthKind::SkeletonFigure);
  const Pose arm = parsePose(R"({"joints": {"right_shoulder": {"abduction": 30}, "right_elbow": {"flexion": 40}}})", "arm.json");
  PoseEditor editor(grid, organs, arm, "arm.json");
  EXPECT_TRUE(editor.pose().joints.empty());
  ASSERT_GE(editor.pose().selections.size(), 3u);
  EXPECT_EQ(editor.pose().selections.front().name, "body parts at rest");
  EXPECT_FALSE(editor.pose().separations.empty());
  EXPECT_TRUE(editor.update());
  // The hand's TM vertices follow the kinematics' motion of the hand.
  const Skeleton s = buildSkeleton(grid, organs, {});
  const PartMotions m = partMotions(s.joints, arm.joints);
  const TetMesh& tm = editor.pipeline().transferMesh();
  double moved = 0.0;
  std::vector<double> error;
  for (std::size_t v = 0; v < tm.vertexCount(); ++v) {
    Index3 c;
    if (!grid.geometry().voxelAt(tm.positions[v], c) || Part(s.parts.parts.at(c[0], c[1], c[2])) != Part::RightHand) continue;
    const Eigen::Vector3d expected = m[std::size_t(Part::RightHand)] * tm.positions[v];
    error.push_back((editor.transferMeshPositions()[v] - expected).norm());
    moved = std::max(moved, (expected - tm.positions[v]).norm());
  }
  ASSERT_GT(error.size(), 3u);
  std::sort(error.begin(), error.end());
  EXPECT_GT(moved, 20.0);
  EXPECT_LT(error[error.size() / 2], 2.0);
  // Another joint pose with the same turned joints (the same separations) loads.
  const Pose more = parsePose(R"({"joints": {"right_shoulder": {"abduction": 45}, "right_elbow": {"flexion": 60}}})", "more.json");
  editor.loadPose(more, "more.json");
  EXPECT_TRUE(editor.update());
  EXPECT_TRUE(editor.canUndo());
  // Without the organ table there are no bones to build the skeleton from.
  try {
    PoseEditor bare(grid, std::nullopt, arm, "arm.json");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("arm.json: a pose with joints or body parts needs the grid's organ table"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vox::skeleton
