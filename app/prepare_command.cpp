// voxmorph prepare: the rest state of a label grid (skeleton, body parts and
// joints, cage, envelope, transfer mesh), computed once and saved for the
// poses to come (deform/prepared_state.h, geometry/deform/run/prepare_run.h).
// `deform`, `render --pose` and `view` take it with --prepared and skip that
// pre-processing; their results are byte-identical to a run without it. The
// file holds a cage and transfer mesh per set of separations: those of each
// --pose (compiled against the skeleton for a joint pose) plus --separate,
// or of a pose without separations when no --pose is given; with
// --articulated also the transfer mesh that resolves the skeleton.

#include "app/command_line.h"
#include "geometry/deform/cage/cage_builder.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/deform/pose/pose_frame.h"
#include "geometry/deform/prepared_state.h"
#include "geometry/deform/run/prepare_run.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/output_path.h"
#include "geometry/organ_table.h"
#include "geometry/skeleton/bones.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace vox::app {

namespace {

struct PrepareOptions {
  PrepareRequest run;
  std::string output, organs;
  std::vector<std::string> poses, separations;
  bool quiet = false;
};

void prepare(const PrepareOptions& o) {
  retainFreedMemory();
  installStderrProgress(o.quiet);
  const auto t0 = std::chrono::steady_clock::now();
  checkOutputPath(o.output, OutputKind::Prepared, "--output");
  checkGridFitsMemory(o.run.input, 0, kDeformMemory, "prepare its rest state", "prepare holds the whole grid in memory");
  PrepareRequest request = o.run;
  const GridGeometry frame = openGridSlices(o.run.input)->geometry();
  if (!o.organs.empty()) request.organs = OrganTable::read(o.organs);
  request.organsSource = o.organs;
  // Poses and --separate boxes are in the world frame (world_frame.h).
  for (const std::string& path : o.poses) {
    request.poses.push_back(poseInGridFrame(readPose(path), frame, path));
    request.poseSources.push_back(path);
  }
  for (const std::string& text : o.separations) {
    request.extraSeparations.push_back(parseSeparation(text));
    regionInGridFrame(request.extraSeparations.back().region, frame, "--separate " + text);
  }
  if (!request.extraSeparations.empty()) requireOrganTable(request.organs.has_value(), OrganTableNeed::Separation, "--separate", true);
  for (std::size_t i = 0; i < request.poses.size(); ++i) {
    const Pose& pose = request.poses[i];
    if (!pose.separations.empty()) requireOrganTable(request.organs.has_value(), OrganTableNeed::Separation, request.poseSources[i]);
    if (usesLabelGroups(pose)) requireOrganTable(request.organs.has_value(), OrganTableNeed::LabelGroup, request.poseSources[i]);
    if (!pose.joints.empty() || usesBodyParts(pose)) {
      requireOrganTable(request.organs.has_value(), OrganTableNeed::Bones, request.poseSources[i]);
      skeleton::requireBones(*request.organs, o.organs);
    }
  }
  if (request.articulated || std::any_of(request.poses.begin(), request.poses.end(), [](const Pose& p) { return p.articulated; })) {
    if (!o.run.parts.empty()) throw UsageError("--articulated", "cannot be combined with --parts (deform --articulated takes none)");
    requireOrganTable(request.organs.has_value(), OrganTableNeed::Bones, "--articulated");
    skeleton::requireBones(*request.organs, o.organs);
  }
  if (!o.run.parts.empty()) {
    requireOrganTable(request.organs.has_value(), OrganTableNeed::Bones, "--parts");
    if (openGridSlices(o.run.parts)->geometry().dims != frame.dims) throw InputError(o.run.parts, "has other dims than the grid " + o.run.input);
  }

  const PrepareResult result = prepareRestState(request);
  result.state.write(o.output);
  if (o.quiet) return;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%s: prepared state of %s, %s bytes, %.1f s\n", o.output.c_str(), o.run.input.c_str(),
              withThousands(std::filesystem::file_size(o.output)).c_str(), seconds);
  std::fputs(result.state.summary().c_str(), stdout);
  for (const StageTime& t : result.stages) std::printf("  %-40s %7.2f s\n", t.name.c_str(), t.seconds);
}

}  // namespace

void addPrepareCommand(CLI::App& app) {
  auto o = std::make_shared<PrepareOptions>();
  CLI::App* cmd = addGridSubcommand(app, "prepare",
                                    "Save the rest state of a label grid (skeleton, cage, envelope, transfer mesh) for deform, render and "
                                    "view --prepared",
                                    o->run.input);
  cmd->add_option("-o,--output", o->output, "Prepared state (.vxprep)")->required();
  cmd->add_option("--organs", o->organs, "Organ table (ID name tissue density): label groups, the bones of the skeleton; the runs "
                                         "that take the state give the same one");
  cmd->add_option("--pose", o->poses,
                  "A pose (JSON, docs/POSES.md) to prepare for (repeatable): the state holds a cage and transfer mesh for its "
                  "separations (a joint pose's compiled ones); without --pose, for a pose without separations")
      ->allow_extra_args(false);
  cmd->add_option("--parts", o->run.parts, "Body-part grid (voxmorph parts, corrected) instead of the assignment from the bones, as deform --parts");
  cmd->add_option("--separate", o->separations,
                  "Separate two label groups in the cage and the transfer mesh, as deform --separate (repeatable; adds to each "
                  "pose's separations; the runs that take the state give the same ones)")
      ->allow_extra_args(false);
  cmd->add_option("--dilation", o->run.dilationMm, "Automatic cage: offset from the foreground, mm (the runs give the same)")
      ->capture_default_str()
      ->check(numberIn(0, 10000, "mm", true));
  cmd->add_option("--vertices", o->run.vertices, "Automatic cage: vertices after QEM (the runs give the same)")
      ->capture_default_str()
      ->check(integerIn(8, 100000));
  CLI::Option* articulated = cmd->add_flag("--articulated", o->run.articulated,
                                           "Also the transfer mesh that resolves the skeleton, for deform --articulated (needs an organ table that names the bones)");
  cmd->add_option("--bone-gap", o->run.boneGapMm, "With --articulated: the bone-gap cut at the wrists, elbows and hips, as deform --bone-gap (the runs give the same), mm")
      ->capture_default_str()
      ->check(numberIn(0, 100, "mm"))
      ->needs(articulated);
  cmd->add_flag("-q,--quiet", o->quiet, "No progress or summary");
  cmd->callback([o] { prepare(*o); });
}

}  // namespace vox::app
