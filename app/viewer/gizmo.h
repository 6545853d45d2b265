#pragma once
// What the mouse does in the view: orbit, pan and zoom the camera, drag the
// gizmo of the active selection (rings rotate, arrows translate) or of the
// selected joint (a ring per degree of freedom, about the joint's axis at
// its centre, turns the joint within its range), slide a cutting
// plane by its handle, and pick built-cage vertices (click, ctrl-drag a
// rectangle; shift adds). Also the overlays drawn over the ray-cast view
// (cage, envelope, transfer mesh, planes, gizmo) and the pointer paths of
// scripted drags, which go through the same handling as the mouse.

#include "app/viewer/cut_controls.h"
#include "app/viewer/orbit_camera.h"
#include "geometry/render/camera.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace vox {
class PoseEditor;
struct RaycastMesh;
}  // namespace vox

namespace vox::app {

// Mouse and keys as the viewer's own handlers see them: from GLFW, or from a
// script (which then also feeds ImGui).
struct InputState {
  double x = 0, y = 0;
  bool down[3] = {false, false, false};
  double scroll = 0;
  bool scripted = false;
};

// The overlays shown.
struct Overlays {
  bool cage = true, envelope = false, tm = false;
};

enum class DragKind { None, Orbit, Pan, Rect, GizmoRotate, GizmoTranslate, CutPlane };

// A scripted drag: pointer positions, one a frame, with the left button held;
// the first must grab the expected handle.
struct PointerPath {
  std::vector<std::pair<double, double>> points;
  DragKind expected = DragKind::None;
};

// The built-cage vertices whose projection lies in the window rectangle
// x0..x1, y0..y1.
std::vector<std::int32_t> cageVerticesInRect(const CameraRays& rays, const std::vector<Eigen::Vector3d>& cage, double x0, double y0,
                                             double x1, double y1);

class Gizmo {
public:
  Gizmo(PoseEditor& editor, OrbitCamera& orbit, CutControls& cuts) : editor_(editor), orbit_(orbit), cuts_(cuts) {}

  // One frame of the pointer: starts, continues or ends a drag, and takes the
  // wheel. Over the UI (unless ignoreUi) nothing starts. Returns true when the
  // camera moved.
  bool handleMouse(const CameraRays& rays, InputState& input, bool ignoreUi);
  DragKind drag() const { return drag_; }
  // The overlays over the view (ImGui draw lists).
  void draw(const CameraRays& rays, const InputState& input, const Overlays& overlays, const RaycastMesh& mesh) const;

  // Scripted drags: about (rotate) or along (translate) the active
  // selection's gizmo axis (x, y, z: 0, 1, 2) or about the selected joint's
  // axis (its skeleton::Dof), and an axis plane's handle along its axis
  // (InputError when that plane is off or the gizmo lacks that handle).
  PointerPath rotatePath(const CameraRays& rays, int axis, double degrees, int steps) const;
  PointerPath translatePath(const CameraRays& rays, int axis, double mm, int steps) const;
  PointerPath cutPath(const CameraRays& rays, int axis, double mm, int steps) const;

  // What the gizmo acts on: its centre, the axes of its rings (a zero axis:
  // no ring) and whether it has arrows; none without an active selection or
  // a selected joint.
  struct Target {
    bool valid = false, arrows = false;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    std::array<Eigen::Vector3d, 3> axes{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  };
  Target target() const;

private:
  void drawGizmo(const CameraRays& rays) const;
  void press(const CameraRays& rays, double mx, double my, bool ctrl, bool otherButton);
  bool move(const CameraRays& rays, double mx, double my);
  void release(const CameraRays& rays, double mx, double my, bool shift);

  PoseEditor& editor_;
  OrbitCamera& orbit_;
  CutControls& cuts_;
  DragKind drag_ = DragKind::None;
  int dragAxis_ = -1;
  double dragX0_ = 0, dragY0_ = 0, lastX_ = 0, lastY_ = 0, dragAngle_ = 0;
  double jointStart_ = 0, jointTurn_ = 0;  // a joint drag: the angle at the press, the ring's turn since
};

}  // namespace vox::app
