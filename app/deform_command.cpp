// voxmorph deform: re-poses a label grid with a pose file (thesis chapters 3
// and 4) and writes the posed full-resolution grid:
//   pre-process (label groups, envelope, cage, transfer mesh, embedding) ->
//   deformation (ARAP -> Green coordinates -> propagation) ->
//   deformation-adaptive refinement (eq. 4.5-4.7; field interpolation on the
//   GPU) -> rasterization of G' (GPU; --cpu for the CPU reference), streamed
//   slab by slab to the output file.
// --max-memory runs out of core: the source is read once (downsampled for the
// pipeline, spooled to an unlinked raw temporary when compressed) and G' is
// rasterized from source windows under the budget.

#include "app/command_line.h"
#include "geometry/deform/adaptive_refinement.h"
#include "geometry/deform/deformation_report.h"
#include "geometry/deform/label_volumes.h"
#include "geometry/deform/out_of_core.h"
#include "geometry/deform/pipeline.h"
#include "geometry/deform/posed_extent.h"
#include "geometry/deform/rasterize.h"
#include "geometry/deform/surface_checks.h"
#include "geometry/error.h"
#include "geometry/io/atomic_file.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/mesh_io.h"
#include "geometry/label_stats.h"
#include "gpu/context.h"
#include "gpu/kernels/field_interpolation.h"
#include "gpu/kernels/rasterize.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

namespace vox::app {

namespace {

struct DeformOptions {
  std::string input, pose, output, report, organs, cage, posedCage, posedMesh;
  std::vector<std::string> separations;
  double dilationMm = 20.0;
  int vertices = 300;
  int samples = 1;
  std::int64_t maxMemoryMb = 0;
  bool cpu = false;
  bool preserveVolumes = false;
  bool allowGrowth = false;
  std::int64_t maxTets = RefinementOptions{}.maxTets;
  int refineIterations = RefinementOptions{}.maxIterations;
  bool quiet = false;
};

// Memory the driver, the Vulkan device and the allocator keep beside the
// rasterization buffers under --max-memory.
constexpr std::int64_t kRasterOverheadBytes = std::int64_t(256) << 20;

// The source: whole in memory, or opened out of core.
struct Source {
  std::optional<LabelGrid> grid;
  std::unique_ptr<OutOfCoreSource> outOfCore;
  LabelGrid working;  // the pipeline's grid when downsampled (empty otherwise)
  int factor = 1;

  const GridGeometry& geometry() const { return grid ? grid->geometry() : outOfCore->geometry(); }
  const LabelGrid& workingGrid() const {
    if (outOfCore) return outOfCore->downsampled();
    return factor > 1 ? working : *grid;
  }
};

Source openSource(const DeformOptions& o) {
  Source s;
  if (o.maxMemoryMb > 0) {
    // Half the budget for the pre-processing's peak, the rest for the mesher,
    // the transfer mesh and its coordinates.
    const std::int64_t budget = o.maxMemoryMb << 20;
    const std::int64_t maxWorking = std::min(kDefaultWorkingVoxels, budget / 2 / kPreprocessBytesPerVoxel);
    const std::string temp = std::filesystem::path(o.output).parent_path().string();
    s.outOfCore = std::make_unique<OutOfCoreSource>(o.input, maxWorking, temp);
    s.factor = s.outOfCore->downsampleFactor();
    return s;
  }
  s.grid = readGrid(o.input);
  s.factor = downsampleFactor(s.grid->geometry(), kDefaultWorkingVoxels);
  if (s.factor > 1) {
    LabelGridSlices slices(*s.grid);
    s.working = downsampleLabels(slices, s.factor);
  }
  return s;
}

// G' held in memory, handed to writePosedGrid slab by slab.
class HeldGrid : public SlabRasterizer {
public:
  explicit HeldGrid(LabelGrid grid) : grid_(std::move(grid)) {}
  const GridGeometry& outputGeometry() const override { return grid_.geometry(); }
  std::int64_t slabSlices() const override { return 64; }
  void rasterizeSlab(std::int64_t z0, std::int64_t z1, Label* out) override {
    const std::int64_t slice = grid_.geometry().sliceVoxels();
    std::copy(grid_.data() + z0 * slice, grid_.data() + z1 * slice, out);
  }

private:
  LabelGrid grid_;
};

// The rasterization engine of G': the GPU kernel, or the CPU reference.
struct Engine {
  std::unique_ptr<gpu::Context> context;
  std::unique_ptr<gpu::RasterizeKernel> kernel;
  std::unique_ptr<RasterizationPlan> plan;
  std::unique_ptr<LabelGridSlices> gridSlices;
  std::unique_ptr<CpuSlabRasterizer> cpu;
  std::string name;

  SlabRasterizer& engine() { return kernel ? static_cast<SlabRasterizer&>(*kernel) : *cpu; }
};

void makeEngine(Engine& e, Source& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed, const DeformOptions& o,
                std::int64_t rasterBudget) {
  // Without a budget the engines keep their own slab and window sizes (in core).
  const RasterMemoryLimits limits = rasterBudget > 0 ? rasterMemoryLimits(rasterBudget, o.samples) : RasterMemoryLimits{};
  const bool limited = rasterBudget > 0;
  if (e.context) {
    gpu::RasterizeKernelOptions ko{.samples = o.samples};
    if (limited) {
      ko.maxSlabSamples = std::uint64_t(limits.slabSamples);
      ko.maxWindowVoxels = std::uint64_t(limits.windowVoxels);
    }
    e.kernel = source.grid ? std::make_unique<gpu::RasterizeKernel>(*e.context, *source.grid, rest, ko)
                           : std::make_unique<gpu::RasterizeKernel>(*e.context, source.outOfCore->slices(), rest, ko);
    e.kernel->setDeformedPositions(deformed);
    return;
  }
  e.plan = std::make_unique<RasterizationPlan>(source.geometry(), rest, deformed, o.samples);
  GridSliceReader* reader = nullptr;
  if (source.grid) {
    e.gridSlices = std::make_unique<LabelGridSlices>(*source.grid);
    reader = e.gridSlices.get();
  } else {
    reader = &source.outOfCore->slices();
  }
  CpuRasterizerLimits cl;
  if (limited) cl = {.slabSamples = limits.slabSamples, .windowVoxels = limits.windowVoxels};
  e.cpu = std::make_unique<CpuSlabRasterizer>(*e.plan, *reader, cl);
}

void deform(const DeformOptions& o) {
  installStderrProgress(o.quiet);
  if (!hasGridExtension(o.output)) throw InputError(o.output, "unknown grid format for the output");
  if (!o.posedCage.empty() && !hasSurfaceExtension(o.posedCage))
    throw InputError(o.posedCage, "unknown surface format for --posed-cage (use .obj, .off or .ply)");
  if (o.preserveVolumes && o.maxMemoryMb > 0)
    throw InputError("--preserve-volumes", "needs the posed grid in memory; it cannot be combined with --max-memory");
  if (!o.posedMesh.empty() && !hasTetMeshExtension(o.posedMesh))
    throw InputError(o.posedMesh, "unknown tet mesh format for --posed-mesh (use .mesh, .meshb, .vtu or .msh)");
  // Everything the command can reject cheaply is checked before the work.
  const Pose pose = readPose(o.pose);
  std::optional<OrganTable> organTable;
  if (!o.organs.empty()) organTable = OrganTable::read(o.organs);
  PipelineOptions options = poseOptions(pose, o.pose, organTable);
  options.cage.dilationMm = o.dilationMm;
  options.cage.targetVertices = o.vertices;
  for (const std::string& text : o.separations) {
    options.cage.separations.push_back(parseSeparation(text));
    options.cuts->push_back(options.cage.separations.back());
  }
  if (!options.cage.separations.empty() && !options.organs)
    throw InputError(o.pose, "limb separation needs the grid's organ table (--organs) to find the label groups");
  if (usesLabelGroups(pose) && !options.organs)
    throw InputError(o.pose, "a selection by label group needs the grid's organ table (--organs)");
  if (!o.cage.empty()) options.userCage = readCage(o.cage);
  const bool separated = !options.cage.separations.empty();

  Engine engine;
  if (!o.cpu) {
    try {
      engine.context = std::make_unique<gpu::Context>();
      engine.name = "GPU (" + engine.context->info().name + ")";
    } catch (const RuntimeFailure& e) {
      std::fprintf(stderr, "voxmorph: warning: %s; using the CPU\n", e.what());
    }
  }
  if (!engine.context) engine.name = "CPU";

  DeformationReport report;
  report.input = o.input;
  report.output = o.output;
  report.pose = o.pose;
  report.samples = o.samples;
  report.maxMemoryBytes = o.maxMemoryMb << 20;
  report.withMasses = options.organs.has_value();

  StageTimer readTimer("read source");
  Source source = openSource(o);
  report.stages.push_back(readTimer.stop());
  report.source = source.geometry();
  report.workingFactor = source.factor;
  report.workingVoxels = source.workingGrid().voxelCount();

  auto pipeline = std::make_unique<DeformationPipeline>(source.workingGrid(), options);
  warnForegroundOutside(pipeline->stats().foregroundOutsideCage, separated);
  pipeline->deform();
  checkPosedGrowth(source.geometry(), pipeline->deformedTransferMesh(), o.pose,
                   selectionMovingFarthest(pipeline->pose(), pipeline->handles(), pipeline->deformedCage(), source.geometry()), o.allowGrowth);

  std::unique_ptr<gpu::FieldInterpolationKernel> interpolationKernel;
  VertexFieldInterpolation interpolate = cpuFieldInterpolation();
  if (engine.context) {
    interpolationKernel = std::make_unique<gpu::FieldInterpolationKernel>(*engine.context);
    interpolate = [k = interpolationKernel.get()](const TetMesh& mesh, const std::vector<double>& values, const GridGeometry& target,
                                                  float fill) { return k->run(mesh, values, target, fill); };
  }
  report.refinement = pipeline->refine({.maxIterations = o.refineIterations, .maxTets = o.maxTets}, interpolate);
  describePipeline(report, *pipeline);
  if (!o.posedCage.empty()) {
    TriMesh posed = pipeline->cage();
    posed.positions = pipeline->deformedCage();
    writeSurface(o.posedCage, posed);
  }
  if (!o.posedMesh.empty()) {
    TetMesh posed = pipeline->transferMesh();
    posed.positions = pipeline->deformedTransferMesh();
    writeTetMesh(o.posedMesh, posed);
  }
  for (const StageTime& t : pipeline->stats().stages) report.stages.push_back(t);

  // The pipeline's grids and coordinates go before the rasterization buffers.
  const TetMesh rest = pipeline->transferMesh();
  const std::vector<Eigen::Vector3d> deformed = pipeline->deformedTransferMesh();
  pipeline.reset();
  interpolationKernel.reset();

  StageTimer rasterTimer("rasterization");
  std::int64_t rasterBudget = 0;
  if (source.outOfCore) {
    const std::int64_t resident = source.outOfCore->downsampled().voxelCount() * std::int64_t(sizeof(Label)) +
                                  std::int64_t(rest.vertexCount()) * 48 + std::int64_t(rest.tetCount()) * 32;
    rasterBudget = std::max<std::int64_t>(std::int64_t(64) << 20, report.maxMemoryBytes - resident - kRasterOverheadBytes);
  }
  makeEngine(engine, source, rest, deformed, o, rasterBudget);
  const Label maxLabel = source.grid ? source.grid->maxLabel() : source.outOfCore->maxLabel();
  std::vector<std::uint64_t> after;
  std::vector<double> deformedVolumes;
  if (o.preserveVolumes) {
    LabelGrid posed = rasterizeAllSlabs(engine.engine());
    report.stages.push_back(rasterTimer.stop());
    StageTimer correctionTimer("volume correction");
    deformedVolumes = deformedLabelVolumes(*source.grid, rest, deformed);
    report.volumeCorrection = preserveLabelVolumes(posed, *source.grid, rest, deformed, deformedVolumes);
    report.stages.push_back(correctionTimer.stop());
    StageTimer writeTimer("write");
    HeldGrid held(std::move(posed));
    after = writePosedGrid(held, o.output, maxLabel);
    report.posed = held.outputGeometry();
    report.stages.push_back(writeTimer.stop());
  } else {
    after = writePosedGrid(engine.engine(), o.output, maxLabel);
    report.posed = engine.engine().outputGeometry();
    report.stages.push_back(rasterTimer.stop());
  }
  report.engine = engine.name;

  const std::vector<std::uint64_t> before = source.grid ? computeLabelStats(*source.grid).counts : source.outOfCore->labelCounts();
  const OrganTable* organs = options.organs ? &*options.organs : nullptr;
  report.labels = labelChanges(before, after, source.geometry().voxelVolume(), organs);
  for (LabelChange& c : report.labels)
    if (c.label < deformedVolumes.size()) c.deformedVolumeVoxels = deformedVolumes[c.label];
  report.wholeBody = wholeBodyChange(report.labels);
  if (!o.report.empty()) {
    const std::string json = deformationReportJson(report);
    if (o.report == "-") std::fputs(json.c_str(), stdout);
    else writeFileAtomic(o.report, json);
  }
  if (!o.quiet && o.report != "-") std::fputs(deformationSummary(report).c_str(), stdout);
}

}  // namespace

void addDeformCommand(CLI::App& app) {
  auto o = std::make_shared<DeformOptions>();
  CLI::App* cmd = app.add_subcommand("deform", "Re-pose a label grid with a pose file and write the posed grid");
  cmd->add_option("grid", o->input, "Label grid (.nii .nii.gz .mha .mhd .nrrd .nhdr .inr)")->required();
  cmd->add_option("--pose", o->pose, "Pose file (JSON, docs/POSES.md)")->required();
  cmd->add_option("-o,--output", o->output, "Posed grid (.nii .nii.gz .mha .mhd; any grid format in core)")->required();
  cmd->add_option("--report", o->report, "JSON report (stage times, sizes, outliers, per-label volume and mass change, "
                                         "distortion, refinement); '-' for stdout");
  cmd->add_option("--organs", o->organs, "Organ table (ID name tissue density): masses, and label groups for limb separation");
  auto* cage = cmd->add_option("--cage", o->cage, "Use this cage (.obj .off .ply; closed, outward, no self-intersections)");
  cmd->add_option("--separate", o->separations,
                  "Separate two label groups in the cage and the transfer mesh, optionally inside a box in mm: right_arm:trunk "
                  "or right_arm:trunk@xmin,ymin,zmin,xmax,ymax,zmax (repeatable; adds to the pose's \"separations\")")
      ->allow_extra_args(false);
  cmd->add_option("--dilation", o->dilationMm, "Automatic cage: offset from the foreground, mm (default 20)")
      ->check(CLI::PositiveNumber)
      ->excludes(cage);
  cmd->add_option("--vertices", o->vertices, "Automatic cage: vertices after QEM (default 300)")
      ->check(CLI::Range(8, 100000))
      ->excludes(cage);
  cmd->add_option("--samples", o->samples, "k: k^3 samples per output voxel, majority label (default 1; odd k recommended)")
      ->check(CLI::Range(1, kMaxRasterSamples));
  cmd->add_option("--max-memory", o->maxMemoryMb,
                  "Out of core under this budget (MB): the pipeline runs on a downsampled grid, G' is rasterized from "
                  "streamed source slices and written slab by slab")
      ->check(CLI::Range(std::int64_t(256), std::int64_t(1) << 30));
  cmd->add_option("--posed-cage", o->posedCage, "Also write the posed cage (.obj .off .ply), to check a pose's handles");
  cmd->add_option("--posed-mesh", o->posedMesh, "Also write the posed transfer mesh (.mesh .vtu .msh)");
  cmd->add_flag("--preserve-volumes", o->preserveVolumes,
                "Relabel boundary voxels of the posed grid so that each label keeps the volume the deformation gives it "
                "(sum of the transfer mesh's Jacobian determinants over its voxels), within about a voxel; in core only");
  cmd->add_flag("--allow-growth", o->allowGrowth,
                "Accept a posed grid of more than 8 times the source's voxels (a pose that moves parts far from the body)");
  cmd->add_flag("--cpu", o->cpu, "Rasterize and interpolate fields with the CPU reference instead of the GPU");
  cmd->add_option("--max-tets", o->maxTets, "Tet budget of the refined transfer mesh (default 250000)")
      ->check(CLI::Range(std::int64_t(1000), std::int64_t(1) << 30));
  cmd->add_option("--refine-iterations", o->refineIterations,
                  "Transfer-mesh regenerations of the deformation-adaptive refinement at most (default 1; 0: none)")
      ->check(CLI::Range(0, 100));
  cmd->add_flag("-q,--quiet", o->quiet, "No progress or summary (warnings still go to stderr)");
  cmd->callback([o] { deform(*o); });
}

}  // namespace vox::app
