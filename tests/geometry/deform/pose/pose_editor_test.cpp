// The viewer's posing session without a window, on the synthetic stick
// figure: picking a label group, fixing and moving selections, turning the
// moving one; undo restores the rest state and positions bit for bit, redo
// the posed ones; a turn re-uses the embedding (same handle sets); live
// figures follow the TM's Jacobians; the saved pose reads back to the same
// pose.

#include "geometry/deform/pose/pose_editor.h"
#include "geometry/skeleton/label_groups.h"
#include "geometry/error.h"
#include "geometry/synth.h"

#include <gtest/gtest.h>

namespace vox {
namespace {

struct Session {
  LabelGrid grid;
  std::unique_ptr<PoseEditor> editor;
};

Session& stickSession() {
  static Session s = [] {
    Session out;
    out.grid = synthesize(SynthKind::StickFigure, 64);
    out.grid.geometry().spacing = {2.0, 2.0, 4.0};
    out.editor = std::make_unique<PoseEditor>(out.grid, synthOrganTable(SynthKind::StickFigure), Pose{}, "session");
    return out;
  }();
  return s;
}

TEST(PoseEditor, EditsUndoToRestAndRedoToThePoseBitForBit) {
  PoseEditor& e = *stickSession().editor;
  const std::vector<Eigen::Vector3d> rest = e.pipeline().transferMesh().positions;
  EXPECT_FALSE(e.update());
  EXPECT_EQ(e.transferMeshPositions(), rest);
  const EditState initial = e.state();

  const std::vector<std::int32_t> arm = e.groupVertices("right_arm");
  ASSERT_FALSE(arm.empty());
  std::vector<std::int32_t> body;
  for (const char* g : {"trunk", "head", "left_arm", "right_leg", "left_leg"})
    for (std::int32_t v : e.groupVertices(g)) body.push_back(v);
  e.pick(body, false);
  e.addPickedSelection("body", true);
  e.pick(arm, false);
  const int moving = e.addPickedSelection("right arm", false);
  EXPECT_EQ(e.state().active, moving);
  e.clearPicked();
  EXPECT_TRUE(e.update());
  EXPECT_TRUE(e.posed());
  // Fixed and moving handles at rest: the rest pose.
  for (std::size_t v = 0; v < rest.size(); ++v) EXPECT_LT((e.transferMeshPositions()[v] - rest[v]).norm(), 1e-6);

  const Pose beforeTurn = e.pose();
  e.rotateActive(Eigen::Vector3d::UnitY(), 20.0);
  e.rotateActive(Eigen::Vector3d::UnitY(), 10.0);
  EXPECT_DOUBLE_EQ(e.pose().selections[std::size_t(moving)].transform.angleDeg, 30.0);
  EXPECT_TRUE(sameHandleSets(beforeTurn, e.pose()));
  EXPECT_TRUE(e.update());
  const std::vector<Eigen::Vector3d> posed = e.transferMeshPositions();
  double moved = 0.0;
  for (std::size_t v = 0; v < rest.size(); ++v) moved = std::max(moved, (posed[v] - rest[v]).norm());
  EXPECT_GT(moved, 5.0);
  const PoseFigures& f = e.figures();
  ASSERT_EQ(f.restVoxels.size(), f.deformedVoxels.size());
  EXPECT_GT(f.restVoxels[3], 0.0);
  EXPECT_NE(f.deformedVoxels[3], f.restVoxels[3]);
  e.setCuts({"x>60mm"});
  const EditState posedState = e.state();

  // Back to rest: four edits (two selections, two turns) and the cut.
  int undone = 0;
  while (e.undo()) ++undone;
  EXPECT_EQ(undone, 5);
  EXPECT_TRUE(e.state() == initial);
  EXPECT_TRUE(e.update());
  EXPECT_EQ(e.transferMeshPositions(), rest);
  EXPECT_EQ(e.figures().deformedVoxels, e.figures().restVoxels);

  while (e.redo()) {
  }
  EXPECT_TRUE(e.state() == posedState);
  EXPECT_TRUE(e.update());
  for (std::size_t v = 0; v < rest.size(); ++v) EXPECT_LT((e.transferMeshPositions()[v] - posed[v]).norm(), 1e-3);

  // The saved pose reads back to the same selections and transforms.
  const Pose saved = parsePose(poseToJson(e.pose()), "saved");
  EXPECT_TRUE((EditState{saved, {}, {}, -1} == EditState{e.pose(), {}, {}, -1}));
  const PoseHandles a = selectHandles(saved, e.pipeline().builtCage(), "saved", e.pipeline().cageGroups());
  const PoseHandles b = selectHandles(e.pose(), e.pipeline().builtCage(), "edited", e.pipeline().cageGroups());
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.selection, b.selection);
}

TEST(PoseEditor, RejectsWhatCannotBeEdited) {
  PoseEditor& e = *stickSession().editor;
  e.clearPicked();
  EXPECT_THROW(e.addPickedSelection("nothing", true), InputError);
  EXPECT_THROW(e.groupVertices("tail"), InputError);
  Pose separated;
  separated.separations.push_back({{Label(LabelGroup::RightArm), Label(LabelGroup::Trunk), std::nullopt}, std::nullopt});
  EXPECT_THROW(e.loadPose(separated, "other.json"), InputError);
}

}  // namespace
}  // namespace vox
