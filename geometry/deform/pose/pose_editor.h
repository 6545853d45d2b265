#pragma once
// PoseEditor: the interactive posing session behind `voxmorph view` (thesis
// 3.2.3 and chapter 5), without a window: the deformation pipeline built
// once, the pose being edited (a Pose, so that saving it gives a file that
// `voxmorph deform --pose` reproduces exactly), the vertices the user has
// picked, and undo / redo of every edit.
//
// The edited state is a Pose plus the view edits that undo also covers
// (cutting planes, hidden labels). A pose with joints (deform/pose/joint_pose.h)
// stays one: its joint angles are edited as such and it is compiled into
// selections for the pipeline (compiledPose()), the pose's own selections
// after the compiled ones, as `voxmorph deform` compiles it. Per frame,
// update() re-embeds the compiled pose (DeformationPipeline::setPose:
// handles, ARAP factorization, Green coordinates) only when its handle set
// changed (a selection added, removed, made fixed or moving; a joint turned
// from or back to its rest); a changed transform or joint angle costs one
// deformTo() frame (the compiled selections' shapes depend on which joints
// are turned, not on their angles, so only their transforms are redone).
// Picked vertices index the built cage (pipeline().builtCage()). Everything
// is in the grid frame: poses given to it must have been converted
// (poseInGridFrame), and the pose it holds says "frame": "grid".

#include "geometry/deform/solve/label_volumes.h"
#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/label_grid.h"
#include "geometry/organ_table.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vox::skeleton {
struct Skeleton;
struct Joint;
class BoneOverlapIndex;
}  // namespace vox::skeleton

namespace vox {

// What undo and redo restore.
struct EditState {
  Pose pose;
  std::vector<std::string> cuts;  // cutting planes as `render --cut` takes them
  std::vector<Label> hidden;      // labels not drawn
  int active = -1;                // selection the gizmo acts on (-1: none)
  int joint = -1;                 // joint the gizmo turns (a skeleton::JointId; -1: none)
  bool operator==(const EditState& other) const;
};

// Where the gizmo turns a joint: its centre and the axes of its degrees of
// freedom (skeleton::Joint::axis) as the parent part's motion has placed
// them, in the grid frame; a zero axis for a degree of freedom the joint lacks.
struct JointFrame {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  std::array<Eigen::Vector3d, 3> axes{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
};

// Live figures of the current frame (no rasterization).
struct PoseFigures {
  std::vector<double> restVoxels;      // per label: source voxels carried by the TM
  std::vector<double> deformedVoxels;  // per label: V'_l (label_volumes.h)
  std::size_t tmOutsideCage = 0;       // TM vertices placed by the propagation
  std::size_t tmInverted = 0;          // deformed TM tets with volume <= 0
  // A joint pose that presses two parts' bones through each other beyond
  // the deform run's default bound (skeleton::bonesThroughEachOther): what
  // an export is refused for.
  std::optional<std::string> bonesThroughEachOther;
  double deformMs = 0.0;               // last update()
};

class PoseEditor {
public:
  // setup: its separations shape the pre-processing (inset cage, TM cuts),
  // it is the first edit state. A setup with joints (or selections by body
  // part) builds the grid's skeleton (which needs the organ table) and is
  // compiled against it (deform/pose/joint_pose.h): its compiled separations
  // shape the pre-processing, and the session edits its joint angles and
  // its own selections, and saves them so. Throws what DeformationPipeline
  // and the compilation throw (InputError for bad input).
  // `prepared` (voxmorph prepare's rest state of this grid, already checked
  // against it: PreparedState::check) gives the skeleton, cage, envelope and
  // transfer mesh; one without the setup's separations is refused
  // (DeformationPipeline).
  PoseEditor(const LabelGrid& grid, std::optional<OrganTable> organs, const Pose& setup, const std::string& setupSource,
             const std::vector<LimbSeparation>& extraSeparations = {}, std::shared_ptr<PreparedState> prepared = nullptr);
  ~PoseEditor();

  const DeformationPipeline& pipeline() const { return *pipeline_; }
  const LabelGrid& grid() const { return grid_; }
  const std::optional<OrganTable>& organs() const { return organs_; }
  const EditState& state() const { return state_; }
  // The pose being edited, as it is saved (joints and the pose's own selections).
  const Pose& pose() const { return state_.pose; }
  // What the pipeline embeds as of the last update(): the pose itself, or
  // for a pose with joints (or selections by body part) its compilation,
  // whose selections end with the pose's own, from ownSelectionsAt().
  const Pose& compiledPose() const { return compiled_; }
  std::size_t ownSelectionsAt() const { return compiled_.selections.size() - std::min(compiled_.selections.size(), compiledFrom_.selections.size()); }

  // Picking (not an edit): built-cage vertex ids.
  const std::vector<std::int32_t>& picked() const { return picked_; }
  void pick(const std::vector<std::int32_t>& vertices, bool add);
  // The built-cage vertices nearest a label group (label_groups.h name);
  // InputError for an unknown name or a grid without organ table.
  std::vector<std::int32_t> groupVertices(const std::string& group) const;
  void clearPicked() { picked_.clear(); }

  // Edits (each one undoable). A selection from the picked vertices
  // ("points") or from a whole label group ("group"); the new selection
  // becomes the active one when it moves. Returns its index.
  int addPickedSelection(const std::string& name, bool fixed);
  int addGroupSelection(const std::string& group, bool fixed);
  void removeSelection(int index);
  void setActive(int index);
  // The active selection's transform, composed with a rotation about its
  // centre or a translation. beginDrag() records the undo step once for a
  // gesture that then calls these many times with `continuing` true.
  void beginDrag();
  void rotateActive(const Eigen::Vector3d& axis, double degrees, bool continuing = false);
  void translateActive(const Eigen::Vector3d& delta, bool continuing = false);
  void setActiveCenter(const Eigen::Vector3d& centre);
  void setArapIterations(int iterations);
  void setCuts(std::vector<std::string> cuts);
  void setHidden(std::vector<Label> hidden);
  // Joints (a session built from the skeleton; none otherwise): the
  // skeleton's joints with the pose's overrides, a joint's angle (degrees,
  // per skeleton::Dof; 0 when the pose does not turn it) and where it turns.
  bool turnsJoints() const { return skeleton_ != nullptr; }
  std::vector<skeleton::Joint> joints() const;
  double jointAngle(int joint, int dof) const;
  JointFrame jointFrame(int joint) const;
  // Edits: a joint's angle, checked against its range (checkJointAngle:
  // InputError naming the joint); `continuing` as for rotateActive. The
  // joint the gizmo turns (-1: none; selecting one leaves no active selection).
  void setJointAngle(int joint, int dof, double degrees, bool continuing = false);
  void selectJoint(int joint);
  // Replaces the selections with a pose file's (a joint pose compiled
  // against the session's skeleton; its separations must be the
  // ones the session was built with: they shape the pre-processing).
  void loadPose(const Pose& pose, const std::string& source);

  bool canUndo() const { return !undo_.empty(); }
  bool canRedo() const { return !redo_.empty(); }
  bool undo();
  bool redo();

  // Brings the pipeline to the current pose; returns true when the deformed
  // positions changed. With no selection the rest pose is shown.
  bool update();
  bool posed() const { return embedded_; }
  // Current TM positions (#V, grid frame) and per built-cage vertex positions.
  const std::vector<Eigen::Vector3d>& transferMeshPositions() const;
  std::vector<Eigen::Vector3d> builtCagePositions() const;
  // Per built-cage vertex: the selection of compiledPose() that holds it as a
  // handle (-1: free).
  std::vector<std::int32_t> handleOwners() const;
  const PoseFigures& figures() const { return figures_; }

private:
  void push();
  void refreshFigures();
  bool compiles(const Pose& pose) const;
  Pose compile(const Pose& pose, const std::string& source) const;
  void recompile();
  void setCompiled(Pose compiled);
  void findCompiledMotions();

  LabelGrid grid_;
  std::optional<OrganTable> organs_;
  std::string setupSource_;
  std::vector<PoseSeparation> separations_;
  std::unique_ptr<skeleton::Skeleton> skeleton_;  // built for a joint pose
  std::unique_ptr<skeleton::BoneOverlapIndex> bones_;  // its bones, for bonesThroughEachOther
  std::unique_ptr<DeformationPipeline> pipeline_;
  TetLabelVoxels tetVoxels_;
  EditState state_;
  std::vector<EditState> undo_, redo_;
  std::vector<std::int32_t> picked_;
  // The compiled pose and the edited pose it was compiled from; per compiled
  // joint selection (before the pose's own), the part whose motion and the
  // joint about whose centre its transform is (screwTransform), so that new
  // angles of the same turned joints only redo the transforms (-1: fixed).
  Pose compiled_, compiledFrom_;
  std::vector<std::array<int, 2>> compiledMotions_;
  bool retargetable_ = false;
  // The pose the pipeline was last embedded and deformed with.
  Pose embeddedPose_;
  bool embedded_ = false;
  bool deformed_ = false;
  PoseFigures figures_;
};

// Selections that give the same handles and differ at most in their
// transforms (so a new frame needs no re-embedding).
bool sameHandleSets(const Pose& a, const Pose& b);

}  // namespace vox
