#pragma once
// The Viewer behind runViewer (viewer.h): it owns the window, the posing
// session (PoseEditor), the ray caster and the pieces around them (orbit
// camera, gizmo and picking, cutting planes, panels, export job, script
// runner) and runs the frame loop. The panels and the script act through
// its public members.

#include "app/viewer/articulated_view.h"
#include "app/viewer/cut_controls.h"
#include "app/viewer/export_job.h"
#include "app/viewer/gizmo.h"
#include "app/viewer/orbit_camera.h"
#include "app/viewer/panels.h"
#include "app/viewer/script_runner.h"
#include "app/viewer/viewer.h"
#include "app/viewer/viewer_window.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/label_grid.h"
#include "geometry/render/palette.h"
#include "gpu/image.h"

#include <fstream>
#include <memory>
#include <optional>
#include <string>

namespace vox {
class PoseEditor;
struct RaycastMesh;
namespace gpu {
class RaycastKernel;
}
}  // namespace vox

namespace vox::app {

struct FrameTimes {
  double deformMs = 0, raycastMs = 0, uiMs = 0, presentMs = 0, totalMs = 0;
  int renderWidth = 0, renderHeight = 0;
};

class Viewer {
public:
  explicit Viewer(const ViewerOptions& options);
  ~Viewer();
  // Runs frames until the window closes or the script quits.
  void run();

  PoseEditor& editor() { return *editor_; }
  const LabelGrid& grid() const { return grid_; }
  const Palette& palette() const { return palette_; }
  CutControls& cuts() { return cuts_; }
  Overlays& overlays() { return overlays_; }
  InputState& input() { return input_; }
  OrbitCamera& orbit() { return orbit_; }
  const Gizmo& gizmo() const { return *gizmo_; }
  ExportJob& exportJob() { return export_; }
  ArticulatedView& articulated() { return articulated_; }
  const FrameTimes& frameTimes() const { return frame_; }
  const std::string& statusText() const { return status_; }
  void framebufferSize(int& width, int& height) const { window_->framebufferSize(width, height); }
  gpu::Context& gpuContext() { return window_->context(); }
  // The rays of the view area as the window is now.
  CameraRays viewRays() const;

  // The widgets, the cutting planes and the palette from the edit state
  // (after undo, redo, a loaded pose or a script step); redraws.
  void applyView();
  void redraw() { viewDirty_ = true; }
  void fitCamera();    // frames the scene; redraws
  void resetCamera();  // the first camera; redraws
  void savePose(const std::string& path);
  void loadPose(const std::string& path);
  // The ray-cast view (window false: at full resolution, without overlays)
  // or the presented window with its panels.
  void screenshot(const std::string& path, bool window);
  // Starts the export in the background (its PNG is rendered first); a
  // refused request only sets the status.
  void startExport(const std::string& path, const std::string& report, const std::string& png, bool preserveVolumes);
  void status(const std::string& message);
  void quit() { quit_ = true; }
  // Solves the joints being edited on the articulated transfer mesh in the
  // background (a running solve is cancelled); its steps are shown once it
  // ends. Without turned joints only the status is set.
  void startArticulated();

private:
  void buildScene();
  void renderView(bool interactive);
  void handleKeys();

  ViewerOptions options_;
  std::optional<ScriptRunner> script_;
  LabelGrid grid_;
  std::unique_ptr<PoseEditor> editor_;
  Pose setupPose_;

  std::unique_ptr<ViewerWindow> window_;
  std::unique_ptr<RaycastMesh> mesh_;
  std::unique_ptr<gpu::RaycastKernel> kernel_;
  gpu::Image2D view_;
  Palette palette_;
  OrbitCamera orbit_, home_;
  Eigen::Vector3d sceneLo_, sceneHi_;
  CutControls cuts_;
  Overlays overlays_;
  bool viewDirty_ = true;

  std::unique_ptr<Panels> panels_;
  std::string status_;
  InputState input_;
  std::unique_ptr<Gizmo> gizmo_;
  FrameTimes frame_;
  std::unique_ptr<std::ofstream> frameLog_;
  ExportJob export_;
  // Last, so that its solve stops and its kernel goes before the grid, the
  // editor and the window.
  ArticulatedView articulated_;
  bool articulatedRunning_ = false;
  bool quit_ = false;
  int frameCount_ = 0;
};

}  // namespace vox::app
