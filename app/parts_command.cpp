// voxmorph parts: the body parts of a label grid from its bones (the organ
// table names them): every foreground voxel gets the part of its nearest
// bone measured inside the body, written as a label grid of the input's
// geometry; the joints estimated from the bones go to the report (mm, world
// frame). A corrected parts grid can be passed back with --parts (here to
// report its joints and sizes, and to deform and render).

#include "app/command_line.h"
#include "geometry/error.h"
#include "geometry/atomic_file.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/output_path.h"
#include "geometry/organ_table.h"
#include "geometry/skeleton/skeleton.h"

#include <cstdio>
#include <memory>

namespace vox::app {

namespace {

struct PartsOptions {
  std::string input, organs, output, report, parts;
  bool quiet = false;
};

void parts(const PartsOptions& o) {
  installStderrProgress(o.quiet);
  checkOutputPath(o.output, OutputKind::Grid, "--output");
  checkOutputPath(o.report, OutputKind::Json, "--report");
  const OrganTable organs = OrganTable::read(o.organs);
  skeleton::requireBones(organs, o.organs);
  const LabelGrid grid = readGrid(o.input);
  std::optional<LabelGrid> user;
  if (!o.parts.empty()) user = readGrid(o.parts);
  const skeleton::Skeleton s = skeleton::buildSkeleton(grid, organs, {o.input, o.organs, o.parts}, std::move(user));
  writeGrid(o.output, s.parts.parts);
  if (!o.report.empty()) {
    const std::string json = skeleton::skeletonReportJson(s, grid.geometry(), o.input, o.output);
    if (o.report == "-") std::fputs(json.c_str(), stdout);
    else writeFileAtomic(o.report, json);
  }
  if (!o.quiet && o.report != "-") {
    std::printf("%s: %zu joints, %.1f s\n\n", o.output.c_str(), s.joints.size(), s.seconds);
    std::fputs(skeleton::skeletonSummary(s, grid.geometry()).c_str(), stdout);
  }
}

}  // namespace

void addPartsCommand(CLI::App& app) {
  auto o = std::make_shared<PartsOptions>();
  CLI::App* cmd = addGridSubcommand(app, "parts", "Body parts from the bones (nearest bone inside the body) and the joints", o->input);
  cmd->add_option("--organs", o->organs, "Organ table (ID name tissue density) that names the bones")->required();
  cmd->add_option("-o,--output", o->output, "Body-part grid (.nii.gz ...; values: the part ids of the report)")->required();
  cmd->add_option("--report", o->report, "JSON report: parts (id, name, voxels, volume, bones), joints (centre, axes, ranges; mm, world frame); "
                                         "'-' for stdout");
  cmd->add_option("--parts", o->parts, "A body-part grid to use instead of the assignment (same dims as the grid)");
  cmd->add_flag("-q,--quiet", o->quiet, "No progress or summary");
  cmd->callback([o] { parts(*o); });
}

}  // namespace vox::app
