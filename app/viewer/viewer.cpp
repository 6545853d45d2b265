#include "app/viewer/viewer.h"

#include "app/command_line.h"
#include "app/viewer/viewer_script.h"
#include "geometry/deform/report/deformation_report.h"
#include "geometry/deform/pose/pose_editor.h"
#include "geometry/deform/pose/pose_frame.h"
#include "geometry/error.h"
#include "geometry/atomic_file.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/png_io.h"
#include "geometry/progress.h"
#include "geometry/render/camera.h"
#include "geometry/render/cutting_planes.h"
#include "geometry/render/palette.h"
#include "geometry/render/raycast_scene.h"
#include "gpu/command.h"
#include "gpu/context.h"
#include "geometry/deform/run/deform_run.h"
#include "gpu/raster_engines.h"
#include "gpu/image.h"
#include "gpu/kernels/raycast.h"
#include "gpu/swapchain.h"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_vulkan.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <unistd.h>

namespace vox::app {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kPanelWidth = 360.0f;
constexpr float kPickRadiusPx = 8.0f;

// An output path whose directory exists and takes new files (checked before
// the work that writes it).
void checkOutputPath(const std::string& path) {
  const std::filesystem::path p(path);
  const std::filesystem::path dir = p.has_parent_path() ? p.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) throw InputError(path, "its directory does not exist");
  const std::filesystem::path probe = dir / (".voxmorph-write-test-" + std::to_string(::getpid()));
  std::ofstream out(probe);
  if (!out) throw InputError(path, "its directory is not writable");
  out.close();
  std::filesystem::remove(probe, ec);
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Orbit camera around a target, z up (camera.h conventions: azimuth 0 looks
// along +y, azimuth 90 along -x).
struct OrbitCamera {
  Eigen::Vector3d target{0, 0, 0};
  double distance = 1000.0;
  double azimuth = 0.0, elevation = 0.0;  // degrees
  double fov = 35.0;

  Camera camera(int width, int height) const {
    const double az = azimuth * kPi / 180.0, el = elevation * kPi / 180.0;
    Camera c;
    c.target = target;
    c.eye = target + distance * Eigen::Vector3d(std::sin(az) * std::cos(el), -std::cos(az) * std::cos(el), std::sin(el));
    c.up = Eigen::Vector3d::UnitZ();
    c.fovYDegrees = fov;
    c.width = width;
    c.height = height;
    return c;
  }
};

// The ray-cast view fills the window right of the panel.
int viewLeft(int /*windowWidth*/) { return int(kPanelWidth); }

// Grid-frame point -> window pixel (x right, y down) for rays of the view
// area; false behind the eye.
bool project(const CameraRays& r, const Eigen::Vector3d& p, float& x, float& y) {
  const Eigen::Vector3d k = p - r.eye;
  const double t = k.dot(r.forward);
  if (t <= 1e-6) return false;
  const double sx = k.dot(r.right) / t, sy = k.dot(r.up) / t;
  x = float(viewLeft(r.width + int(kPanelWidth)) + (sx / (r.tanHalfFovY * r.aspect) + 1.0) * 0.5 * r.width);
  y = float((1.0 - sy / r.tanHalfFovY) * 0.5 * r.height);
  return true;
}

// The handle of axis cut a: the centre of the plane's section of the scene box.
Eigen::Vector3d cutHandle(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int a, double at) {
  Eigen::Vector3d c = 0.5 * (lo + hi);
  c[a] = at;
  return c;
}

ImU32 rgba(int r, int g, int b, int a = 255) { return IM_COL32(r, g, b, a); }

// Export on a worker thread: deformGrid with the viewer's pose. The
// progress sink is process-wide; only the worker's reports move the bar, and
// a cancel request ends the worker at its next report (the writers are
// atomic, so no partial file is left).
struct ExportCancelled {};

class ExportJob {
public:
  ~ExportJob() {
    cancel();
    if (thread_.joinable()) thread_.join();
    setProgressSink(nullptr);
  }
  bool running() const { return running_; }
  void start(DeformGridRequest request, std::string reportPath) {
    if (thread_.joinable()) thread_.join();
    cancel_ = false;
    running_ = true;
    fraction_ = 0.0;
    {
      std::lock_guard lock(mutex_);
      stage_ = "starting";
      message_.clear();
    }
    thread_ = std::thread([this, request = std::move(request), reportPath = std::move(reportPath)] {
      const std::thread::id me = std::this_thread::get_id();
      setProgressSink([this, me](std::string_view stage, double fraction) {
        if (std::this_thread::get_id() != me) return;
        if (cancel_) throw ExportCancelled{};
        fraction_ = fraction;
        std::lock_guard lock(mutex_);
        stage_ = std::string(stage);
      });
      std::string message;
      try {
        const DeformationReport report = deformGrid(request, *gpu::makeRasterEngines(false, request.warn));
        if (!reportPath.empty()) writeFileAtomic(reportPath, deformationReportJson(report));
        message = "exported " + request.output;
      } catch (const ExportCancelled&) {
        message = "export cancelled; nothing written";
      } catch (const std::exception& e) {
        message = std::string("export failed: ") + e.what();
      }
      setProgressSink(nullptr);
      {
        std::lock_guard lock(mutex_);
        message_ = message;
      }
      running_ = false;
    });
  }
  void cancel() { cancel_ = true; }
  void wait() {
    if (thread_.joinable()) thread_.join();
  }
  double fraction() const { return fraction_; }
  std::string stage() const {
    std::lock_guard lock(mutex_);
    return stage_;
  }
  std::string message() const {
    std::lock_guard lock(mutex_);
    return message_;
  }

private:
  std::thread thread_;
  std::atomic<bool> running_{false}, cancel_{false};
  std::atomic<double> fraction_{0.0};
  mutable std::mutex mutex_;
  std::string stage_, message_;
};

// Mouse and keys as the viewer's own handlers see them: from GLFW, or from a
// script (which then also feeds ImGui).
struct InputState {
  double x = 0, y = 0;
  bool down[3] = {false, false, false};
  double scroll = 0;
  bool scripted = false;
};

enum class DragKind { None, Orbit, Pan, Rect, GizmoRotate, GizmoTranslate, CutPlane };

struct Frame {
  double deformMs = 0, raycastMs = 0, uiMs = 0, presentMs = 0, totalMs = 0;
  int renderWidth = 0, renderHeight = 0;
};

class Viewer {
public:
  explicit Viewer(const ViewerOptions& options);
  ~Viewer();
  void run();

private:
  void initWindow(int width, int height);
  void initImGui();
  void buildScene();
  void fitCamera();
  void renderView(bool interactive);
  void drawOverlays(const CameraRays& rays);
  void drawGizmo(const CameraRays& rays);
  void handleMouse(const CameraRays& rays, bool ignoreUi = false);
  void panels();
  void applyView();
  void runScriptStep(const ScriptStep& step);
  // Scripted gizmo drags: a pointer path played one point per frame
  // through the same input handling as the mouse (press, moves, release).
  void gizmoRotate(int axis, double degrees, int steps);
  void gizmoTranslate(int axis, double mm, int steps);
  void cutDrag(int axis, double mm, int steps);
  void startExport(const std::string& path, const std::string& report, const std::string& png, bool preserve);
  void savePose(const std::string& path);
  void loadPose(const std::string& path);
  void screenshot(const std::string& path, bool window);
  std::string scriptPath(const std::string& path) const;
  void status(const std::string& message);
  Eigen::Vector3d activeCentre() const;
  std::vector<std::string> cutsFromPanel() const;

  ViewerOptions options_;
  std::optional<ViewerScript> script_;
  LabelGrid grid_;
  std::unique_ptr<PoseEditor> editor_;
  Pose setupPose_;

  GLFWwindow* window_ = nullptr;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  std::unique_ptr<gpu::Context> context_;
  std::unique_ptr<gpu::Swapchain> swapchain_;
  VkDescriptorPool imguiPool_ = VK_NULL_HANDLE;
  bool imguiReady_ = false;
  std::unique_ptr<RaycastMesh> mesh_;
  std::unique_ptr<gpu::RaycastKernel> kernel_;
  gpu::Image2D view_;
  Palette palette_;
  OrbitCamera orbit_, home_;
  Eigen::Vector3d sceneLo_, sceneHi_;
  bool viewDirty_ = true;

  // Panels.
  bool showCage_ = true, showEnvelope_ = false, showTm_ = false, arapOn_ = true;
  int arapIterations_ = 10;
  bool cutOn_[3] = {false, false, false};
  bool cutAbove_[3] = {true, true, true};
  float cutAt_[3] = {0, 0, 0};
  bool freeCutOn_ = false;
  float freeNormal_[3] = {1, 0, 0};
  float freeOffset_ = 0;
  char organFilter_[64] = "";
  char posePath_[512] = "pose.json";
  char exportPath_[512] = "posed.nii.gz";
  bool exportPreserve_ = true;
  float rotateStep_ = 15.0f;
  int groupChoice_ = 2;
  std::string status_;
  float interactiveScale_ = 0.5f;

  InputState input_;
  DragKind drag_ = DragKind::None;
  std::vector<std::pair<double, double>> dragPath_;
  std::size_t dragIndex_ = 0;
  DragKind dragExpected_ = DragKind::None;
  int dragAxis_ = -1;
  double dragX0_ = 0, dragY0_ = 0, lastX_ = 0, lastY_ = 0, dragAngle_ = 0;
  Frame frame_;
  std::unique_ptr<std::ofstream> frameLog_;
  ExportJob export_;
  bool quit_ = false;
  int frameCount_ = 0;
};

Viewer::Viewer(const ViewerOptions& options) : options_(options) {
  if (!options.script.empty()) script_ = readViewerScript(options.script);
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
  if (!options.frameLog.empty()) checkOutputPath(options.frameLog);
  const int width = script_ && script_->width ? script_->width : options.width;
  const int height = script_ && script_->height ? script_->height : options.height;
  // The window first: without a display the session ends before the
  // pre-processing.
  initWindow(width, height);
  std::fprintf(stderr, "view: pre-processing %s (cage, transfer mesh, embedding)\n", options.grid.c_str());
  editor_ = std::make_unique<PoseEditor>(grid_, organs, setupPose_, setupSource, extra);
  palette_ = organs ? Palette::fromOrgans(*organs, grid_.maxLabel()) : Palette(grid_.maxLabel());
  arapIterations_ = editor_->pose().arapIterations;
  buildScene();
  initImGui();
  if (!options.frameLog.empty()) {
    frameLog_ = std::make_unique<std::ofstream>(options.frameLog);
    *frameLog_ << "frame,render_width,render_height,deform_ms,raycast_ms,ui_ms,present_ms,total_ms\n";
  }
}

Viewer::~Viewer() {
  export_.cancel();
  export_.wait();
  if (context_) vkDeviceWaitIdle(context_->device());
  if (imguiReady_) {
    ImGui_ImplVulkan_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  kernel_.reset();
  view_ = {};
  swapchain_.reset();
  if (imguiPool_) vkDestroyDescriptorPool(context_->device(), imguiPool_, nullptr);
  if (surface_) vkDestroySurfaceKHR(context_->instance(), surface_, nullptr);
  context_.reset();
  if (window_) glfwDestroyWindow(window_);
  glfwTerminate();
}

void Viewer::initWindow(int width, int height) {
  glfwSetErrorCallback(nullptr);
  if (!glfwInit()) throw RuntimeFailure("view: no display (set DISPLAY, or run under xvfb-run); the window cannot open");
  if (!glfwVulkanSupported()) throw RuntimeFailure("view: GLFW finds no Vulkan loader for this display");
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  window_ = glfwCreateWindow(width, height, ("voxmorph view - " + options_.grid).c_str(), nullptr, nullptr);
  if (!window_) throw RuntimeFailure("view: the window could not be created on this display");
  gpu::ContextOptions co;
  std::uint32_t n = 0;
  const char** extensions = glfwGetRequiredInstanceExtensions(&n);
  co.instanceExtensions.assign(extensions, extensions + n);
  co.deviceExtensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  co.acceptQueue = [](VkInstance instance, VkPhysicalDevice pd, std::uint32_t family) {
    std::uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, nullptr);
    std::vector<VkQueueFamilyProperties> props(count);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, props.data());
    return family < count && (props[family].queueFlags & VK_QUEUE_GRAPHICS_BIT) &&
           glfwGetPhysicalDevicePresentationSupport(instance, pd, family) == GLFW_TRUE;
  };
  context_ = std::make_unique<gpu::Context>(co);
  if (glfwCreateWindowSurface(context_->instance(), window_, nullptr, &surface_) != VK_SUCCESS)
    throw RuntimeFailure("view: no Vulkan surface for the window");
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(window_, &fw, &fh);
  swapchain_ = std::make_unique<gpu::Swapchain>(*context_, surface_, std::uint32_t(fw), std::uint32_t(fh),
                                                gpu::SwapchainOptions{.vsync = options_.vsync && !script_});
  glfwSetWindowUserPointer(window_, this);
  glfwSetScrollCallback(window_, [](GLFWwindow* w, double, double dy) {
    auto* self = static_cast<Viewer*>(glfwGetWindowUserPointer(w));
    ImGui_ImplGlfw_ScrollCallback(w, 0, dy);
    if (!self->input_.scripted) self->input_.scroll += dy;
  });
}

void Viewer::initImGui() {
  const VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 16}};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
  pci.maxSets = 16;
  pci.poolSizeCount = 1;
  pci.pPoolSizes = sizes;
  if (vkCreateDescriptorPool(context_->device(), &pci, nullptr, &imguiPool_) != VK_SUCCESS)
    throw RuntimeFailure("view: cannot create the UI's descriptor pool");
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsDark();
  // The GLFW backend installs its callbacks and chains ours (scroll).
  ImGui_ImplGlfw_InitForVulkan(window_, true);
  ImGui_ImplVulkan_InitInfo info{};
  info.Instance = context_->instance();
  info.PhysicalDevice = context_->physicalDevice();
  info.Device = context_->device();
  info.QueueFamily = context_->queueFamily();
  info.Queue = context_->queue();
  info.PipelineCache = context_->pipelineCache();
  info.DescriptorPool = imguiPool_;
  info.MinImageCount = swapchain_->minImageCount();
  info.ImageCount = swapchain_->imageCount();
  info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
  ImGui_ImplVulkan_Init(&info, swapchain_->renderPass());
  gpu::CommandBatch batch(*context_);
  batch.record([](VkCommandBuffer cmd) { ImGui_ImplVulkan_CreateFontsTexture(cmd); });
  batch.submitAndWait();
  ImGui_ImplVulkan_DestroyFontUploadObjects();
  imguiReady_ = true;
}

void Viewer::buildScene() {
  mesh_ = std::make_unique<RaycastMesh>(buildRaycastMesh(editor_->pipeline().transferMesh(), grid_.geometry(), options_.grid));
  kernel_ = std::make_unique<gpu::RaycastKernel>(*context_, grid_, *mesh_);
  // Cutting planes start at the foreground box's middle.
  const RaycastFrame rest = prepareRaycastFrame(*mesh_, editor_->transferMeshPositions());
  sceneLo_ = rest.toGrid(rest.cellsLo);
  sceneHi_ = rest.toGrid(rest.cellsHi);
  for (int a = 0; a < 3; ++a) cutAt_[a] = float(0.5 * (sceneLo_[a] + sceneHi_[a]));
  freeOffset_ = float(0.5 * (sceneLo_[0] + sceneHi_[0]));
  fitCamera();
  home_ = orbit_;
}

void Viewer::fitCamera() {
  // The parsed default orbit fits the foreground box (render's framing).
  const Camera c = parseCamera("", sceneLo_, sceneHi_, 640, 480);
  orbit_.target = c.target;
  orbit_.distance = (c.eye - c.target).norm();
  orbit_.fov = c.fovYDegrees;
}

std::vector<std::string> Viewer::cutsFromPanel() const {
  std::vector<std::string> cuts;
  const char axes[3] = {'x', 'y', 'z'};
  char buf[128];
  for (int a = 0; a < 3; ++a)
    if (cutOn_[a]) {
      std::snprintf(buf, sizeof buf, "%c%c%.3fmm", axes[a], cutAbove_[a] ? '>' : '<', double(cutAt_[a]));
      cuts.push_back(buf);
    }
  if (freeCutOn_) {
    std::snprintf(buf, sizeof buf, "plane=%.6f,%.6f,%.6f,%.3f", double(freeNormal_[0]), double(freeNormal_[1]), double(freeNormal_[2]),
                  double(freeOffset_));
    cuts.push_back(buf);
  }
  return cuts;
}

// Panel widgets from the edit state (after undo / redo / script steps).
void Viewer::applyView() {
  const EditState& s = editor_->state();
  for (int a = 0; a < 3; ++a) cutOn_[a] = false;
  freeCutOn_ = false;
  for (const std::string& c : s.cuts) {
    CuttingPlanes one;
    one.add(c);
    for (int a = 0; a < 3; ++a)
      if (one.axis[a]) {
        cutOn_[a] = true;
        cutAbove_[a] = one.axis[a]->normal[a] > 0;
        cutAt_[a] = float(one.axis[a]->offset * (cutAbove_[a] ? 1.0 : -1.0));
      }
    if (one.free) {
      freeCutOn_ = true;
      for (int a = 0; a < 3; ++a) freeNormal_[a] = float(one.free->normal[a]);
      freeOffset_ = float(one.free->offset);
    }
  }
  arapIterations_ = s.pose.arapIterations;
  arapOn_ = arapIterations_ > 0;
  for (std::size_t l = 1; l < palette_.size(); ++l) palette_.setVisible(Label(l), true);
  for (Label l : s.hidden)
    if (l < palette_.size()) palette_.setVisible(l, false);
  viewDirty_ = true;
}

void Viewer::renderView(bool interactive) {
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(window_, &fw, &fh);
  const int viewW = std::max(1, fw - viewLeft(fw)), viewH = std::max(1, fh);
  const double scale = interactive ? double(interactiveScale_) : 1.0;
  const int w = std::max(16, int(viewW * scale)), h = std::max(16, int(viewH * scale));
  if (!view_.valid() || int(view_.width()) != w || int(view_.height()) != h) view_ = gpu::Image2D(*context_, std::uint32_t(w), std::uint32_t(h));
  const auto t0 = std::chrono::steady_clock::now();
  CuttingPlanes cuts;
  for (const std::string& c : editor_->state().cuts) cuts.add(c);
  const RaycastFrame frame = prepareRaycastFrame(*mesh_, editor_->transferMeshPositions());
  const RaycastView view = makeRaycastView(frame, orbit_.camera(w, h), cuts);
  kernel_->renderTo(view_, frame, view, palette_);
  frame_.raycastMs = msSince(t0);
  frame_.renderWidth = w;
  frame_.renderHeight = h;
}

Eigen::Vector3d Viewer::activeCentre() const {
  const int a = editor_->state().active;
  if (a < 0) return Eigen::Vector3d::Zero();
  const PoseTransform& t = editor_->pose().selections[std::size_t(a)].transform;
  return t.center + t.translation;
}

void Viewer::drawOverlays(const CameraRays& rays) {
  ImDrawList* dl = ImGui::GetBackgroundDrawList();
  const auto projectAll = [&](const std::vector<Eigen::Vector3d>& pts) {
    std::vector<ImVec2> out(pts.size(), ImVec2(-1e9f, -1e9f));
    for (std::size_t i = 0; i < pts.size(); ++i) {
      float x, y;
      if (project(rays, pts[i], x, y)) out[i] = ImVec2(x, y);
    }
    return out;
  };
  const auto drawTriangles = [&](const std::vector<ImVec2>& p, const std::vector<Tri>& tris, ImU32 colour, float width) {
    // Closed surfaces: every edge appears once in each direction.
    for (const Tri& t : tris)
      for (int k = 0; k < 3; ++k) {
        const std::int32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
        const ImVec2 &pa = p[std::size_t(a)], &pb = p[std::size_t(b)];
        if (a < b && pa.x > -1e8f && pb.x > -1e8f) dl->AddLine(pa, pb, colour, width);
      }
  };
  if (showTm_) {
    std::vector<Tri> faces;
    for (const BoundaryFace& f : mesh_->boundary) faces.push_back(f.vertices);
    drawTriangles(projectAll(editor_->transferMeshPositions()), faces, rgba(120, 220, 255, 90), 1.0f);
  }
  if (showEnvelope_ && !editor_->pipeline().envelope().triangles.empty()) {
    const std::vector<Eigen::Vector3d>& env = editor_->posed() ? editor_->pipeline().deformedEnvelope() : editor_->pipeline().envelope().positions;
    drawTriangles(projectAll(env), editor_->pipeline().envelope().triangles, rgba(255, 230, 120, 70), 1.0f);
  }
  if (showCage_) {
    const std::vector<ImVec2> p = projectAll(editor_->builtCagePositions());
    drawTriangles(p, editor_->pipeline().builtCage().triangles, rgba(200, 200, 210, 140), 1.0f);
    const std::vector<std::int32_t> owners = editor_->handleOwners();
    const std::vector<std::int32_t>& picked = editor_->picked();
    for (std::size_t v = 0; v < p.size(); ++v) {
      if (p[v].x < -1e8f) continue;
      ImU32 c = rgba(230, 230, 235, 200);  // free
      const std::int32_t o = owners[v];
      if (o >= 0) c = editor_->pose().selections[std::size_t(o)].fixed ? rgba(90, 140, 255) : (o == editor_->state().active ? rgba(255, 150, 40) : rgba(255, 220, 60));
      const bool isPicked = std::binary_search(picked.begin(), picked.end(), std::int32_t(v));
      dl->AddCircleFilled(p[v], isPicked ? 5.0f : 3.0f, isPicked ? rgba(255, 60, 200) : c);
    }
  }
  // Axis cuts: the plane's section of the scene box and a handle to slide it.
  for (int a = 0; a < 3; ++a) {
    if (!cutOn_[a]) continue;
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    ImVec2 corner[4];
    bool shown = true;
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector3d q;
      q[a] = cutAt_[a];
      q[u] = (k == 0 || k == 3) ? sceneLo_[u] : sceneHi_[u];
      q[v] = k < 2 ? sceneLo_[v] : sceneHi_[v];
      shown = shown && project(rays, q, corner[k].x, corner[k].y);
    }
    float hx, hy;
    if (shown && project(rays, cutHandle(sceneLo_, sceneHi_, a, cutAt_[a]), hx, hy)) {
      const ImU32 c = drag_ == DragKind::CutPlane && dragAxis_ == a ? rgba(255, 255, 255) : rgba(120, 255, 200, 200);
      dl->AddPolyline(corner, 4, c, ImDrawFlags_Closed, 1.5f);
      dl->AddCircleFilled(ImVec2(hx, hy), 7.0f, c);
    }
  }
  if (drag_ == DragKind::Rect) {
    dl->AddRect(ImVec2(float(dragX0_), float(dragY0_)), ImVec2(float(input_.x), float(input_.y)), rgba(255, 60, 200), 0, 0, 1.5f);
  }
  drawGizmo(rays);
}

// Gizmo radius in mm: a fixed share of the view at the centre's depth.
double gizmoRadiusMm(const CameraRays& rays, const Eigen::Vector3d& centre) {
  const double depth = std::max(1.0, (centre - rays.eye).dot(rays.forward));
  return 0.12 * depth * rays.tanHalfFovY * 2.0;
}

void Viewer::drawGizmo(const CameraRays& rays) {
  if (editor_->state().active < 0) return;
  ImDrawList* dl = ImGui::GetForegroundDrawList();
  const Eigen::Vector3d c = activeCentre();
  const double r = gizmoRadiusMm(rays, c);
  const ImU32 colours[3] = {rgba(235, 70, 70), rgba(80, 210, 90), rgba(70, 130, 245)};
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d u = Eigen::Vector3d::Unit((a + 1) % 3), v = Eigen::Vector3d::Unit((a + 2) % 3);
    std::vector<ImVec2> ring;
    for (int k = 0; k <= 64; ++k) {
      const double t = 2.0 * kPi * k / 64.0;
      float x, y;
      if (project(rays, c + r * (std::cos(t) * u + std::sin(t) * v), x, y)) ring.emplace_back(x, y);
    }
    const float width = (drag_ == DragKind::GizmoRotate && dragAxis_ == a) ? 4.0f : 2.0f;
    if (ring.size() > 1) dl->AddPolyline(ring.data(), int(ring.size()), colours[a], 0, width);
    float x0, y0, x1, y1;
    if (project(rays, c, x0, y0) && project(rays, c + 1.4 * r * Eigen::Vector3d::Unit(a), x1, y1)) {
      dl->AddLine(ImVec2(x0, y0), ImVec2(x1, y1), colours[a], (drag_ == DragKind::GizmoTranslate && dragAxis_ == a) ? 5.0f : 3.0f);
      dl->AddCircleFilled(ImVec2(x1, y1), 6.0f, colours[a]);
    }
  }
}

// The screen angle of the mouse about the gizmo centre, for a rotation about
// axis a: the signed angle in the ring's plane of the mouse ray's hit.
bool ringAngle(const CameraRays& rays, const Eigen::Vector3d& c, int a, double mx, double my, double& angle) {
  mx -= viewLeft(rays.width + int(kPanelWidth));
  const Eigen::Vector3d dir = rays.forward + ((2.0 * mx / rays.width - 1.0) * rays.tanHalfFovY * rays.aspect) * rays.right +
                              ((1.0 - 2.0 * my / rays.height) * rays.tanHalfFovY) * rays.up;
  const Eigen::Vector3d n = Eigen::Vector3d::Unit(a);
  const double denom = dir.dot(n);
  if (std::abs(denom) < 1e-9) return false;
  const double t = (c - rays.eye).dot(n) / denom;
  const Eigen::Vector3d q = rays.eye + t * dir - c;
  const Eigen::Vector3d u = Eigen::Vector3d::Unit((a + 1) % 3), v = Eigen::Vector3d::Unit((a + 2) % 3);
  angle = std::atan2(q.dot(v), q.dot(u)) * 180.0 / kPi;
  return true;
}

void Viewer::handleMouse(const CameraRays& rays, bool ignoreUi) {
  const ImGuiIO& io = ImGui::GetIO();
  const bool overUi = !ignoreUi && (io.WantCaptureMouse || input_.x < viewLeft(0)) && drag_ == DragKind::None;
  const double mx = input_.x, my = input_.y;
  if (input_.scroll != 0.0) {
    if (!overUi) {
      orbit_.distance *= std::pow(0.9, input_.scroll);
      viewDirty_ = true;
    }
    input_.scroll = 0.0;
  }
  const bool left = input_.down[0], right = input_.down[1], middle = input_.down[2];
  if (drag_ == DragKind::None && !overUi && (left || right || middle)) {
    dragX0_ = lastX_ = mx;
    dragY0_ = lastY_ = my;
    const bool ctrl = io.KeyCtrl;
    drag_ = DragKind::Orbit;
    if (right || middle) drag_ = DragKind::Pan;
    else if (ctrl) drag_ = DragKind::Rect;
    for (int a = 0; a < 3 && drag_ == DragKind::Orbit; ++a) {
      float hx, hy;
      if (cutOn_[a] && project(rays, cutHandle(sceneLo_, sceneHi_, a, cutAt_[a]), hx, hy) && std::hypot(hx - mx, hy - my) < 9.0) {
        drag_ = DragKind::CutPlane;
        dragAxis_ = a;
      }
    }
    if (drag_ == DragKind::CutPlane) {
    } else if (editor_->state().active >= 0 && drag_ == DragKind::Orbit) {
      // Gizmo handles first: arrow tips, then rings.
      const Eigen::Vector3d c = activeCentre();
      const double r = gizmoRadiusMm(rays, c);
      for (int a = 0; a < 3 && drag_ == DragKind::Orbit; ++a) {
        float x, y;
        if (project(rays, c + 1.4 * r * Eigen::Vector3d::Unit(a), x, y) && std::hypot(x - mx, y - my) < 10.0) {
          drag_ = DragKind::GizmoTranslate;
          dragAxis_ = a;
        }
      }
      // The ring nearest the pointer, within a few pixels.
      double nearest = 7.0;
      for (int a = 0; a < 3 && drag_ != DragKind::GizmoTranslate; ++a) {
        const Eigen::Vector3d u = Eigen::Vector3d::Unit((a + 1) % 3), v = Eigen::Vector3d::Unit((a + 2) % 3);
        for (int k = 0; k < 128; ++k) {
          const double t = 2.0 * kPi * k / 128.0;
          float x, y;
          if (project(rays, c + r * (std::cos(t) * u + std::sin(t) * v), x, y))
            if (const double d = std::hypot(x - mx, y - my); d < nearest) {
              nearest = d;
              drag_ = DragKind::GizmoRotate;
              dragAxis_ = a;
            }
        }
      }
      if (drag_ == DragKind::GizmoRotate) ringAngle(rays, c, dragAxis_, mx, my, dragAngle_);
      if (drag_ == DragKind::GizmoRotate || drag_ == DragKind::GizmoTranslate) editor_->beginDrag();
    }
  } else if (drag_ != DragKind::None && (left || right || middle)) {
    const double dx = mx - lastX_, dy = my - lastY_;
    switch (drag_) {
      case DragKind::Orbit:
        orbit_.azimuth -= 0.4 * dx;
        orbit_.elevation = std::clamp(orbit_.elevation + 0.4 * dy, -89.0, 89.0);
        viewDirty_ = dx != 0 || dy != 0 || viewDirty_;
        break;
      case DragKind::Pan: {
        const double mmPerPx = 2.0 * orbit_.distance * rays.tanHalfFovY / rays.height;
        orbit_.target += mmPerPx * (-dx * rays.right + dy * rays.up);
        viewDirty_ = true;
        break;
      }
      case DragKind::GizmoRotate: {
        double angle = 0.0;
        if (ringAngle(rays, activeCentre(), dragAxis_, mx, my, angle)) {
          double delta = angle - dragAngle_;
          while (delta > 180.0) delta -= 360.0;
          while (delta < -180.0) delta += 360.0;
          if (delta != 0.0) editor_->rotateActive(Eigen::Vector3d::Unit(dragAxis_), delta, true);
          dragAngle_ = angle;
        }
        break;
      }
      case DragKind::GizmoTranslate: {
        float x0, y0, x1, y1;
        const Eigen::Vector3d c = activeCentre();
        const double r = gizmoRadiusMm(rays, c);
        if (project(rays, c, x0, y0) && project(rays, c + r * Eigen::Vector3d::Unit(dragAxis_), x1, y1)) {
          const double ax = x1 - x0, ay = y1 - y0, len2 = ax * ax + ay * ay;
          if (len2 > 1e-6) {
            const double mm = (dx * ax + dy * ay) / len2 * r;
            if (mm != 0.0) editor_->translateActive(mm * Eigen::Vector3d::Unit(dragAxis_), true);
          }
        }
        break;
      }
      case DragKind::CutPlane: {
        // Along the plane's axis as it appears on screen.
        float x0, y0, x1, y1;
        const Eigen::Vector3d c = cutHandle(sceneLo_, sceneHi_, dragAxis_, cutAt_[dragAxis_]);
        const double r = gizmoRadiusMm(rays, c);
        if (project(rays, c, x0, y0) && project(rays, c + r * Eigen::Vector3d::Unit(dragAxis_), x1, y1)) {
          const double ax = x1 - x0, ay = y1 - y0, len2 = ax * ax + ay * ay;
          if (len2 > 1e-6) {
            const double mm = (dx * ax + dy * ay) / len2 * r;
            cutAt_[dragAxis_] = float(std::clamp(double(cutAt_[dragAxis_]) + mm, sceneLo_[dragAxis_], sceneHi_[dragAxis_]));
          }
        }
        break;
      }
      default: break;
    }
    lastX_ = mx;
    lastY_ = my;
  } else if (drag_ != DragKind::None) {
    // Released.
    if (drag_ == DragKind::CutPlane) editor_->setCuts(cutsFromPanel());
    const bool click = std::hypot(mx - dragX0_, my - dragY0_) < 3.0;
    const std::vector<Eigen::Vector3d> cage = editor_->builtCagePositions();
    if (drag_ == DragKind::Rect) {
      const double x0 = std::min(dragX0_, mx), x1 = std::max(dragX0_, mx), y0 = std::min(dragY0_, my), y1 = std::max(dragY0_, my);
      std::vector<std::int32_t> inside;
      for (std::size_t v = 0; v < cage.size(); ++v) {
        float x, y;
        if (project(rays, cage[v], x, y) && x >= x0 && x <= x1 && y >= y0 && y <= y1) inside.push_back(std::int32_t(v));
      }
      editor_->pick(inside, io.KeyShift);
    } else if (drag_ == DragKind::Orbit && click) {
      std::int32_t best = -1;
      double bestD = kPickRadiusPx;
      for (std::size_t v = 0; v < cage.size(); ++v) {
        float x, y;
        if (project(rays, cage[v], x, y))
          if (const double d = std::hypot(x - mx, y - my); d < bestD) {
            bestD = d;
            best = std::int32_t(v);
          }
      }
      if (best >= 0) editor_->pick({best}, io.KeyShift);
      else if (!io.KeyShift) editor_->clearPicked();
    }
    drag_ = DragKind::None;
    dragAxis_ = -1;
  }
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
    auto frame = swapchain_->beginFrame();
    if (!frame) return;
    swapchain_->blit(*frame, view_, std::uint32_t(viewLeft(int(swapchain_->width()))), RaycastShading{}.background);
    swapchain_->beginRenderPass(*frame);
    ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), frame->commands);
    swapchain_->endRenderPass(*frame);
    RgbImage image;
    swapchain_->endFrame(*frame, &image);
    writePng(path, image);
  } else {
    // The ray-cast view at full resolution, without overlays.
    renderView(false);
    writePng(path, view_.download());
  }
  status("screenshot " + path);
}

void Viewer::startExport(const std::string& path, const std::string& report, const std::string& png, bool preserve) {
  if (export_.running()) {
    status("an export is already running");
    return;
  }
  DeformGridRequest request;
  request.input = options_.grid;
  request.output = path;
  request.pose = editor_->pose();
  request.poseSource = "view";
  request.organs = editor_->organs();
  request.preserveVolumes = preserve;
  request.warn = [](const std::string& m) { std::fprintf(stderr, "view: warning: %s\n", m.c_str()); };
  try {
    checkDeformGridRequest(request);
    request.provenance = commandProvenance({{"grid", options_.grid}, {"organs", options_.organs}});
    addTextInput(request.provenance, "pose", "edited in the viewer (grid frame, as poseToJson writes it)", poseToJson(request.pose));
    checkOutputPath(path);
    if (!report.empty()) checkOutputPath(report);
    if (!png.empty()) {
      checkOutputPath(png);
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

std::string Viewer::scriptPath(const std::string& path) const {
  if (options_.screenshotDir.empty() || std::filesystem::path(path).is_absolute()) return path;
  return (std::filesystem::path(options_.screenshotDir) / path).string();
}

void Viewer::gizmoRotate(int axis, double degrees, int steps) {
  // Through the gizmo's drag code: press on the ring, move along it, release.
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(window_, &fw, &fh);
  const CameraRays rays = cameraRays(orbit_.camera(fw - viewLeft(fw), fh));
  const Eigen::Vector3d c = activeCentre();
  const double r = gizmoRadiusMm(rays, c);
  const Eigen::Vector3d u = Eigen::Vector3d::Unit((axis + 1) % 3), v = Eigen::Vector3d::Unit((axis + 2) % 3);
  // Start at the point of the ring farthest on screen from the other two.
  double start = 0.0, widest = -1.0;
  for (int k = 0; k < 32; ++k) {
    const double t = 2.0 * kPi * (k + 0.5) / 32.0;
    float x, y;
    if (!project(rays, c + r * (std::cos(t) * u + std::sin(t) * v), x, y)) continue;
    double clearance = 1e30;
    for (int b = 0; b < 3; ++b) {
      if (b == axis) continue;
      const Eigen::Vector3d bu = Eigen::Vector3d::Unit((b + 1) % 3), bv = Eigen::Vector3d::Unit((b + 2) % 3);
      for (int j = 0; j < 128; ++j) {
        const double s2 = 2.0 * kPi * j / 128.0;
        float bx, by;
        if (project(rays, c + r * (std::cos(s2) * bu + std::sin(s2) * bv), bx, by)) clearance = std::min(clearance, double(std::hypot(bx - x, by - y)));
      }
    }
    if (clearance > widest) {
      widest = clearance;
      start = t;
    }
  }
  const auto at = [&](double t) {
    float x = 0, y = 0;
    project(rays, c + r * (std::cos(t) * u + std::sin(t) * v), x, y);
    return std::pair<double, double>(x, y);
  };
  dragPath_.clear();
  for (int k = 0; k <= steps; ++k) dragPath_.push_back(at(start + degrees * kPi / 180.0 * k / steps));
  dragIndex_ = 0;
  dragExpected_ = DragKind::GizmoRotate;
}

void Viewer::gizmoTranslate(int axis, double mm, int steps) {
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(window_, &fw, &fh);
  const CameraRays rays = cameraRays(orbit_.camera(fw - viewLeft(fw), fh));
  const Eigen::Vector3d c = activeCentre();
  const double r = gizmoRadiusMm(rays, c);
  float x0, y0, x1, y1;
  project(rays, c, x0, y0);
  project(rays, c + 1.4 * r * Eigen::Vector3d::Unit(axis), x1, y1);
  const double pxPerMm = std::hypot(x1 - x0, y1 - y0) / (1.4 * r);
  dragPath_.clear();
  for (int k = 0; k <= steps; ++k) {
    const double f = mm * pxPerMm * k / steps / std::hypot(x1 - x0, y1 - y0);
    dragPath_.emplace_back(x1 + f * (x1 - x0), y1 + f * (y1 - y0));
  }
  dragIndex_ = 0;
  dragExpected_ = DragKind::GizmoTranslate;
}

void Viewer::cutDrag(int axis, double mm, int steps) {
  // Press on the plane's handle, drag it along its axis, release.
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(window_, &fw, &fh);
  const CameraRays rays = cameraRays(orbit_.camera(fw - viewLeft(fw), fh));
  if (!cutOn_[axis]) throw InputError("script", "cut_drag: that axis has no cutting plane");
  const Eigen::Vector3d c = cutHandle(sceneLo_, sceneHi_, axis, cutAt_[axis]);
  dragPath_.clear();
  for (int k = 0; k <= steps; ++k) {
    float x = 0, y = 0;
    project(rays, c + (mm * k / steps) * Eigen::Vector3d::Unit(axis), x, y);
    dragPath_.emplace_back(x, y);
  }
  dragIndex_ = 0;
  dragExpected_ = DragKind::CutPlane;
}

void Viewer::runScriptStep(const ScriptStep& s) {
  const std::string& k = s.step;
  if (k == "mouse_move") {
    input_.x = s.numbers[0];
    input_.y = s.numbers[1];
  } else if (k == "mouse_down" || k == "mouse_up") {
    if (s.numbers.size() == 2) {
      input_.x = s.numbers[0];
      input_.y = s.numbers[1];
    }
    input_.down[std::clamp(s.button, 0, 2)] = k == "mouse_down";
  } else if (k == "scroll") {
    input_.scroll += s.value;
  } else if (k == "key") {
    if (s.text == "Z" && s.flag) editor_->undo();
    else if (s.text == "Y" && s.flag) editor_->redo();
    else if (s.text == "F") fitCamera();
    else if (s.text == "R") orbit_ = home_;
    else throw InputError("script", "key '" + s.text + "' has no binding");
    applyView();
  } else if (k == "select_group") {
    editor_->pick(editor_->groupVertices(s.text), s.flag);
  } else if (k == "pick_rect") {
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window_, &fw, &fh);
    const CameraRays rays = cameraRays(orbit_.camera(fw - viewLeft(fw), fh));
    const std::vector<Eigen::Vector3d> cage = editor_->builtCagePositions();
    std::vector<std::int32_t> inside;
    for (std::size_t v = 0; v < cage.size(); ++v) {
      float x, y;
      if (project(rays, cage[v], x, y) && x >= s.numbers[0] && x <= s.numbers[2] && y >= s.numbers[1] && y <= s.numbers[3])
        inside.push_back(std::int32_t(v));
    }
    editor_->pick(inside, s.flag);
  } else if (k == "pick_clear") {
    editor_->clearPicked();
  } else if (k == "fix" || k == "move") {
    editor_->addPickedSelection(s.text.empty() ? (k == "fix" ? "fixed" : "moving") : s.text, k == "fix");
    if (k == "move" && s.numbers.size() == 3) editor_->setActiveCenter({s.numbers[0], s.numbers[1], s.numbers[2]});
    editor_->clearPicked();
  } else if (k == "gizmo_rotate") {
    gizmoRotate(s.text[0] - 'x', s.value, s.substeps);
  } else if (k == "gizmo_translate") {
    gizmoTranslate(s.text[0] - 'x', s.value, s.substeps);
  } else if (k == "cut_drag") {
    cutDrag(s.text[0] - 'x', s.value, s.substeps);
  } else if (k == "toggle") {
    if (s.text == "cage") showCage_ = s.flag;
    else if (s.text == "envelope") showEnvelope_ = s.flag;
    else if (s.text == "tm") showTm_ = s.flag;
    else throw InputError("script", "toggle: unknown overlay '" + s.text + "' (cage, envelope, tm)");
  } else if (k == "arap") {
    editor_->setArapIterations(s.flag ? int(s.value > 0 ? s.value : 10) : 0);
    applyView();
  } else if (k == "cut") {
    for (const std::string& c : s.list) CuttingPlanes().add(c);
    editor_->setCuts(s.list);
    applyView();
  } else if (k == "hide") {
    std::vector<Label> hidden;
    Palette probe = palette_;
    for (std::size_t l = 1; l < probe.size(); ++l) probe.setVisible(Label(l), true);
    std::string list;
    for (const std::string& o : s.list) list += (list.empty() ? "" : ",") + o;
    if (!list.empty()) probe.hide(list, editor_->organs() ? &*editor_->organs() : nullptr);
    for (std::size_t l = 1; l < probe.size(); ++l)
      if (!probe.visible(Label(l))) hidden.push_back(Label(l));
    editor_->setHidden(hidden);
    applyView();
  } else if (k == "undo" || k == "redo") {
    for (int i = 0; i < s.count; ++i)
      if (!(k == "undo" ? editor_->undo() : editor_->redo())) throw InputError("script", "nothing to " + k);
    applyView();
  } else if (k == "save_pose") {
    savePose(s.path);
  } else if (k == "load_pose") {
    loadPose(s.path);
  } else if (k == "export") {
    startExport(s.path, s.report, s.png, s.flag);
    if (!s.background) {
      export_.wait();
      status(export_.message());
      if (export_.message().rfind("exported", 0) != 0) throw RuntimeFailure("view: " + export_.message());
    }
  } else if (k == "cancel_export") {
    export_.cancel();
    export_.wait();
    status(export_.message());
  } else if (k == "screenshot") {
    screenshot(scriptPath(s.path), s.flag);
  } else if (k == "camera") {
    if (s.value != 0.0 || !s.numbers.empty()) orbit_.azimuth = s.value;
    if (!s.numbers.empty()) orbit_.elevation = s.numbers[0];
    viewDirty_ = true;
  } else if (k == "wait") {
  } else if (k == "quit") {
    quit_ = true;
  }
}

void Viewer::panels() {
  ImGui::SetNextWindowPos(ImVec2(0, 0), ImGuiCond_Always);
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(window_, &fw, &fh);
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, float(fh)), ImGuiCond_Always);
  ImGui::Begin("voxmorph", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);

  if (ImGui::CollapsingHeader("Pose", ImGuiTreeNodeFlags_DefaultOpen)) {
    if (ImGui::Button("Undo") ) { editor_->undo(); applyView(); }
    ImGui::SameLine();
    if (ImGui::Button("Redo")) { editor_->redo(); applyView(); }
    ImGui::SameLine();
    ImGui::Text("picked: %zu", editor_->picked().size());
    static const char* groups[] = {"trunk", "head", "right_arm", "left_arm", "right_leg", "left_leg"};
    ImGui::SetNextItemWidth(130);
    ImGui::Combo("##group", &groupChoice_, groups, 6);
    ImGui::SameLine();
    if (ImGui::Button("Pick group")) {
      try {
        editor_->pick(editor_->groupVertices(groups[groupChoice_]), ImGui::GetIO().KeyShift);
      } catch (const std::exception& e) {
        status(e.what());
      }
    }
    if (ImGui::Button("Fix picked") && !editor_->picked().empty()) {
      editor_->addPickedSelection("fixed " + std::to_string(editor_->pose().selections.size() + 1), true);
      editor_->clearPicked();
    }
    ImGui::SameLine();
    if (ImGui::Button("Move picked") && !editor_->picked().empty()) {
      editor_->addPickedSelection("moving " + std::to_string(editor_->pose().selections.size() + 1), false);
      editor_->clearPicked();
    }
    ImGui::SameLine();
    if (ImGui::Button("Clear")) editor_->clearPicked();
    for (std::size_t k = 0; k < editor_->pose().selections.size(); ++k) {
      const PoseSelection& s = editor_->pose().selections[k];
      ImGui::PushID(int(k));
      if (!s.fixed) {
        if (ImGui::RadioButton("##active", editor_->state().active == int(k))) editor_->setActive(int(k));
        ImGui::SameLine();
      }
      ImGui::Text("%s %s", s.fixed ? "[fixed]" : "[moving]", s.name.c_str());
      ImGui::SameLine();
      if (ImGui::SmallButton("x")) editor_->removeSelection(int(k));
      ImGui::PopID();
    }
    if (editor_->state().active >= 0) {
      const PoseTransform& t = editor_->pose().selections[std::size_t(editor_->state().active)].transform;
      ImGui::Text("rotation %.1f deg about (%.2f %.2f %.2f)", t.angleDeg, t.axis.x(), t.axis.y(), t.axis.z());
      ImGui::Text("translation %.1f %.1f %.1f mm", t.translation.x(), t.translation.y(), t.translation.z());
      ImGui::SetNextItemWidth(80);
      ImGui::InputFloat("step deg", &rotateStep_);
      for (int a = 0; a < 3; ++a) {
        ImGui::PushID(a + 100);
        const char axes[] = "xyz";
        if (ImGui::SmallButton(("-" + std::string(1, axes[a])).c_str())) editor_->rotateActive(Eigen::Vector3d::Unit(a), -rotateStep_);
        ImGui::SameLine();
        if (ImGui::SmallButton(("+" + std::string(1, axes[a])).c_str())) editor_->rotateActive(Eigen::Vector3d::Unit(a), rotateStep_);
        ImGui::PopID();
        if (a < 2) ImGui::SameLine();
      }
    }
    if (ImGui::Checkbox("ARAP", &arapOn_) || ImGui::SliderInt("iterations", &arapIterations_, 1, 30))
      editor_->setArapIterations(arapOn_ ? std::max(1, arapIterations_) : 0);
    ImGui::InputText("pose file", posePath_, sizeof posePath_);
    if (ImGui::Button("Save pose")) {
      try { savePose(posePath_); } catch (const std::exception& e) { status(e.what()); }
    }
    ImGui::SameLine();
    if (ImGui::Button("Load pose")) {
      try { loadPose(posePath_); } catch (const std::exception& e) { status(e.what()); }
    }
  }

  if (ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Checkbox("cage", &showCage_);
    ImGui::SameLine();
    ImGui::Checkbox("envelope", &showEnvelope_);
    ImGui::SameLine();
    ImGui::Checkbox("TM", &showTm_);
    if (ImGui::Button("Fit (F)")) { fitCamera(); viewDirty_ = true; }
    ImGui::SameLine();
    if (ImGui::Button("Reset (R)")) { orbit_ = home_; viewDirty_ = true; }
    ImGui::SetNextItemWidth(120);
    ImGui::SliderFloat("drag resolution", &interactiveScale_, 0.25f, 1.0f, "%.2f");
    bool cutChanged = false;
    const char* names[3] = {"x cut", "y cut", "z cut"};
    for (int a = 0; a < 3; ++a) {
      ImGui::PushID(a + 200);
      cutChanged |= ImGui::Checkbox(names[a], &cutOn_[a]);
      ImGui::SameLine();
      cutChanged |= ImGui::Checkbox(">", &cutAbove_[a]);
      ImGui::SameLine();
      ImGui::SetNextItemWidth(150);
      cutChanged |= ImGui::SliderFloat("mm", &cutAt_[a], float(sceneLo_[a]), float(sceneHi_[a]), "%.0f");
      ImGui::PopID();
    }
    cutChanged |= ImGui::Checkbox("free plane", &freeCutOn_);
    if (freeCutOn_) {
      cutChanged |= ImGui::SliderFloat3("normal", freeNormal_, -1.0f, 1.0f);
      cutChanged |= ImGui::SliderFloat("offset", &freeOffset_, -2000.0f, 2000.0f, "%.0f");
      if (std::abs(freeNormal_[0]) + std::abs(freeNormal_[1]) + std::abs(freeNormal_[2]) == 0.0f) freeNormal_[0] = 1.0f;
    }
    if (cutChanged) editor_->setCuts(cutsFromPanel());
  }

  const PoseFigures& f = editor_->figures();
  const double voxelMm3 = grid_.geometry().voxelVolume();
  if (ImGui::CollapsingHeader("Live figures", ImGuiTreeNodeFlags_DefaultOpen)) {
    double rest = 0, now = 0, restMass = 0, nowMass = 0;
    for (std::size_t l = 1; l < f.restVoxels.size(); ++l) {
      rest += f.restVoxels[l];
      now += f.deformedVoxels[l];
      const Organ* o = editor_->organs() ? editor_->organs()->find(int(l)) : nullptr;
      const double density = o ? o->density : 1.0;
      restMass += f.restVoxels[l] * voxelMm3 * density * 1e-3;
      nowMass += f.deformedVoxels[l] * voxelMm3 * density * 1e-3;
    }
    ImGui::Text("whole body: volume %+.3f %%, mass %+.3f %%", rest > 0 ? 100.0 * (now / rest - 1.0) : 0.0,
                restMass > 0 ? 100.0 * (nowMass / restMass - 1.0) : 0.0);
    ImGui::Text("TM vertices outside the cage: %zu", f.tmOutsideCage);
    ImGui::Text("inverted TM tets: %zu", f.tmInverted);
    ImGui::Text("frame %.1f ms, UI %.1f, present %.1f", frame_.totalMs, frame_.uiMs, frame_.presentMs);
    ImGui::Text("last deformation %.1f ms, ray cast %.1f ms (%dx%d)", frame_.deformMs, frame_.raycastMs, frame_.renderWidth,
                frame_.renderHeight);
  }
  if (ImGui::CollapsingHeader("Organs", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::InputText("search", organFilter_, sizeof organFilter_);
    std::string filter(organFilter_);
    std::transform(filter.begin(), filter.end(), filter.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    ImGui::BeginChild("organs", ImVec2(0, 0), true);
    if (ImGui::BeginTable("organ table", 4, ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit)) {
      ImGui::TableSetupColumn("show");
      ImGui::TableSetupColumn("organ", ImGuiTableColumnFlags_WidthStretch);
      ImGui::TableSetupColumn("mass g");
      ImGui::TableSetupColumn("change");
      ImGui::TableHeadersRow();
      for (std::size_t l = 1; l < f.restVoxels.size() && l < palette_.size(); ++l) {
        if (f.restVoxels[l] <= 0.0) continue;
        const Organ* o = editor_->organs() ? editor_->organs()->find(int(l)) : nullptr;
        std::string name = o ? o->name : "label " + std::to_string(l);
        std::string lower = name;
        std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
        if (!filter.empty() && lower.find(filter) == std::string::npos) continue;
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        bool visible = palette_.visible(Label(l));
        ImGui::PushID(int(l));
        if (ImGui::Checkbox("##v", &visible)) {
          std::vector<Label> hidden = editor_->state().hidden;
          if (visible) hidden.erase(std::remove(hidden.begin(), hidden.end(), Label(l)), hidden.end());
          else hidden.push_back(Label(l));
          editor_->setHidden(hidden);
          applyView();
        }
        ImGui::PopID();
        ImGui::TableNextColumn();
        const Rgb c = palette_.color(Label(l));
        ImGui::TextColored(ImVec4(c.r / 255.f, c.g / 255.f, c.b / 255.f, 1.f), "%s", name.c_str());
        ImGui::TableNextColumn();
        const double density = o ? o->density : 1.0;
        ImGui::Text("%.1f", f.deformedVoxels[l] * voxelMm3 * density * 1e-3);
        ImGui::TableNextColumn();
        const double change = 100.0 * (f.deformedVoxels[l] / f.restVoxels[l] - 1.0);
        ImGui::TextColored(std::abs(change) > 3.0 ? ImVec4(1, 0.4f, 0.3f, 1) : ImVec4(0.8f, 0.8f, 0.8f, 1), "%+.2f%%", change);
      }
      ImGui::EndTable();
    }
    ImGui::EndChild();
  }
  ImGui::End();

  // Export and status, bottom right.
  ImGui::SetNextWindowPos(ImVec2(float(fw) - 10.0f, float(fh) - 10.0f), ImGuiCond_Always, ImVec2(1, 1));
  ImGui::Begin("export", nullptr, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoMove);
  ImGui::SetNextItemWidth(220);
  ImGui::InputText("##out", exportPath_, sizeof exportPath_);
  ImGui::SameLine();
  ImGui::Checkbox("preserve volumes", &exportPreserve_);
  if (export_.running()) {
    ImGui::ProgressBar(float(export_.fraction()), ImVec2(220, 0), export_.stage().c_str());
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) export_.cancel();
  } else if (ImGui::Button("Export posed grid")) {
    const std::string out = exportPath_;
    const std::string stem = out.substr(0, out.find('.'));
    startExport(out, stem + "_report.json", stem + ".png", exportPreserve_);
  }
  if (!export_.running() && !export_.message().empty()) ImGui::TextUnformatted(export_.message().c_str());
  if (!status_.empty()) ImGui::TextUnformatted(status_.c_str());
  ImGui::End();
}

void Viewer::run() {
  std::size_t nextStep = 0;
  int wait = script_ && !script_->steps.empty() ? script_->steps[0].frames : 0;
  EditState lastState = editor_->state();
  bool lastDragging = false;
  while (!quit_ && !glfwWindowShouldClose(window_)) {
    const auto t0 = std::chrono::steady_clock::now();
    glfwPollEvents();
    input_.scripted = script_.has_value();
    if (!script_) {
      glfwGetCursorPos(window_, &input_.x, &input_.y);
      for (int b = 0; b < 3; ++b) input_.down[b] = glfwGetMouseButton(window_, b) == GLFW_PRESS;
    }
    const bool playing = script_ && !dragPath_.empty();
    if (playing) {
      if (dragIndex_ < dragPath_.size()) {
        input_.x = dragPath_[dragIndex_].first;
        input_.y = dragPath_[dragIndex_].second;
        input_.down[0] = true;
      } else {
        input_.down[0] = false;
      }
    } else if (script_) {
      if (nextStep >= script_->steps.size()) {
        quit_ = true;
      } else if (wait <= 0) {
        runScriptStep(script_->steps[nextStep]);
        ++nextStep;
        wait = nextStep < script_->steps.size() ? script_->steps[nextStep].frames : 0;
      } else {
        --wait;
      }
    }
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window_, &fw, &fh);
    if (fw == 0 || fh == 0) {
      glfwWaitEvents();
      continue;
    }
    if (std::uint32_t(fw) != swapchain_->width() || std::uint32_t(fh) != swapchain_->height()) {
      swapchain_->resize(std::uint32_t(fw), std::uint32_t(fh));
      viewDirty_ = true;
    }
    const CameraRays rays = cameraRays(orbit_.camera(fw - viewLeft(fw), fh));

    const auto tUi = std::chrono::steady_clock::now();
    ImGui_ImplVulkan_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGuiIO& io = ImGui::GetIO();
    if (script_) {
      io.MousePos = ImVec2(float(input_.x), float(input_.y));
      for (int b = 0; b < 3; ++b) io.MouseDown[b] = input_.down[b];
    }
    ImGui::NewFrame();
    if (!io.WantCaptureKeyboard && !script_) {
      if (ImGui::IsKeyPressed(GLFW_KEY_Z) && io.KeyCtrl) {
        if (io.KeyShift) editor_->redo();
        else editor_->undo();
        applyView();
      }
      if (ImGui::IsKeyPressed(GLFW_KEY_Y) && io.KeyCtrl) {
        editor_->redo();
        applyView();
      }
      if (ImGui::IsKeyPressed(GLFW_KEY_F)) { fitCamera(); viewDirty_ = true; }
      if (ImGui::IsKeyPressed(GLFW_KEY_R)) { orbit_ = home_; viewDirty_ = true; }
    }
    handleMouse(rays, !dragPath_.empty());
    if (playing) {
      if (dragIndex_ == 0 && drag_ != dragExpected_) {
        input_.down[0] = false;
        handleMouse(rays, true);
        throw InputError("script", "gizmo drag: the gizmo handle is not under the pointer (is a moving selection active?)");
      }
      if (dragIndex_ >= dragPath_.size()) dragPath_.clear();
      else ++dragIndex_;
    }
    panels();
    frame_.uiMs = msSince(tUi);

    // Deformation, then the ray casting when anything it shows changed.
    const auto tDeform = std::chrono::steady_clock::now();
    const bool moved = editor_->update();
    if (moved) frame_.deformMs = msSince(tDeform);
    const bool dragging = drag_ != DragKind::None;
    if (!(editor_->state() == lastState)) {
      lastState = editor_->state();
      viewDirty_ = true;
    }
    bool rendered = false;
    if (moved || viewDirty_ || (lastDragging && !dragging)) {
      renderView(dragging && interactiveScale_ < 1.0f);
      viewDirty_ = false;
      rendered = true;
    }
    lastDragging = dragging;

    const auto tUi2 = std::chrono::steady_clock::now();
    drawOverlays(rays);
    ImGui::Render();
    frame_.uiMs += msSince(tUi2);

    const auto tPresent = std::chrono::steady_clock::now();
    auto frame = swapchain_->beginFrame();
    if (!frame) {
      swapchain_->resize(std::uint32_t(fw), std::uint32_t(fh));
      continue;
    }
    if (view_.valid()) swapchain_->blit(*frame, view_, std::uint32_t(viewLeft(fw)), RaycastShading{}.background);
    else swapchain_->clear(*frame, RaycastShading{}.background);
    swapchain_->beginRenderPass(*frame);
    ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), frame->commands);
    swapchain_->endRenderPass(*frame);
    if (!swapchain_->endFrame(*frame)) swapchain_->resize(std::uint32_t(fw), std::uint32_t(fh));
    frame_.presentMs = msSince(tPresent);
    frame_.totalMs = msSince(t0);
    if (frameLog_ && rendered)
      *frameLog_ << frameCount_ << ',' << frame_.renderWidth << ',' << frame_.renderHeight << ',' << (moved ? frame_.deformMs : 0.0)
                 << ',' << frame_.raycastMs << ',' << frame_.uiMs << ',' << frame_.presentMs << ',' << frame_.totalMs << '\n';
    ++frameCount_;
  }
}

}  // namespace

void runViewer(const ViewerOptions& options) {
  Viewer viewer(options);
  viewer.run();
}

}  // namespace vox::app
