// The posing session (the viewer's PoseEditor) opened with a joint pose on
// the synthetic skeleton figure: the session keeps the joints (and saves
// them), compiled against the figure's skeleton into the selections the
// pipeline embeds; the first frame turns the hand as the kinematics do; a
// joint angle is an undoable edit whose new compilation equals
// compileJointPose's from scratch (new angles of the same turned joints
// change only transforms: no re-embedding); the gizmo's joint frame follows
// the parent's motion; an angle outside the range is a one-line error naming
// the joint; another joint pose with the same separations loads into the
// session, and a joint pose without an organ table is a one-line InputError.

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
  EXPECT_EQ(editor.pose().joints, arm.joints);
  EXPECT_TRUE(editor.pose().selections.empty());
  EXPECT_TRUE(editor.turnsJoints());
  ASSERT_GE(editor.compiledPose().selections.size(), 3u);
  EXPECT_EQ(editor.compiledPose().selections.front().name, "body parts at rest");
  EXPECT_EQ(editor.ownSelectionsAt(), editor.compiledPose().selections.size());
  EXPECT_FALSE(editor.compiledPose().separations.empty());
  EXPECT_TRUE(editor.pose().separations.empty());  // the compiled ones follow from the joints
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
  // Joint angles: each an edit; the same turned joints at new angles compile
  // to the same selections with new transforms, as from scratch.
  const auto shoulder = int(JointId::RightShoulder), elbow = int(JointId::RightElbow);
  const auto fromScratch = [&] {
    Pose p = compileJointPose(editor.pose(), s, "arm.json");
    p.separations = editor.compiledPose().separations;
    return p;
  };
  const Pose before = editor.compiledPose();
  editor.setJointAngle(shoulder, int(Dof::Abduction), 50.0);
  editor.beginDrag();
  for (double f = 41.0; f <= 60.0; f += 7.0) editor.setJointAngle(elbow, int(Dof::Flexion), f, true);
  editor.setJointAngle(shoulder, int(Dof::Flexion), 20.0);  // the shoulder turned already: same selections
  EXPECT_TRUE(editor.update());
  EXPECT_DOUBLE_EQ(editor.jointAngle(elbow, int(Dof::Flexion)), 55.0);
  EXPECT_TRUE(sameHandleSets(before, editor.compiledPose()));
  const Pose scratch = fromScratch();
  ASSERT_EQ(scratch.selections.size(), editor.compiledPose().selections.size());
  bool turned = false;
  for (std::size_t k = 0; k < scratch.selections.size(); ++k) {
    const PoseTransform &a = scratch.selections[k].transform, &b = editor.compiledPose().selections[k].transform;
    EXPECT_TRUE(a.axis == b.axis && a.angleDeg == b.angleDeg && a.center == b.center && a.translation == b.translation) << k;
    const PoseTransform& old = before.selections[k].transform;
    turned = turned || old.angleDeg != b.angleDeg;
  }
  EXPECT_TRUE(turned);
  // The gizmo turns the elbow where the shoulder put it, about its hinge.
  const std::vector<Joint> posed = posedJoints(s, editor.pose().joints, "arm.json");
  const PartMotions now = partMotions(posed, editor.pose().joints);
  const JointFrame frame = editor.jointFrame(elbow);
  for (const Joint& j : posed)
    if (j.id == JointId::RightElbow) {
      EXPECT_LT((frame.centre - now[std::size_t(Part::RightUpperArm)] * j.centre).norm(), 1e-9);
      EXPECT_LT((frame.axes[0] - now[std::size_t(Part::RightUpperArm)].linear() * j.axis(Dof::Flexion)).norm(), 1e-9);
    }
  EXPECT_EQ(frame.axes[1], Eigen::Vector3d::Zero());  // an elbow has no abduction
  // Undo: one step per edit, the drag's steps as one.
  ASSERT_TRUE(editor.undo());
  EXPECT_DOUBLE_EQ(editor.jointAngle(shoulder, int(Dof::Flexion)), 0.0);
  ASSERT_TRUE(editor.undo());
  EXPECT_DOUBLE_EQ(editor.jointAngle(elbow, int(Dof::Flexion)), 40.0);
  ASSERT_TRUE(editor.redo());
  ASSERT_TRUE(editor.redo());
  // The elbow back at rest: its selections go (the handle set changes).
  editor.setJointAngle(elbow, int(Dof::Flexion), 0.0);
  editor.update();
  EXPECT_FALSE(sameHandleSets(before, editor.compiledPose()));
  EXPECT_EQ(fromScratch().selections.size(), editor.compiledPose().selections.size());
  editor.undo();
  // Saved, the pose reads back with its joints.
  const Pose saved = parsePose(poseToJson(editor.pose()), "saved.json");
  EXPECT_EQ(saved.joints, editor.pose().joints);
  // Outside the range: the pose reader's one-line error, nothing changed.
  try {
    editor.setJointAngle(elbow, int(Dof::Flexion), 170.0);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "view: joint 'right_elbow' flexion 170 is outside its range [0, 150] degrees");
  }
  EXPECT_DOUBLE_EQ(editor.jointAngle(elbow, int(Dof::Flexion)), 55.0);
  // Selecting a joint leaves no active selection (the gizmo turns the joint).
  editor.selectJoint(shoulder);
  EXPECT_EQ(editor.state().joint, shoulder);
  EXPECT_EQ(editor.state().active, -1);
  // Another joint pose with the same turned joints (the same separations) loads.
  const Pose more = parsePose(R"({"joints": {"right_shoulder": {"abduction": 45}, "right_elbow": {"flexion": 60}}})", "more.json");
  editor.loadPose(more, "more.json");
  EXPECT_EQ(editor.pose().joints, more.joints);
  EXPECT_EQ(editor.state().joint, -1);
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
