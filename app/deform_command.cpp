// voxmorph deform: re-poses a label grid with a pose file (thesis chapters 3
// and 4) and writes the posed full-resolution grid:
//   pre-process (label groups, envelope, cage, transfer mesh, embedding) ->
//   deformation (ARAP -> Green coordinates -> propagation) ->
//   deformation-adaptive refinement (eq. 4.5-4.7; field interpolation on the
//   GPU) -> rasterization of G' (GPU; --cpu for the CPU reference), streamed
//   slab by slab to the output file.
// --prepared takes the pre-processing from `voxmorph prepare`'s file.
// --max-memory runs out of core. The run itself is deformGrid
// (geometry/deform/run/deform_run.h), which the viewer's export calls too,
// on the GPU's engines (gpu/raster_engines.h) or the CPU's.

#include "app/command_line.h"
#include "geometry/deform/report/deformation_report.h"
#include "geometry/deform/report/distortion_plot.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/deform/pose/pose_frame.h"
#include "geometry/deform/cage/surface_checks.h"
#include "geometry/error.h"
#include "geometry/atomic_file.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/output_path.h"
#include "geometry/io/png_io.h"
#include "geometry/organ_table.h"
#include "geometry/raster/rasterize.h"
#include "geometry/world_frame.h"
#include "geometry/deform/run/deform_run.h"
#include "gpu/raster_engines.h"

#include <cstdio>
#include <future>
#include <filesystem>
#include <memory>

namespace vox::app {

namespace {

struct DeformOptions {
  // The options the run takes as they are (input, output, parts, cage
  // options, samples, memory, growth, rigid bones, refinement, extra outputs).
  DeformGridRequest run;
  std::string pose, report, organs, cage, plots;
  double flagPercent = kDefaultFlagPercent;
  std::vector<std::string> separations;
  bool cpu = false;
  std::string volumeTarget;  // --preserve-volumes[=deformed|rest]; "" without it
  bool quiet = false;
};

// The per-organ CSV lies beside the JSON report: r.json -> r.csv.
std::string tablePath(const DeformOptions& o) {
  if (o.report.empty() || o.report == "-") return "";
  std::filesystem::path p(o.report);
  return p.replace_extension(".csv").string();
}

void deform(const DeformOptions& o) {
  retainFreedMemory();
  installStderrProgress(o.quiet);
  checkOutputPath(o.run.output, OutputKind::Grid, "--output");
  checkOutputPath(o.report, OutputKind::Json, "--report");
  checkOutputPath(o.run.posedCage, OutputKind::Surface, "--posed-cage");
  checkOutputPath(o.run.posedMesh, OutputKind::TetMesh, "--posed-mesh");
  checkOutputPath(o.run.collisionMask, OutputKind::Grid, "--collision-mask");
  checkOutputPath(tablePath(o), OutputKind::Csv, "--report");
  checkOutputPath(o.plots, OutputKind::Png, "--plots");
  if (o.run.maxMemoryMb == 0)
    checkGridFitsMemory(o.run.input, 0, kDeformMemory, "deform in memory", "run out of core with --max-memory MB");
  DeformGridRequest request = o.run;
  request.poseSource = o.pose;
  request.preserveVolumes = !o.volumeTarget.empty();
  request.volumeTarget = o.volumeTarget == "rest" ? DeformGridRequest::VolumeTarget::Rest
                                                  : DeformGridRequest::VolumeTarget::Deformed;
  request.warn = [](const std::string& message) { std::fprintf(stderr, "voxmorph: warning: %s\n", message.c_str()); };
  // Everything the command can reject cheaply is checked before the work.
  // Poses, cages and --separate boxes are in the world frame (world_frame.h);
  // the pipeline works in the grid frame.
  const GridGeometry frame = openGridSlices(o.run.input)->geometry();
  request.pose = poseInGridFrame(readPose(o.pose), frame, o.pose);
  if (!o.organs.empty()) request.organs = OrganTable::read(o.organs);
  request.organsSource = o.organs;
  for (const std::string& text : o.separations) {
    request.extraSeparations.push_back(parseSeparation(text));
    regionInGridFrame(request.extraSeparations.back().region, frame, "--separate " + text);
  }
  if (!o.cage.empty()) {
    request.cage = readCage(o.cage);
    surfaceWorldToGrid(*request.cage, frame);
  }
  checkDeformGridRequest(request);
  // The inputs' SHA-256 (the report's provenance) on a thread of its own
  // beside the run, which reads the grid meanwhile: a large grid's digest
  // takes a core for a while.
  std::future<Provenance> provenance = std::async(std::launch::async, [&o] {
    return commandProvenance({{"grid", o.run.input}, {"organs", o.organs}, {"pose", o.pose}, {"cage", o.cage}, {"prepared", o.run.prepared}});
  });

  const std::unique_ptr<RasterEngines> engines = gpu::makeRasterEngines(o.cpu, request.warn);
  DeformationReport report = deformGrid(request, *engines);
  report.provenance = provenance.get();
  if (!o.report.empty()) {
    const std::string json = deformationReportJson(report);
    if (o.report == "-") {
      std::fputs(json.c_str(), stdout);
    } else {
      writeFileAtomic(o.report, json);
      writeFileAtomic(tablePath(o), labelChangeCsv(report, o.flagPercent));
    }
  }
  if (!o.plots.empty()) writePng(o.plots, distortionPlot(report));
  if (!o.quiet && o.report != "-") {
    std::fputs(deformationSummary(report).c_str(), stdout);
    std::fputs(("\n" + labelChangeTable(report, o.flagPercent)).c_str(), stdout);
  }
  for (const std::string& w : deformationWarnings(report)) std::fprintf(stderr, "voxmorph: warning: %s\n", w.c_str());
}

}  // namespace

void addDeformCommand(CLI::App& app) {
  auto o = std::make_shared<DeformOptions>();
  CLI::App* cmd = addGridSubcommand(app, "deform", "Re-pose a label grid with a pose file and write the posed grid", o->run.input);
  cmd->add_option("--pose", o->pose, "Pose file (JSON, docs/POSES.md)")->required();
  cmd->add_option("-o,--output", o->run.output, "Posed grid (.nii .nii.gz .mha .mhd; any grid format in core)")->required();
  cmd->add_option("--report", o->report, "JSON report, and the per-organ table as CSV beside it (r.json -> r.csv) (stage times, sizes, outliers, per-label volume and mass change, "
                                         "distortion, refinement); '-' for stdout");
  cmd->add_option("--plots", o->plots, "Also draw the distortion and organ volume-change histograms (thesis Figure 3.19) as PNG");
  cmd->add_option("--flag", o->flagPercent, "Flag organs whose volume changes by more than this, %")->capture_default_str()
      ->check(numberIn(0, 1000, "%"));
  cmd->add_option("--organs", o->organs, "Organ table (ID name tissue density): masses, label groups for limb separation, the bones "
                                         "of a joint pose");
  cmd->add_option("--parts", o->run.parts, "Body-part grid (voxmorph parts, corrected) to use for a joint pose instead of the assignment "
                                       "from the bones (same dims as the grid)");
  auto* cage = cmd->add_option("--cage", o->cage, "Use this cage (.obj .off .ply; closed, outward, no self-intersections)");
  cmd->add_option("--separate", o->separations,
                  "Separate two label groups in the cage and the transfer mesh, optionally inside a box in mm: right_arm:trunk "
                  "or right_arm:trunk@xmin,ymin,zmin,xmax,ymax,zmax (repeatable; adds to the pose's \"separations\")")
      ->allow_extra_args(false);
  cmd->add_option("--dilation", o->run.dilationMm, "Automatic cage: offset from the foreground, mm")->capture_default_str()
      ->check(numberIn(0, 10000, "mm", true))
      ->excludes(cage);
  cmd->add_option("--vertices", o->run.vertices, "Automatic cage: vertices after QEM")->capture_default_str()
      ->check(integerIn(8, 100000))
      ->excludes(cage);
  cmd->add_option("--prepared", o->run.prepared,
                  "Rest state saved by voxmorph prepare (.vxprep): its skeleton, cage, envelope and transfer mesh instead of "
                  "building them (same result); refused when made from another grid, organ table or --parts, or without this "
                  "pose's separations, --separate, --dilation and --vertices");
  cmd->add_option("--samples", o->run.samples, "k: k^3 samples per output voxel, majority label (odd k recommended)")->capture_default_str()
      ->check(integerIn(1, kMaxRasterSamples));
  cmd->add_option("--max-memory", o->run.maxMemoryMb,
                  "Out of core under this budget (MB): the pipeline runs on a downsampled grid, G' is rasterized from "
                  "streamed source slices and written slab by slab")
      ->check(integerIn(256, std::int64_t(1) << 30, "MB"));
  cmd->add_option("--posed-cage", o->run.posedCage, "Also write the posed cage (.obj .off .ply), to check a pose's handles");
  cmd->add_option("--posed-mesh", o->run.posedMesh, "Also write the posed transfer mesh (.mesh .vtu .msh)");
  cmd->add_option("--collision-mask", o->run.collisionMask,
                  "With body parts (an organ table that names the bones, or --parts): also write a grid, 1 where the posed tissue of two body parts overlaps "
                  "(the posed grid's extent at the working grid's spacing)");
  cmd->add_flag("--preserve-volumes{deformed}", o->volumeTarget,
                "Fill the gaps the pose opens inside the body (background no tet covers, enclosed by tissue) with the tissue around "
                "them, then relabel boundary voxels of the posed grid so that each label keeps the volume the deformation gives it "
                "(sum of the transfer mesh's Jacobian determinants over its voxels), within about a voxel; "
                "--preserve-volumes=rest: its rest volume instead, so organ masses are kept; in core only")
      ->check(CLI::IsMember({"deformed", "rest"}));
  cmd->add_flag("!--no-skin-cover", o->run.coverSkin,
                "With --preserve-volumes: leave bare the tissue the pose lays open (the arm parted from the trunk, a crease opened, "
                "a thin skin stripped by the slices) instead of relabelling it skin (the organ table's 'Skin...' label nearest it; "
                "tissue bare at rest and bone are left as they are either way)");
  cmd->add_flag("--rigid-bones", o->run.rigidBones,
                "With body parts (a joint pose, --parts): hold each part's bones rigid (its forward-kinematics motion, else the rigid fit) "
                "and turn the cage near each turned joint with the moving part (joint_options zone 'child' unless the pose sets it); "
                "the tissue between bones turning against each other may fold (docs/POSES.md)");
  CLI::Option* articulated = cmd->add_flag("--articulated", o->run.articulated,
                                           "A joint pose on the transfer mesh that resolves the skeleton: bones moved by their parts' motions exactly, "
                                           "shoulders, hips, elbows and knees sliding, the soft tissue by an injective solve (no cage, no refinement); "
                                           "a pose it cannot reach without inverting a tet is refused unless --force (docs/POSES.md)");
  cmd->add_option("--bone-gap", o->run.boneGapMm,
                  "With --articulated: cut the tissue between the two parts' bones where they lie within this gap of each other "
                  "near a wrist, elbow or hip, so that the carpals slide past the radius, the olecranon out of the humerus' fossa and "
                  "the femoral neck past the acetabulum's rim as the joint turns, mm (0: none; docs/POSES.md)")
      ->capture_default_str()
      ->check(numberIn(0, 100, "mm"))
      ->needs(articulated);
  cmd->add_option("--max-body-change", o->run.maxBodyChangePercent,
                  "Refuse (write nothing) when the whole body's volume changes by more than this, %")
      ->capture_default_str()
      ->check(numberIn(0, 1000, "%"));
  cmd->add_option("--max-bone-change", o->run.maxBoneChangePercent,
                  "Refuse (write nothing) when a bone's volume changes by more than this, % (with an organ table that names the bones)")
      ->capture_default_str()
      ->check(numberIn(0, 1000, "%"));
  cmd->add_option("--max-bone-overlap", o->run.maxBoneOverlapPercent,
                  "Refuse (write nothing) a joint pose that presses two parts' bones through each other by more than this share of the "
                  "smaller part's bones, %")
      ->capture_default_str()
      ->check(numberIn(0, 100, "%"));
  cmd->add_option("--max-tissue-overlap", o->run.maxTissueOverlapPercent,
                  "Refuse (write nothing) a pose that presses two body parts' tissue through each other over more than this share of "
                  "the body, % (the report's collisions; with an organ table that names the bones)")
      ->capture_default_str()
      ->check(numberIn(0, 100, "%"));
  cmd->add_flag("--force", o->run.force,
                "Write a result beyond --max-body-change, --max-bone-change, --max-bone-overlap or --max-tissue-overlap anyway (a "
                "warning, and \"forced\": true in the report)");
  cmd->add_flag("--allow-growth", o->run.allowGrowth,
                "Accept a posed grid of more than 8 times the source's voxels (a pose that moves parts far from the body)");
  cmd->add_flag("--cpu", o->cpu, "Rasterize and interpolate fields with the CPU reference instead of the GPU");
  cmd->add_option("--max-tets", o->run.maxTets, "Tet budget of the refined transfer mesh")->capture_default_str()
      ->check(integerIn(1000, std::int64_t(1) << 30));
  cmd->add_option("--refine-iterations", o->run.refineIterations,
                  "Splitting rounds of the deformation-adaptive refinement at most (0: none)")
      ->capture_default_str()
      ->check(integerIn(0, 100));
  cmd->add_flag("-q,--quiet", o->quiet, "No progress or summary (warnings still go to stderr)");
  cmd->callback([o] { deform(*o); });
}

}  // namespace vox::app
