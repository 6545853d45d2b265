// voxmorph render: transfer-mesh-guided ray casting of a label grid to a PNG
// (thesis chapter 5). With --pose the deformation pipeline (voxmorph deform's
// pre-processing and one frame, without refinement) gives the transfer mesh
// and its posed positions, and the source grid is rendered through them
// without rasterizing the posed grid (--prepared: voxmorph prepare's rest
// state instead of that pre-processing). Without a pose the grid is shown at
// rest through an identity transfer mesh (six tets over the foreground's box). The GPU kernel
// renders by default; --cpu uses the CPU reference and --verify runs both and
// fails when they disagree beyond the stated tolerance. With --articulated a
// joint pose is applied to the transfer mesh that resolves the skeleton
// (deform --articulated's solve, without its checks and the rasterization),
// and --step shows where any step of the way left it.

#include "app/command_line.h"
#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/deform/pose/pose_frame.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/output_path.h"
#include "geometry/io/png_io.h"
#include "geometry/label_stats.h"
#include "geometry/organ_table.h"
#include "geometry/render/camera.h"
#include "geometry/render/cutting_planes.h"
#include "geometry/render/image_annotations.h"
#include "geometry/render/palette.h"
#include "geometry/render/raycast_reference.h"
#include "geometry/render/raycast_scene.h"
#include "geometry/render/rest_transfer_mesh.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/deform/prepared_state.h"
#include "geometry/deform/run/deform_run.h"
#include "gpu/context.h"
#include "gpu/kernels/raycast.h"

#include <chrono>
#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>

namespace vox::app {

namespace {

// GPU and CPU images agree when at most this fraction of pixels differ by more
// than kVerifyThreshold in a channel.
constexpr int kVerifyThreshold = 5;
constexpr double kVerifyFraction = 0.001;

struct RenderOptions {
  std::string input;
  std::string output;
  std::string camera;
  std::string size = "640x480";
  std::vector<std::string> cuts;
  std::string hide;
  std::string organs;
  std::string pose;
  std::int64_t maxMemoryMb = 0;  // 0: the machine's memory
  std::string parts;
  std::string prepared;  // voxmorph prepare's rest state, with --pose
  std::string shading = surfaceNormalsName(RaycastShading{}.normals);
  bool articulated = false;
  double boneGapMm = ArticulatedMeshOptions{}.boneGapMm;
  int step = 0;  // with articulated: the step of the way shown (1-based; 0: the posed mesh)
  bool cpu = false;
  bool verify = false;
  bool legend = false;
  bool scaleBar = false;
  bool quiet = false;
};

// The organs the image shows (rays of every fourth pixel row and column on
// the CPU reference), most pixels first, with their colours.
std::vector<LegendEntry> visibleOrgans(const LabelGrid& grid, const RaycastMesh& mesh, const RaycastFrame& frame, const RaycastView& view,
                                       const Palette& palette, const OrganTable* organs) {
  const std::vector<std::uint64_t> pixels = visibleLabelPixels(grid, mesh, frame, view, palette, 4);
  std::vector<std::size_t> labels;
  for (std::size_t l = 1; l < pixels.size(); ++l)
    if (pixels[l] > 0) labels.push_back(l);
  std::stable_sort(labels.begin(), labels.end(), [&](std::size_t a, std::size_t b) { return pixels[a] > pixels[b]; });
  std::vector<LegendEntry> entries;
  for (const std::size_t l : labels) {
    const Organ* organ = organs ? organs->find(int(l)) : nullptr;
    const std::string name = organ ? organ->name : organs ? "label " + std::to_string(l) + " (not in organ table)" : "label " + std::to_string(l);
    entries.push_back({palette.color(Label(l)), name});
  }
  return entries;
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void render(const RenderOptions& o) {
  installStderrProgress(o.quiet);
  checkOutputPath(o.output, OutputKind::Png, "--output");
  int width = 0, height = 0;
  parseImageSize(o.size, width, height);
  CuttingPlanes cuts;
  for (const std::string& c : o.cuts) cuts.add(c);

  std::optional<OrganTable> organs;
  if (!o.organs.empty()) organs = OrganTable::read(o.organs);
  std::optional<Pose> worldPose;
  if (!o.pose.empty()) {
    worldPose = readPose(o.pose);
    const bool skeletal = !worldPose->joints.empty() || usesBodyParts(*worldPose) || !o.parts.empty();
    if (skeletal) requireOrganTable(organs.has_value(), OrganTableNeed::Bones, o.pose);
    if (skeletal) skeleton::requireBones(*organs, o.organs);
    if (o.articulated || worldPose->articulated) {
      if (worldPose->joints.empty()) throw InputError(o.pose, "--articulated poses joints: the pose has no \"joints\"");
      if (!worldPose->selections.empty() || !worldPose->separations.empty())
        throw InputError(o.pose, "--articulated poses joints only: the pose's selections and separations have no place there");
      if (!o.parts.empty()) throw UsageError("--articulated", "cannot be combined with --parts");
      if (o.step > articulatedStepCount(*worldPose))
        throw UsageError("--step", std::to_string(o.step) + " is beyond the pose's " + std::to_string(articulatedStepCount(*worldPose)) + " steps");
    }
  } else if (o.articulated) {
    throw UsageError("--articulated", "needs a --pose");
  } else if (!o.parts.empty()) {
    throw UsageError("--parts", "needs a --pose");
  } else if (!o.prepared.empty()) {
    throw UsageError("--prepared", "needs a --pose");
  }
  checkGridFitsMemory(o.input, o.maxMemoryMb, o.pose.empty() ? kRenderMemory : kPosedMemory,
                      o.pose.empty() ? "render" : "render the pose", "rendering needs the whole grid in memory");
  const LabelGrid grid = readGrid(o.input);
  Palette palette = organs ? Palette::fromOrgans(*organs, grid.maxLabel()) : Palette(grid.maxLabel());
  if (!o.hide.empty()) palette.hide(o.hide, organs ? &*organs : nullptr);
  const LabelStats stats = computeLabelStats(grid);
  bool anyVisible = false;
  for (std::size_t l = 1; l < stats.counts.size(); ++l) anyVisible = anyVisible || (stats.counts[l] > 0 && palette.visible(Label(l)));
  if (!anyVisible && stats.foregroundVoxels() > 0)
    throw UsageError("--hide", "'" + o.hide + "' hides every label of the grid; the image would be empty");

  TetMesh restMesh;
  std::vector<Eigen::Vector3d> posed;
  if (o.pose.empty()) {
    restMesh = boxTransferMesh(grid, o.input);
    posed = restMesh.positions;
  } else if (o.articulated || worldPose->articulated) {
    ArticulatedStepsRequest request{grid, *organs};
    request.pose = poseInGridFrame(*worldPose, grid.geometry(), o.pose);
    request.gridSource = o.input;
    request.organsSource = o.organs;
    request.poseSource = o.pose;
    request.boneGapMm = o.boneGapMm;
    std::shared_ptr<PreparedState> prepared;
    if (!o.prepared.empty()) {
      prepared = std::make_shared<PreparedState>(PreparedState::read(o.prepared));
      const std::string note = prepared->check(preparedInputs(o.input, organs, o.organs, "", 1, grid.dims()));
      if (!note.empty() && !o.quiet) std::fprintf(stderr, "voxmorph: warning: %s\n", note.c_str());
      request.prepared = prepared.get();
    }
    if (!o.quiet) request.warn = [](const std::string& w) { std::fprintf(stderr, "voxmorph: warning: %s\n", w.c_str()); };
    ArticulatedSteps steps = poseArticulatedSteps(request);
    const std::size_t shown = o.step > 0 ? std::min<std::size_t>(std::size_t(o.step), steps.steps.size()) : steps.steps.size();
    if (!o.quiet)
      std::fprintf(stderr, "articulated: step %zu of %zu, %zu tets inverted in the posed mesh (smallest det J on the way %.4f)\n", shown,
                   steps.steps.size(), steps.report.invertedTets, steps.report.minRelativeVolume);
    restMesh = std::move(steps.rest);
    posed = std::move(steps.steps[shown - 1]);
  } else {
    const Pose pose = poseInGridFrame(*worldPose, grid.geometry(), o.pose);
    // A prepared state (voxmorph prepare) gives the skeleton, cage and
    // transfer mesh; the pipeline runs on the whole grid here (working factor 1).
    std::shared_ptr<PreparedState> prepared;
    if (!o.prepared.empty()) {
      prepared = std::make_shared<PreparedState>(PreparedState::read(o.prepared));
      const std::string note = prepared->check(preparedInputs(o.input, organs, o.organs, o.parts, 1, grid.dims()));
      if (!note.empty() && !o.quiet) std::fprintf(stderr, "voxmorph: warning: %s\n", note.c_str());
    }
    const bool skeletal = !pose.joints.empty() || usesBodyParts(pose) || !o.parts.empty();
    std::optional<LabelGrid> userParts;
    if (!o.parts.empty() && !(prepared && prepared->skeleton)) userParts = readGrid(o.parts);
    PipelineOptions options = prepared && prepared->skeleton && skeletal
                                  ? skeleton::skeletalPoseOptions(pose, o.pose, *prepared->skeleton, organs)
                                  : skeleton::skeletalPoseOptions(pose, o.pose, grid, organs, {o.input, o.organs, o.parts}, std::move(userParts));
    options.envelope = false;
    options.prepared = prepared;
    DeformationPipeline pipeline(grid, options);
    warnForegroundOutside(pipeline.stats().foregroundOutsideCage, !options.cage.separations.empty());
    pipeline.deform();
    restMesh = pipeline.transferMesh();
    posed = pipeline.deformedTransferMesh();
  }
  const RaycastMesh mesh = buildRaycastMesh(restMesh, grid.geometry(), o.input);
  const RaycastFrame frame = prepareRaycastFrame(mesh, posed);
  const Camera camera = parseCamera(o.camera, frame.toGrid(frame.cellsLo), frame.toGrid(frame.cellsHi), width, height);
  const RaycastView view = makeRaycastView(frame, camera, cuts);
  RaycastShading shading;
  shading.normals = parseSurfaceNormals(o.shading, "--shading");

  RgbImage image;
  std::string engine;
  double ms = 0.0;
  if (!o.cpu) {
    try {
      gpu::Context context;
      gpu::RaycastKernel kernel(context, grid, mesh);
      image = kernel.render(frame, view, palette, shading);
      ms = kernel.lastTimes().totalMs;
      engine = "GPU (" + context.info().name + ")";
    } catch (const RuntimeFailure& e) {
      if (o.verify) throw;
      std::fprintf(stderr, "voxmorph: warning: %s; using the CPU\n", e.what());
    }
  }
  if (engine.empty() || o.verify) {
    const auto t0 = std::chrono::steady_clock::now();
    RgbImage cpu = raycastReference(grid, mesh, frame, view, palette, shading);
    const double cpuMs = msSince(t0);
    if (engine.empty()) {
      image = std::move(cpu);
      ms = cpuMs;
      engine = "CPU";
    } else {
      const ImageDifference d = compareImages(image, cpu, kVerifyThreshold);
      if (!o.quiet)
        std::fprintf(stderr, "verify: %zu of %zu pixels (%.4f%%) differ from the CPU reference by more than %d/255\n", d.differing,
                     d.pixels, 100.0 * d.differingFraction(), kVerifyThreshold);
      if (d.differingFraction() > kVerifyFraction)
        throw RuntimeFailure("GPU image differs from the CPU reference on more than 0.1% of the pixels");
    }
  }
  if (o.legend) drawLegend(image, visibleOrgans(grid, mesh, frame, view, palette, organs ? &*organs : nullptr));
  if (o.scaleBar) drawScaleBar(image, view.camera, (camera.target - camera.eye).dot(view.camera.forward));
  writePng(o.output, image);
  if (!o.quiet)
    std::fprintf(stderr, "%s: %d x %d, %s, %.1f ms\n", o.output.c_str(), width, height, engine.c_str(), ms);
}

}  // namespace

void addRenderCommand(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* cmd = addGridSubcommand(app, "render", "Ray-cast a label grid to a PNG image, smoothly shaded or voxel faces visible (at rest: identity TM)", o->input);
  cmd->add_option("-o,--output", o->output, "Output image (.png)")->required();
  cmd->add_option("--camera", o->camera,
                  "Camera: \"azimuth=30,elevation=10,distance=2.5,fov=35\" (degrees; distance in scene diagonals or "
                  "with an mm suffix; default fits the foreground) or \"eye=x,y,z,target=x,y,z,up=x,y,z,fov=35\" (mm). "
                  "Azimuth 0 looks along +y with z up");
  cmd->add_option("--size", o->size, "Image size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--cut", o->cuts,
                  "Cutting plane (repeatable: one per axis and one free plane): \"x>120mm\" removes the voxels whose centre "
                  "has x > 120 mm, \"z<400\" those below 400 mm, \"plane=nx,ny,nz,d\" those with n.c > d")
      ->allow_extra_args(false);
  cmd->add_option("--hide", o->hide, "Labels to hide: \"5,7,10-20\", or organ-name substrings with --organs (\"skin,adipose\")");
  cmd->add_option("--organs", o->organs, "Organ table (ID name tissue density): colours by organ name");
  cmd->add_option("--pose", o->pose, "Pose file (JSON, docs/POSES.md): render the grid posed through its transfer mesh (a pose with "
                                     "joints needs --organs)");
  cmd->add_option("--parts", o->parts, "Body-part grid (voxmorph parts) for a joint pose instead of the assignment from the bones");
  CLI::Option* articulated =
      cmd->add_flag("--articulated", o->articulated,
                    "A joint pose on the transfer mesh that resolves the skeleton, as deform --articulated poses it (without its checks; "
                    "the posed grid is not rasterized)");
  cmd->add_option("--bone-gap", o->boneGapMm, "With --articulated: the bone-gap cut at the wrists, elbows and hips, as deform --bone-gap, mm")
      ->capture_default_str()
      ->check(numberIn(0, 100, "mm"))
      ->needs(articulated);
  cmd->add_option("--step", o->step,
                  "With --articulated: show where step N of the way from rest left the mesh (1 to the pose's steps: the approach's, "
                  "then the last with the bones on their motions; default the posed mesh)")
      ->check(integerIn(1, 100000, ""))
      ->needs(articulated);
  cmd->add_option("--prepared", o->prepared,
                  "With --pose: the rest state saved by voxmorph prepare (.vxprep) instead of building the cage and transfer mesh "
                  "(same image); refused when made from another grid, organ table or --parts, or without this pose's separations");
  cmd->add_option("--max-memory", o->maxMemoryMb,
                  "Refuse a grid whose in-core work exceeds this budget (MB; default the machine's memory)")
      ->check(integerIn(64, std::int64_t(1) << 30, "MB"));
  cmd->add_option("--shading", o->shading,
                  "Surface normals: \"smooth\" (gradient of the smoothed occupancy of the visible labels; cut faces flat) or "
                  "\"faces\" (each voxel face's own normal, voxel faces visible)")
      ->check(CLI::IsMember({"smooth", "faces"}))
      ->capture_default_str();
  cmd->add_flag("--legend", o->legend, "List the organs the image shows, with their colours (names from --organs)");
  cmd->add_flag("--scale-bar", o->scaleBar, "Draw a scale bar (mm, at the depth of the camera's target)");
  cmd->add_flag("--cpu", o->cpu, "Render with the CPU reference instead of the GPU");
  cmd->add_flag("--verify", o->verify, "Render on both and fail if more than 0.1% of the pixels differ by more than 5/255");
  cmd->add_flag("-q,--quiet", o->quiet, "No progress or summary on stderr");
  cmd->callback([o] { render(*o); });
}

}  // namespace vox::app
