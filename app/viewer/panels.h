#pragma once
// The viewer's Dear ImGui panels: the column on the left (pose: picking,
// selections, rotation steps, ARAP, pose files; joints (joints_panel.h):
// the skeleton's joint angles; view: overlays, camera, shading,
// cutting planes; live figures; organs: visibility, masses, changes) and
// the export and status box at the bottom right. They act through the
// Viewer's public members.

#include "app/viewer/joints_panel.h"
#include "geometry/render/raycast_scene.h"

namespace vox::app {

class Viewer;

class Panels {
public:
  explicit Panels(int arapIterations) : arapIterations_(arapIterations) {}
  // Draws the panels of this frame (between ImGui::NewFrame and Render).
  void draw(Viewer& viewer);
  // The ARAP widgets from the edit state (after undo, redo, a script step).
  void readArap(int iterations) {
    arapIterations_ = iterations;
    arapOn_ = iterations > 0;
  }
  // Share of the view's resolution rendered while dragging.
  float interactiveScale() const { return interactiveScale_; }
  // The view's normals: smooth, or each voxel face's own (for inspecting
  // the voxels).
  SurfaceNormals surfaceNormals() const { return smoothShading_ ? SurfaceNormals::Smooth : SurfaceNormals::Faces; }

private:
  void posePanel(Viewer& viewer);
  void viewPanel(Viewer& viewer);
  void figuresPanel(Viewer& viewer);
  void organsPanel(Viewer& viewer);
  void exportBox(Viewer& viewer, int fw, int fh);

  JointsPanel joints_;
  bool arapOn_ = true;
  int arapIterations_ = 10;
  char organFilter_[64] = "";
  char posePath_[512] = "pose.json";
  char exportPath_[512] = "posed.nii.gz";
  bool exportPreserve_ = true;
  float rotateStep_ = 15.0f;
  int groupChoice_ = 2;
  float interactiveScale_ = 0.5f;
  bool smoothShading_ = RaycastShading{}.normals == SurfaceNormals::Smooth;
};

}  // namespace vox::app
