#pragma once
// PoseEditor: the interactive posing session behind `voxmorph view` (thesis
// 3.2.3 and chapter 5), without a window: the deformation pipeline built
// once, the pose being edited (a Pose, so that saving it gives a file that
// `voxmorph deform --pose` reproduces exactly), the vertices the user has
// picked, and undo / redo of every edit.
//
// The edited state is a Pose plus the view edits that undo also covers
// (cutting planes, hidden labels). Per frame, update() re-embeds the pose
// (DeformationPipeline::setPose: handles, ARAP factorization, Green
// coordinates) only when its handle set changed (a selection added, removed,
// made fixed or moving); a changed transform costs one deformTo() frame.
// Picked vertices index the built cage (pipeline().builtCage()). Everything
// is in the grid frame: poses given to it must have been converted
// (poseInGridFrame), and the pose it holds says "frame": "grid".

#include "geometry/deform/solve/label_volumes.h"
#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/label_grid.h"
#include "geometry/organ_table.h"

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vox::skeleton {
struct Skeleton;
}

namespace vox {

// What undo and redo restore.
struct EditState {
  Pose pose;
  std::vector<std::string> cuts;  // cutting planes as `render --cut` takes them
  std::vector<Label> hidden;      // labels not drawn
  int active = -1;                // selection the gizmo acts on (-1: none)
  bool operator==(const EditState& other) const;
};

// Live figures of the current frame (no rasterization).
struct PoseFigures {
  std::vector<double> restVoxels;      // per label: source voxels carried by the TM
  std::vector<double> deformedVoxels;  // per label: V'_l (label_volumes.h)
  std::size_t tmOutsideCage = 0;       // TM vertices placed by the propagation
  std::size_t tmInverted = 0;          // deformed TM tets with volume <= 0
  double deformMs = 0.0;               // last update()
};

class PoseEditor {
public:
  // setup: its separations shape the pre-processing (inset cage, TM cuts),
  // its selections are the first edit state. A setup with joints (or
  // selections by body part) is compiled against the grid's skeleton first
  // (deform/pose/joint_pose.h, which needs the organ table): the session then
  // edits the compiled selections, and saves them. Throws what
  // DeformationPipeline and the compilation throw (InputError for bad input).
  PoseEditor(const LabelGrid& grid, std::optional<OrganTable> organs, const Pose& setup, const std::string& setupSource,
             const std::vector<LimbSeparation>& extraSeparations = {});
  ~PoseEditor();

  const DeformationPipeline& pipeline() const { return *pipeline_; }
  const LabelGrid& grid() const { return grid_; }
  const std::optional<OrganTable>& organs() const { return organs_; }
  const EditState& state() const { return state_; }
  const Pose& pose() const { return state_.pose; }

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
  // Per built-cage vertex: the selection that holds it as a handle (-1: free).
  std::vector<std::int32_t> handleOwners() const;
  const PoseFigures& figures() const { return figures_; }

private:
  void push();
  void refreshFigures();

  LabelGrid grid_;
  std::optional<OrganTable> organs_;
  std::string setupSource_;
  std::vector<PoseSeparation> separations_;
  std::unique_ptr<skeleton::Skeleton> skeleton_;  // built for a joint pose
  std::unique_ptr<DeformationPipeline> pipeline_;
  TetLabelVoxels tetVoxels_;
  EditState state_;
  std::vector<EditState> undo_, redo_;
  std::vector<std::int32_t> picked_;
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
