#pragma once
// What `voxmorph mesh` and `voxmorph remesh` share: the remesher's options,
// and running it on an initial mesh, writing the mesh and the report.

#include "app/command_line.h"
#include "geometry/atomic_file.h"
#include "geometry/io/mesh_io.h"
#include "geometry/io/png_io.h"
#include "geometry/io/output_path.h"
#include "geometry/io/sizing_grid_io.h"
#include "geometry/error.h"
#include "geometry/organ_table.h"
#include "geometry/remesh/meshing_estimate.h"
#include "geometry/remesh/remesh.h"
#include "geometry/remesh/remesh_report.h"
#include "geometry/remesh/sizing_field.h"
#include "geometry/world_frame.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace vox::app {

struct RemeshCliOptions {
  std::string input, output, report, organs;
  OrganTable organTable;  // read from `organs` by checkRemeshArguments
  remesh::RemeshOptions remesh;
  // Adaptive sizing: l_B and l_I of eq. 2.2 (0: uniform), or a grid of lengths.
  double sizeBoundary = 0.0, sizeInterior = 0.0;
  std::string sizeGrid;
  ScalarGrid sizeGridLengths;  // read from `sizeGrid` by checkRemeshArguments
  std::shared_ptr<const remesh::SizingField> sizing;  // what remesh.sizing points to
  // Tagged features (thesis 2.3.8): the user's polylines (read from
  // `features` by checkRemeshArguments, world mm) and the outer boundary's
  // sharp creases (remesh.sharpFeatures, remesh.featureAngle).
  std::string features;
  std::vector<remesh::FeatureSegment> featureSegments;
  std::string surface = "hpss";
  bool keepImaginary = false;
  bool noDistances = false;
  std::int64_t maxMemoryMb = 0;  // 0: the machine's physical memory
  bool quiet = false;
};

inline void addRemeshOptions(CLI::App& cmd, RemeshCliOptions& o) {
  const CLI::Validator meshExtension(
      [](std::string& path) {
        return hasTetMeshExtension(path) ? std::string() : "unknown mesh format '" + path + "' (use .mesh, .vtu or .msh)";
      },
      "MESH");
  CLI::Option* length =
      cmd.add_option("-l,--length", o.remesh.targetLength,
                     "Target edge length l (mm); e_min = 4/5 l, e_max = 4/3 l (required unless the sizing is adaptive)")
          ->check(numberIn(0, 100000, "mm", true));
  CLI::Option* boundary =
      cmd.add_option("--size-boundary", o.sizeBoundary,
                     "Adaptive sizing: target edge length l_B on the label interfaces (mm), with --size-interior; "
                     "l = (l_I - l_B) D + l_B, D the distance to the interfaces normalized to [0, 1]")
          ->check(numberIn(0, 100000, "mm", true));
  CLI::Option* interior = cmd.add_option("--size-interior", o.sizeInterior,
                                         "Adaptive sizing: target edge length l_I farthest from the interfaces (mm), at "
                                         "least l_B")
                              ->check(numberIn(0, 100000, "mm", true));
  CLI::Option* grid = cmd.add_option("--size-grid", o.sizeGrid,
                                     "Adaptive sizing from a grid of target edge lengths (NIfTI, mm, all > 0), sampled in "
                                     "world mm (any extent and affine)");
  boundary->needs(interior);
  interior->needs(boundary);
  length->excludes(boundary)->excludes(interior)->excludes(grid);
  grid->excludes(boundary)->excludes(interior);
  cmd.add_option("-o,--output", o.output, "Output tet mesh (.mesh .vtu .msh), domain tets (label > 0)")
      ->required()
      ->check(meshExtension);
  cmd.add_option("--iterations", o.remesh.iterations, "Split-collapse-flip-smooth iterations")->capture_default_str()
      ->check(integerIn(0, 100));
  cmd.add_option("--flip-smooth", o.remesh.flipSmoothCycles, "Final flip-smooth cycles")->capture_default_str()->check(integerIn(0, 100));
  cmd.add_option("--surface", o.surface, "Interface model boundary vertices are projected on: hpss, pss, none")->capture_default_str()
      ->check(CLI::IsMember({"hpss", "pss", "none"}));
  cmd.add_option("--mls-radius", o.remesh.mlsRadius, "Width of the interface model's kernel (mm; default automatic)")
      ->check(numberIn(0, 100000, "mm"));
  cmd.add_option("--steiner-angle", o.remesh.steiner.angle,
                 "Sliver removal: split an edge of each tet still under this dihedral angle (degrees) where a new vertex "
                 "lifts the worst angle around it; 0 skips it")
      ->capture_default_str()
      ->check(numberIn(0, 60, "degrees"));
  cmd.add_flag("--sharp-features", o.remesh.sharpFeatures,
               "Keep the sharp creases of the outer boundary: its facets clustered into patches of normals within "
               "--feature-angle, the lines between patches tagged and written (.mesh Edges, .msh physical lines)");
  cmd.add_option("--feature-angle", o.remesh.featureAngle,
                 "Crease angle (degrees between facet normals) for --sharp-features; a feature line turning by more "
                 "is kept exactly at that point")
      ->capture_default_str()
      ->check(numberIn(1, 179, "degrees"));
  cmd.add_option("--features", o.features,
                 "Polylines to keep (world mm): a Medit .mesh with Vertices and Edges, or a text file of segments "
                 "'x0 y0 z0 x1 y1 z1' per line; snapped to the mesh's edges (split where they stray from it), tagged and "
                 "written like --sharp-features");
  cmd.add_option("--hausdorff", o.remesh.hausdorff, "Interface bound (units of l): collapses, smoothing moves and valence flips keep every "
                 "interface within it of the input's, both ways; 0: none")->capture_default_str()->check(numberIn(0, 10, "l"));
  cmd.add_option("--threads", o.remesh.threads, "Threads")->capture_default_str()->check(integerIn(1, 64));
  cmd.add_option("--organs", o.organs,
                 "Organ table (ID name tissue density): label names in the report, the .msh physical names and the "
                 ".vtu field data");
  cmd.add_option("--report", o.report,
                 "Also write the quality report as JSON, and its dihedral-angle histogram as a PNG beside it "
                 "(report.json: report_dihedral.png); - prints the JSON on stdout instead of the text");
  cmd.add_option("--max-memory", o.maxMemoryMb,
                 "Refuse a run whose estimated peak memory exceeds this budget (MB; default the machine's memory)")
      ->check(integerIn(64, std::int64_t(1) << 30, "MB"));
  cmd.add_flag("--keep-imaginary", o.keepImaginary, "Also write the imaginary layer around the domain (label 0)");
  cmd.add_flag("--no-distance", o.noDistances, "Skip the interface Hausdorff distances of the report");
  cmd.add_flag("-q,--quiet", o.quiet, "No progress on stderr");
}

// Where the dihedral-angle histogram of the report at `reportPath` goes: its
// name without a .json extension, followed by "_dihedral.png".
inline std::string dihedralHistogramPath(const std::string& reportPath) {
  const std::string ext = ".json";
  const bool json = reportPath.size() > ext.size() && reportPath.compare(reportPath.size() - ext.size(), ext.size(), ext) == 0;
  return (json ? reportPath.substr(0, reportPath.size() - ext.size()) : reportPath) + "_dihedral.png";
}

// Checks the output and report paths and reads the organ table, before the
// input is read.
inline void checkRemeshArguments(RemeshCliOptions& o) {
  if (o.remesh.targetLength == 0.0 && o.sizeBoundary == 0.0 && o.sizeGrid.empty())
    throw UsageError("--length", "a target edge length is required (or --size-boundary with --size-interior, or --size-grid)");
  if (o.sizeBoundary > 0.0) {
    if (o.sizeInterior < o.sizeBoundary) {
      char text[160];
      std::snprintf(text, sizeof text, "l_I = %g mm is shorter than --size-boundary l_B = %g mm", o.sizeInterior, o.sizeBoundary);
      throw UsageError("--size-interior", text);
    }
    o.remesh.targetLength = o.sizeBoundary;
  }
  checkOutputPath(o.output, OutputKind::TetMesh, "--output");
  if ((o.remesh.sharpFeatures || !o.features.empty()) && meshFormatFromPath(o.output) == MeshFormat::Vtu)
    throw UsageError("--output", "feature lines are written to .mesh and .msh only, not to " + o.output);
  checkOutputPath(o.report, OutputKind::Json, "--report");
  if (!o.organs.empty()) o.organTable = OrganTable::read(o.organs);
  if (!o.features.empty()) {
    o.featureSegments = readPolylineSegments(o.features);
    o.remesh.featureSource = o.features;
  }
  if (!o.sizeGrid.empty()) {
    o.sizeGridLengths = readSizingGrid(o.sizeGrid);
    remesh::checkSizingGrid(o.sizeGridLengths, o.sizeGrid);
    o.remesh.targetLength = double(*std::min_element(o.sizeGridLengths.values.begin(), o.sizeGridLengths.values.end()));
  }
}

// The files whose digests the report's provenance records: the input (as
// `role`), and the sizing grid when one was given.
inline std::vector<std::pair<std::string, std::string>> remeshInputs(const RemeshCliOptions& o, const std::string& role) {
  std::vector<std::pair<std::string, std::string>> files{{role, o.input}};
  if (!o.sizeGrid.empty()) files.emplace_back("size_grid", o.sizeGrid);
  if (!o.features.empty()) files.emplace_back("features", o.features);
  return files;
}

// Sets the remesher's sizing field from the options, for a mesh whose frame
// is the world rotated by `meshDirection` (world = meshDirection * p).
// `interfaces` builds the field of eq. 2.2 for l_B and l_I in that frame.
inline void setSizing(RemeshCliOptions& o, const Eigen::Matrix3d& meshDirection,
                      const std::function<remesh::SizingField(double, double)>& interfaces) {
  if (o.sizeBoundary > 0.0) {
    o.sizing = std::make_shared<remesh::SizingField>(interfaces(o.sizeBoundary, o.sizeInterior));
  } else if (!o.sizeGrid.empty()) {
    const Eigen::Matrix3d meshToGrid = o.sizeGridLengths.geometry.direction.transpose() * meshDirection;
    o.sizing = std::make_shared<remesh::SizingField>(std::move(o.sizeGridLengths), meshToGrid);
  }
  o.remesh.sizing = o.sizing.get();
}

// Names of the labels `mesh` holds: the organ table's when one was given,
// else those the input mesh had.
inline void nameLabels(TetMesh& mesh, const RemeshCliOptions& o, const TetMesh& input) {
  if (o.organs.empty()) {
    mesh.labelNames = input.labelNames;
    return;
  }
  std::map<std::int32_t, std::string> names;
  for (const auto& [id, organ] : o.organTable.organs()) names[id] = organ.name;
  setLabelNames(mesh, names);
}

// Prints the run's estimated size and refuses, before any work, a length
// longer than the labelled region or a run beyond the memory budget.
inline void checkRemeshEstimate(const RemeshCliOptions& o, const remesh::MeshingEstimate& e) {
  const double l = o.remesh.targetLength;
  char text[160];
  if (l > e.extentMm) {
    std::snprintf(text, sizeof text, "%g mm is longer than the labelled region (%.4g mm across); use at most %.4g mm", l, e.extentMm,
                  e.extentMm);
    throw UsageError("--length", text);
  }
  const std::int64_t budgetMb = o.maxMemoryMb > 0 ? o.maxMemoryMb : physicalMemoryMb();
  const std::string size = remesh::describeEstimate(e);
  if (e.bytes > (budgetMb << 20)) {
    const double shortest = l * std::cbrt(double(e.bytes) / double(budgetMb << 20));
    std::snprintf(text, sizeof text, "%g mm asks for %s, over the %lld MB budget; use -l %.3g or more, or raise --max-memory", l,
                  size.c_str(), (long long)budgetMb, shortest * 1.01);
    throw UsageError("--length", text);
  }
  if (!o.quiet && o.report != "-") std::fprintf(stderr, "estimate: %s at l = %g mm\n", size.c_str(), l);
}

// Remeshes `initial` (whose domain tets and topology the report compares
// against), writes the output mesh, prints the report and writes its JSON.
// `initialTopology` is computed once the remesher has accepted `initial`:
// its input checks name the file and the tet at fault, the topology's do not.
// `toWorld`: the grid whose frame `initial` is in (mesh), written in its
// world frame (world_frame.h); none for remesh, whose input is in world.
// `provenance` goes into the report.
inline void runRemesh(RemeshCliOptions& o, const TetMesh& initial, const std::function<remesh::MeshTopology()>& initialTopology,
                      double setupSeconds, const Provenance& provenance, const GridGeometry* toWorld = nullptr) {
  o.remesh.projectOnInterfaces = o.surface != "none";
  o.remesh.hermite = o.surface == "hpss";
  // The polylines are in world mm; the mesh of a grid is in the grid's frame.
  std::vector<remesh::FeatureSegment> segments = o.featureSegments;
  if (toWorld)
    for (remesh::FeatureSegment& s : segments)
      for (Eigen::Vector3d& p : s) p = worldToGrid(*toWorld, p);
  o.remesh.featureSegments = &segments;
  remesh::RemeshStats stats;
  std::vector<remesh::TaggedEdge> tagged;
  TetMesh output = remesh::remeshTetMesh(initial, o.remesh, &stats, o.keepImaginary, o.input, &tagged);
  nameLabels(output, o, initial);
  // One reference per line, from 1.
  MeshEdges edges;
  for (const remesh::TaggedEdge& e : tagged) {
    edges.edges.push_back({e.a, e.b});
    edges.refs.push_back(e.line + 1);
  }
  if (toWorld) {
    TetMesh world = output;
    tetMeshGridToWorld(world, *toWorld);
    writeTetMesh(o.output, world, edges);
  } else {
    writeTetMesh(o.output, output, edges);
  }
  remesh::ReportOptions reportOptions;
  reportOptions.distances = !o.noDistances;
  reportOptions.threads = o.remesh.threads;
  reportOptions.named = !o.organs.empty();
  remesh::RemeshReport report =
      remesh::buildRemeshReport(initial, initialTopology(), output, o.remesh.targetLength, stats, reportOptions);
  report.setupSeconds = setupSeconds;
  if (o.sizing) {
    report.sizingMin = o.sizing->minimum();
    report.sizingMax = o.sizing->maximum();
  }
  report.provenance = provenance;
  if (o.remesh.sharpFeatures || !o.features.empty()) {
    std::vector<remesh::FeatureSegment> kept;
    for (const remesh::TaggedEdge& e : tagged)
      kept.push_back({output.positions[std::size_t(e.a)], output.positions[std::size_t(e.b)]});
    remesh::measureFeatures(report, kept);
  }
  if (o.report == "-") {
    std::cout << remesh::reportJson(report);
    return;
  }
  std::printf("%s -> %s\n%s", o.input.c_str(), o.output.c_str(), remesh::reportText(report).c_str());
  if (!o.report.empty()) {
    writeFileAtomic(o.report, remesh::reportJson(report));
    writePng(dihedralHistogramPath(o.report), remesh::dihedralHistogramImage(report));
  }
}

}  // namespace vox::app
