#include "app/viewer/viewer.h"

#include "app/command_line.h"
#include "app/viewer/viewer_app.h"
#include "geometry/deform/pose/pose_editor.h"
#include "geometry/deform/pose/pose_frame.h"
#include "geometry/deform/prepared_state.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/png_io.h"
#include "geometry/render/raycast_scene.h"
#include "gpu/kernels/raycast.h"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cstdio>

namespace vox::app {

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

Viewer::Viewer(const ViewerOptions& options) : options_(options) {
  if (!options.script.empty()) script_.emplace(readViewerScript(options.script), options.screenshotDir);
  grid_ = readGrid(options.grid);
  std::optional<OrganTable> organs;
  if (!options.organs.empty()) organs = OrganTable::read(options.organs);
  std::string setupSource = "view";
  if (!options.pose.empty()) {
    setupPose_ = poseInGridFrame(readPose(options.pose), grid_.geometry(), options.pose);
    setupSource = options.pose;
  }
  std::vector<LimbSeparation> extra;
  for (const std::string& s : options.separations) extra.push_back(parseSeparation(s));
  if (!setupPose_.separations.empty() || !extra.empty()) requireOrganTable(organs.has_value(), OrganTableNeed::Separation, setupSource);
  if (usesLabelGroups(setupPose_)) requireOrganTable(organs.has_value(), OrganTableNeed::LabelGroup, setupSource);
  if (!options.frameLog.empty()) checkWritablePath(options.frameLog);
  const int width = script_ && script_->script().width ? script_->script().width : options.width;
  const int height = script_ && script_->script().height ? script_->script().height : options.height;
  // The window first: without a display the session ends before the
  // pre-processing.
  window_ = std::make_unique<ViewerWindow>("voxmorph view - " + options_.grid, width, height, options_.vsync && !script_,
                                           options_.offscreen);
  window_->onScroll([this](double dy) {
    if (!input_.scripted) input_.scroll += dy;
  });
  std::fprintf(stderr, "view: pre-processing %s (cage, transfer mesh, embedding)\n", options.grid.c_str());
  std::shared_ptr<PreparedState> prepared;
  if (!options.prepared.empty()) {
    prepared = std::make_shared<PreparedState>(PreparedState::read(options.prepared));
    const std::string note = prepared->check(preparedInputs(options.grid, organs, options.organs, "", 1, grid_.dims()));
    if (!note.empty()) std::fprintf(stderr, "voxmorph: warning: %s\n", note.c_str());
  }
  editor_ = std::make_unique<PoseEditor>(grid_, organs, setupPose_, setupSource, extra, std::move(prepared));
  palette_ = organs ? Palette::fromOrgans(*organs, grid_.maxLabel()) : Palette(grid_.maxLabel());
  panels_ = std::make_unique<Panels>(editor_->pose().arapIterations);
  gizmo_ = std::make_unique<Gizmo>(*editor_, orbit_, cuts_);
  buildScene();
  window_->initImGui();
  if (!options.frameLog.empty()) {
    frameLog_ = std::make_unique<std::ofstream>(options.frameLog);
    *frameLog_ << "frame,render_width,render_height,deform_ms,raycast_ms,ui_ms,present_ms,total_ms\n";
  }
}

Viewer::~Viewer() {
  export_.cancel();
  export_.wait();
  window_->shutdownImGui();
  kernel_.reset();
  view_ = {};
}

void Viewer::buildScene() {
  mesh_ = std::make_unique<RaycastMesh>(buildRaycastMesh(editor_->pipeline().transferMesh(), grid_.geometry(), options_.grid));
  kernel_ = std::make_unique<gpu::RaycastKernel>(window_->context(), grid_, *mesh_);
  // Cutting planes start at the foreground box's middle.
  const RaycastFrame rest = prepareRaycastFrame(*mesh_, editor_->transferMeshPositions());
  sceneLo_ = rest.toGrid(rest.cellsLo);
  sceneHi_ = rest.toGrid(rest.cellsHi);
  cuts_.setBox(sceneLo_, sceneHi_);
  fitCamera();
  home_ = orbit_;
}

void Viewer::fitCamera() {
  orbit_.fit(sceneLo_, sceneHi_);
  viewDirty_ = true;
}

void Viewer::resetCamera() {
  orbit_ = home_;
  viewDirty_ = true;
}

CameraRays Viewer::viewRays() const {
  int fw = 0, fh = 0;
  window_->framebufferSize(fw, fh);
  return orbit_.viewRays(fw, fh);
}

void Viewer::applyView() {
  const EditState& s = editor_->state();
  cuts_.read(s.cuts);
  panels_->readArap(s.pose.arapIterations);
  for (std::size_t l = 1; l < palette_.size(); ++l) palette_.setVisible(Label(l), true);
  for (Label l : s.hidden)
    if (l < palette_.size()) palette_.setVisible(l, false);
  viewDirty_ = true;
}

void Viewer::renderView(bool interactive) {
  int fw = 0, fh = 0;
  window_->framebufferSize(fw, fh);
  const int viewW = std::max(1, fw - viewLeft(fw)), viewH = std::max(1, fh);
  const double scale = interactive ? double(panels_->interactiveScale()) : 1.0;
  const int w = std::max(16, int(viewW * scale)), h = std::max(16, int(viewH * scale));
  if (!view_.valid() || int(view_.width()) != w || int(view_.height()) != h) {
    kernel_->wait();  // the last frame may still write the old image
    if (articulated_.held()) articulated_.kernel().wait();
    view_ = gpu::Image2D(window_->context(), std::uint32_t(w), std::uint32_t(h));
  }
  const auto t0 = std::chrono::steady_clock::now();
  const CuttingPlanes& cuts = cuts_.planes(editor_->state().cuts);
  // The articulated solve's step while it belongs to the joints edited,
  // else the cage pipeline's frame.
  const bool articulated = articulated_.shows(editor_->pose().joints);
  const std::vector<Eigen::Vector3d>& positions = articulated ? articulated_.positions() : editor_->transferMeshPositions();
  const RaycastFrame frame = placeRaycastFrame(articulated ? articulated_.mesh() : *mesh_, positions);
  const RaycastView view = makeRaycastView(frame, orbit_.camera(w, h), cuts);
  RaycastShading shading;
  shading.normals = panels_->surfaceNormals();
  (articulated ? articulated_.kernel() : *kernel_).renderTo(view_, frame, positions, view, palette_, shading);
  frame_.raycastMs = msSince(t0);
  frame_.renderWidth = w;
  frame_.renderHeight = h;
}

void Viewer::status(const std::string& message) {
  status_ = message;
  std::fprintf(stderr, "view: %s\n", message.c_str());
}

void Viewer::savePose(const std::string& path) {
  writePose(path, editor_->pose());
  status("pose saved to " + path);
}

void Viewer::loadPose(const std::string& path) {
  editor_->loadPose(poseInGridFrame(readPose(path), grid_.geometry(), path), path);
  applyView();
  status("pose loaded from " + path);
}

void Viewer::screenshot(const std::string& path, bool window) {
  if (window) {
    // The next presented frame is read back (the window with its panels).
    RgbImage image;
    if (window_->present(view_, &image) == ViewerWindow::Presented::NoImage) return;
    writePng(path, image);
  } else {
    // The ray-cast view at full resolution, without overlays.
    renderView(false);
    writePng(path, view_.download());
  }
  status("screenshot " + path);
}

void Viewer::startExport(const std::string& path, const std::string& report, const std::string& png, bool preserveVolumes) {
  if (export_.running()) {
    status("an export is already running");
    return;
  }
  DeformGridRequest request;
  try {
    request = exportRequest(*editor_, options_.grid, options_.organs, path, report, preserveVolumes);
    if (!png.empty()) {
      checkWritablePath(png);
      renderView(false);
      writePng(png, view_.download());
    }
  } catch (const std::exception& e) {
    status(std::string("export refused: ") + e.what());
    return;
  }
  export_.start(std::move(request), report);
  status("exporting " + path);
}

void Viewer::startArticulated() {
  if (!editor_->turnsJoints() || editor_->pose().joints.empty() || !editor_->organs()) {
    status("the articulated mesh poses joints: open a joint pose with --organs");
    return;
  }
  articulated_.start(grid_, *editor_->organs(), editor_->pose(), options_.grid, options_.organs);
  articulatedRunning_ = true;
  status(articulated_.message());
}

void Viewer::handleKeys() {
  const ImGuiIO& io = ImGui::GetIO();
  if (io.WantCaptureKeyboard || script_) return;
  if (ImGui::IsKeyPressed(GLFW_KEY_Z) && io.KeyCtrl) {
    if (io.KeyShift) editor_->redo();
    else editor_->undo();
    applyView();
  }
  if (ImGui::IsKeyPressed(GLFW_KEY_Y) && io.KeyCtrl) {
    editor_->redo();
    applyView();
  }
  if (ImGui::IsKeyPressed(GLFW_KEY_F)) fitCamera();
  if (ImGui::IsKeyPressed(GLFW_KEY_R)) resetCamera();
}

void Viewer::run() {
  gpu::RenderTarget& target = window_->target();
  EditState lastState = editor_->state();
  bool lastDragging = false;
  while (!quit_ && !window_->closeRequested()) {
    const auto t0 = std::chrono::steady_clock::now();
    window_->pollEvents();
    input_.scripted = script_.has_value();
    if (!script_) window_->pointer(input_.x, input_.y, input_.down);
    const bool playing = script_ && script_->beginFrame(*this);
    int fw = 0, fh = 0;
    window_->framebufferSize(fw, fh);
    if (fw == 0 || fh == 0) {
      window_->waitEvents();
      continue;
    }
    if (std::uint32_t(fw) != target.width() || std::uint32_t(fh) != target.height()) {
      target.resize(std::uint32_t(fw), std::uint32_t(fh));
      viewDirty_ = true;
    }
    const CameraRays rays = orbit_.viewRays(fw, fh);

    const auto tUi = std::chrono::steady_clock::now();
    window_->newBackendFrame();
    ImGuiIO& io = ImGui::GetIO();
    if (script_) {
      io.MousePos = ImVec2(float(input_.x), float(input_.y));
      for (int b = 0; b < 3; ++b) io.MouseDown[b] = input_.down[b];
    }
    ImGui::NewFrame();
    handleKeys();
    if (gizmo_->handleMouse(rays, input_, script_ && script_->dragging())) viewDirty_ = true;
    if (playing && !script_->advance(gizmo_->drag())) {
      input_.down[0] = false;
      gizmo_->handleMouse(rays, input_, true);
      throw InputError("script", "gizmo drag: the gizmo handle is not under the pointer (is a moving selection active?)");
    }
    panels_->draw(*this);
    frame_.uiMs = msSince(tUi);

    // Deformation, then the ray casting when anything it shows changed.
    const auto tDeform = std::chrono::steady_clock::now();
    const bool moved = editor_->update();
    if (moved) frame_.deformMs = msSince(tDeform);
    if (articulatedRunning_ && !articulated_.running()) {
      articulatedRunning_ = false;
      if (articulated_.collect(window_->context(), grid_)) viewDirty_ = true;
      status(articulated_.message());
    }
    const bool dragging = gizmo_->drag() != DragKind::None;
    if (!(editor_->state() == lastState)) {
      lastState = editor_->state();
      viewDirty_ = true;
    }
    bool rendered = false;
    if (moved || viewDirty_ || (lastDragging && !dragging)) {
      renderView(dragging && panels_->interactiveScale() < 1.0f);
      viewDirty_ = false;
      rendered = true;
    }
    lastDragging = dragging;

    const auto tUi2 = std::chrono::steady_clock::now();
    // The cage, the envelope, the transfer mesh and the gizmo belong to the
    // live frame, not to the articulated solve's steps.
    if (!articulated_.shows(editor_->pose().joints)) gizmo_->draw(rays, input_, overlays_, *mesh_);
    ImGui::Render();
    frame_.uiMs += msSince(tUi2);

    const auto tPresent = std::chrono::steady_clock::now();
    const ViewerWindow::Presented presented = window_->present(view_);
    if (presented != ViewerWindow::Presented::Done) target.resize(std::uint32_t(fw), std::uint32_t(fh));
    if (presented == ViewerWindow::Presented::NoImage) continue;
    frame_.presentMs = msSince(tPresent);
    frame_.totalMs = msSince(t0);
    if (frameLog_ && rendered)
      *frameLog_ << frameCount_ << ',' << frame_.renderWidth << ',' << frame_.renderHeight << ',' << (moved ? frame_.deformMs : 0.0)
                 << ',' << frame_.raycastMs << ',' << frame_.uiMs << ',' << frame_.presentMs << ',' << frame_.totalMs << '\n';
    ++frameCount_;
  }
}

void runViewer(const ViewerOptions& options) {
  Viewer viewer(options);
  viewer.run();
}

}  // namespace vox::app
