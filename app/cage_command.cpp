// voxmorph cage: the automatic cage of a label grid (thesis 3.2.2, 4.2.1):
// dilation in mm, restricted Delaunay boundary, QEM to a vertex count; an
// inset cage where limbs are separated (--separate, with the organ table that
// names the label groups). Reports its size, validity and the foreground
// voxels it leaves outside; an invalid cage is an error and is not written.

#include "app/command_line.h"
#include "geometry/deform/cage/cage_builder.h"
#include "geometry/skeleton/label_groups.h"
#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/pose_frame.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/mesh_io.h"
#include "geometry/io/output_path.h"
#include "geometry/organ_table.h"
#include "geometry/world_frame.h"

#include <chrono>
#include <cstdio>
#include <memory>
#include <sstream>

namespace vox::app {

LimbSeparation parseSeparation(const std::string& text) {
  const std::string usage = "expected GROUP:GROUP or GROUP:GROUP@xmin,ymin,zmin,xmax,ymax,zmax (mm), e.g. right_arm:trunk";
  const std::size_t at = text.find('@');
  const std::string groups = text.substr(0, at);
  const std::size_t colon = groups.find(':');
  if (colon == std::string::npos) throw InputError("--separate " + text, usage);
  LimbSeparation s;
  s.groupA = Label(labelGroupFromName(groups.substr(0, colon), "--separate " + text));
  s.groupB = Label(labelGroupFromName(groups.substr(colon + 1), "--separate " + text));
  if (s.groupA == s.groupB) throw InputError("--separate " + text, "separates a group from itself");
  if (at != std::string::npos) {
    std::istringstream in(text.substr(at + 1));
    double v[6];
    for (int k = 0; k < 6; ++k) {
      char comma = ',';
      if (!(in >> v[k]) || (k < 5 && !(in >> comma)) || comma != ',') throw InputError("--separate " + text, usage);
    }
    in >> std::ws;
    if (!in.eof()) throw InputError("--separate " + text, usage);
    const Eigen::Vector3d lo(v[0], v[1], v[2]), hi(v[3], v[4], v[5]);
    if ((lo.array() > hi.array()).any() || !lo.allFinite() || !hi.allFinite())
      throw InputError("--separate " + text, "the region needs min <= max on every axis");
    s.region = Eigen::AlignedBox3d(lo, hi);
  }
  return s;
}

void warnForegroundOutside(std::int64_t voxels, bool separated) {
  if (voxels == 0 || separated) return;
  std::fprintf(stderr,
               "voxmorph: warning: %s foreground voxels lie outside the cage without limb separation; the propagation "
               "solve places them, but a larger --dilation (or --separate where limbs touch) keeps them inside\n",
               withThousands(std::uint64_t(voxels)).c_str());
}

namespace {

struct CageCommandOptions {
  std::string input, output, report, organs;
  std::vector<std::string> separations;
  CageOptions cage;
  std::int64_t maxMemoryMb = 0;  // 0: the machine's memory
  bool quiet = false;
};

void buildCageCommand(const CageCommandOptions& o) {
  installStderrProgress(o.quiet);
  checkOutputPath(o.output, OutputKind::Surface, "--output");
  checkOutputPath(o.report, OutputKind::Json, "--report");
  CageOptions options = o.cage;
  for (const std::string& s : o.separations) options.separations.push_back(parseSeparation(s));
  if (!options.separations.empty()) requireOrganTable(!o.organs.empty(), OrganTableNeed::Separation, "--separate", true);

  checkGridFitsMemory(o.input, o.maxMemoryMb, kCageMemory, "build the cage", "the cage needs the whole grid in memory");
  const auto t0 = std::chrono::steady_clock::now();
  const LabelGrid grid = readGrid(o.input);
  const Provenance provenance = commandProvenance({{"grid", o.input}, {"organs", o.organs}});
  for (LimbSeparation& s : options.separations) regionInGridFrame(s.region, grid.geometry(), "--separate");
  const LabelGrid groups = options.separations.empty() ? binaryGroupGrid(grid) : labelGroupGrid(grid, OrganTable::read(o.organs));
  const CageResult r = buildCage(groups, options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const SurfaceCheck& c = r.report.check;
  if (!c.validCage())
    throw RuntimeFailure(o.input + ": the automatic cage is not a valid cage (" + cageFault(c) +
                         "); try another --vertices or --dilation");
  TriMesh cage = r.cage;
  surfaceGridToWorld(cage, grid.geometry());
  writeSurface(o.output, cage);

  if (!o.report.empty()) {
    nlohmann::json j = {{"input", o.input},
                        {"output", o.output},
                        {"seconds", seconds},
                        {"vertices", r.cage.vertexCount()},
                        {"faces", r.cage.faceCount()},
                        {"meshed_vertices_before_qem", r.report.meshedVertices},
                        {"dilation_mm", options.dilationMm},
                        {"separations", options.separations.size()},
                        {"eroded_voxels", r.report.erodedVoxels},
                        {"foreground_voxels_outside", r.report.foregroundOutside},
                        {"valid", c.validCage()},
                        {"closed_manifold", c.closedManifold()},
                        {"self_intersections", c.selfIntersections},
                        {"genus", c.genus},
                        {"components", c.components},
                        {"volume_mm3", c.volume},
                        {"provenance", nlohmann::json::parse(provenanceJson(provenance))}};
    writeJson(o.report, j);
  }
  if (!o.quiet)
    std::printf("%s: %zu vertices, %zu faces (from %zu before QEM), genus %d, valid; %s foreground voxels outside%s; %.1f s\n",
                o.output.c_str(), r.cage.vertexCount(), r.cage.faceCount(), r.report.meshedVertices, c.genus,
                withThousands(std::uint64_t(r.report.foregroundOutside)).c_str(),
                options.separations.empty() ? "" : (" (" + withThousands(std::uint64_t(r.report.erodedVoxels)) + " eroded)").c_str(),
                seconds);
  warnForegroundOutside(r.report.foregroundOutside, !options.separations.empty());
}

}  // namespace

void addCageCommand(CLI::App& app) {
  auto o = std::make_shared<CageCommandOptions>();
  CLI::App* cmd = addGridSubcommand(app, "cage", "Build the automatic deformation cage of a label grid (inset where limbs are separated)", o->input);
  cmd->add_option("-o,--output", o->output, "Output cage (.obj .off .ply)")->required();
  cmd->add_option("--report", o->report, "JSON report (sizes, validity, voxels outside); '-' for stdout");
  cmd->add_option("--organs", o->organs, "Organ table (ID name tissue density): label groups for --separate");
  cmd->add_option("--max-memory", o->maxMemoryMb,
                  "Refuse a grid whose in-core work exceeds this budget (MB; default the machine's memory)")
      ->check(integerIn(64, std::int64_t(1) << 30, "MB"));
  cmd->add_option("--separate", o->separations,
                  "Separate two label groups (trunk, head, right_arm, left_arm, right_leg, left_leg), optionally inside a "
                  "box in mm: right_arm:trunk or right_arm:trunk@xmin,ymin,zmin,xmax,ymax,zmax (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--dilation", o->cage.dilationMm, "Offset of the cage from the foreground, mm")->capture_default_str()
      ->check(numberIn(0, 10000, "mm", true));
  cmd->add_option("--vertices", o->cage.targetVertices, "Cage vertices after QEM simplification")->capture_default_str()
      ->check(integerIn(8, 100000));
  cmd->add_flag("-q,--quiet", o->quiet, "No progress or summary (warnings still go to stderr)");
  cmd->callback([o] { buildCageCommand(*o); });
}

}  // namespace vox::app
