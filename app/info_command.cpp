// voxmorph info: what a grid or mesh holds. For grids, per-label voxel counts
// and boxes are computed on the GPU (CPU reference with --cpu, both compared
// with --verify); with an organ table, names, volumes and masses.

#include "app/command_line.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/mesh_io.h"
#include "geometry/label_stats.h"
#include "geometry/mesh_quality.h"
#include "geometry/organ_table.h"
#include "geometry/world_frame.h"
#include "gpu/context.h"
#include "gpu/kernels/label_stats.h"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

namespace vox::app {

namespace {

struct InfoOptions {
  std::string input;
  std::string organs;
  bool json = false;
  bool cpu = false;
  bool verify = false;
  bool devices = false;
  std::int64_t maxMemoryMb = 0;
};

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

nlohmann::json vec3(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }

void printGridInfo(const InfoOptions& o, const GridGeometry& g, const LabelStats& stats, const std::optional<OrganTable>& organs,
                   const std::string& engine, double readMs, double statsMs, double gpuMs, std::optional<bool> cpuEqual);

void gridInfo(const InfoOptions& o) {
  std::optional<OrganTable> organs;
  if (!o.organs.empty()) organs = OrganTable::read(o.organs);
  auto t0 = std::chrono::steady_clock::now();
  LabelStats stats;
  std::string engine;
  double readMs = 0.0, statsMs = 0.0, gpuMs = 0.0;
  std::optional<bool> cpuEqual;
  if (o.maxMemoryMb > 0) {
    // Streamed: the grid is never held; statistics on the CPU, slab by slab.
    const std::unique_ptr<GridSliceReader> reader = openGridSlices(o.input);
    stats = computeLabelStats(*reader, (o.maxMemoryMb << 20) / 2);
    statsMs = msSince(t0);
    engine = "CPU (streamed under --max-memory)";
    printGridInfo(o, reader->geometry(), stats, organs, engine, readMs, statsMs, gpuMs, cpuEqual);
    return;
  }
  const LabelGrid grid = readGrid(o.input);
  readMs = msSince(t0);
  if (!o.cpu) {
    try {
      gpu::Context ctx;
      gpu::LabelStatsKernel kernel(ctx);
      t0 = std::chrono::steady_clock::now();
      stats = kernel.run(grid);
      statsMs = msSince(t0);
      gpuMs = kernel.lastGpuMs();
      engine = "GPU (" + ctx.info().name + ")";
    } catch (const RuntimeFailure& e) {
      if (o.verify) throw;
      std::fprintf(stderr, "voxmorph: warning: %s; using the CPU\n", e.what());
    }
  }
  if (engine.empty() || o.verify) {
    t0 = std::chrono::steady_clock::now();
    LabelStats cpu = computeLabelStats(grid);
    const double cpuMs = msSince(t0);
    if (engine.empty()) {
      stats = std::move(cpu);
      statsMs = cpuMs;
      engine = "CPU";
    } else {
      cpuEqual = cpu == stats;
    }
  }

  printGridInfo(o, grid.geometry(), stats, organs, engine, readMs, statsMs, gpuMs, cpuEqual);
}

void printGridInfo(const InfoOptions& o, const GridGeometry& g, const LabelStats& stats, const std::optional<OrganTable>& organs,
                   const std::string& engine, double readMs, double statsMs, double gpuMs, std::optional<bool> cpuEqual) {
  const double vv = g.voxelVolume();
  nlohmann::json j;
  j["file"] = o.input;
  j["kind"] = "grid";
  j["dims"] = {g.dims[0], g.dims[1], g.dims[2]};
  j["voxels"] = g.voxelCount();
  j["spacing_mm"] = vec3(g.spacing);
  j["origin_mm"] = vec3(g.origin);
  // World (RAS) coordinates, as nibabel reports them: the affine and the
  // axis codes.
  const Eigen::Matrix4d affine = g.indexToWorld();
  j["world_origin_mm"] = vec3(affine.topRightCorner<3, 1>());
  j["affine"] = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) j["affine"].push_back({affine(r, 0), affine(r, 1), affine(r, 2), affine(r, 3)});
  j["orientation"] = orientationCode(g);
  j["axis_aligned"] = axisAligned(g);
  j["voxel_volume_mm3"] = vv;
  j["read_ms"] = readMs;
  j["label_stats"] = {{"engine", engine}, {"ms", statsMs}, {"gpu_ms", gpuMs}};
  if (cpuEqual) j["label_stats"]["equals_cpu_reference"] = *cpuEqual;
  const std::uint64_t fg = stats.foregroundVoxels();
  j["foreground_voxels"] = fg;
  j["foreground_volume_mm3"] = double(fg) * vv;
  double totalMass = 0.0;
  nlohmann::json labels = nlohmann::json::array();
  for (std::size_t l = 0; l < stats.counts.size(); ++l) {
    if (stats.counts[l] == 0) continue;
    nlohmann::json e;
    e["label"] = l;
    e["voxels"] = stats.counts[l];
    e["volume_mm3"] = double(stats.counts[l]) * vv;
    const auto& b = stats.boxes[l];
    e["box_min"] = {b.lo[0], b.lo[1], b.lo[2]};
    e["box_max"] = {b.hi[0], b.hi[1], b.hi[2]};
    if (organs && l > 0) {
      if (const Organ* org = organs->find(int(l))) {
        e["name"] = org->name;
        e["density_g_cm3"] = org->density;
        e["mass_g"] = organs->mass(int(l), stats.counts[l], vv);
        totalMass += e["mass_g"].get<double>();
      } else {
        e["name"] = nullptr;
        e["unnamed"] = true;
      }
    }
    labels.push_back(e);
  }
  j["labels"] = labels;
  j["label_count"] = stats.presentLabels();
  std::string unnamedNote;
  if (organs) {
    j["total_mass_g"] = totalMass;
    j["unnamed_labels"] = organs->unnamedLabels(stats.counts);
    unnamedNote = unnamedLabelsNote(*organs, stats.counts);
  }

  if (o.json) {
    std::cout << j.dump(2) << "\n";
  } else {
    std::printf("file        %s\n", o.input.c_str());
    std::printf("dims        %lld x %lld x %lld (%s voxels)\n", (long long)g.dims[0], (long long)g.dims[1], (long long)g.dims[2],
                withThousands(std::uint64_t(g.voxelCount())).c_str());
    std::printf("spacing     %g x %g x %g mm (voxel %g mm^3)\n", g.spacing[0], g.spacing[1], g.spacing[2], vv);
    std::printf("origin      %g %g %g mm (world, RAS; centre of voxel 0,0,0)\n", affine(0, 3), affine(1, 3), affine(2, 3));
    std::printf("orientation %s (i, j, k towards; nibabel's aff2axcodes)%s\n", orientationCode(g).c_str(),
                axisAligned(g) ? "" : ", oblique");
    for (int r = 0; r < 3; ++r)
      std::printf("%s[%9.4f %9.4f %9.4f %10.3f]\n", r == 0 ? "affine      " : "            ", affine(r, 0), affine(r, 1), affine(r, 2),
                  affine(r, 3));
    std::printf("labels      %zu non-zero\n", stats.presentLabels());
    std::printf("foreground  %s voxels, %.1f cm^3\n", withThousands(fg).c_str(), double(fg) * vv * 1e-3);
    std::printf("statistics  %s, %.1f ms", engine.c_str(), statsMs);
    if (gpuMs > 0) std::printf(" (kernel %.1f ms)", gpuMs);
    if (cpuEqual) std::printf("; CPU reference %s", *cpuEqual ? "equal" : "DIFFERENT");
    std::printf("\n\n");
    std::printf("%6s  %-44s %12s %12s %8s %12s\n", "label", "name", "voxels", "volume cm3", "density", "mass g");
    for (const auto& e : labels) {
      const std::string name = e.contains("name") && e["name"].is_string() ? e["name"].get<std::string>() : (e["label"] == 0 ? "(background)" : organs ? "(not in organ table)" : "");
      std::printf("%6d  %-44.44s %12s %12.3f", e["label"].get<int>(), name.c_str(),
                  withThousands(e["voxels"].get<std::uint64_t>()).c_str(), e["volume_mm3"].get<double>() * 1e-3);
      if (e.contains("mass_g")) std::printf(" %8.3f %12.3f", e["density_g_cm3"].get<double>(), e["mass_g"].get<double>());
      std::printf("\n");
    }
    if (organs) std::printf("\ntotal mass  %.1f g\n", totalMass);
    if (!unnamedNote.empty()) std::printf("warning: %s\n", unnamedNote.c_str());
  }
  if (cpuEqual && !*cpuEqual) throw RuntimeFailure("GPU label statistics differ from the CPU reference");
}

void meshInfo(const InfoOptions& o) {
  const TetMesh mesh = readTetMesh(o.input);
  const TetQualitySummary q = summarizeTetQuality(mesh);
  nlohmann::json j;
  j["file"] = o.input;
  j["kind"] = "tet_mesh";
  j["vertices"] = mesh.vertexCount();
  j["tets"] = mesh.tetCount();
  j["domain_tets"] = q.tets;
  j["min_dihedral_deg"] = q.minDihedral;
  j["max_dihedral_deg"] = q.maxDihedral;
  j["tets_under_15_deg"] = q.under15;
  j["tets_under_5_deg"] = q.under5;
  j["mean_dihedral_deviation_from_70_5"] = q.meanDeviationFrom70;
  j["inverted_tets"] = q.inverted;
  nlohmann::json labels = nlohmann::json::array();
  for (const auto& [label, n] : q.tetsPerLabel) labels.push_back({{"label", label}, {"tets", n}, {"volume_mm3", q.volumePerLabel.at(label)}});
  j["labels"] = labels;
  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("file            %s\n", o.input.c_str());
  std::printf("vertices        %s\n", withThousands(mesh.vertexCount()).c_str());
  std::printf("tets            %s (%s with label > 0)\n", withThousands(mesh.tetCount()).c_str(), withThousands(q.tets).c_str());
  std::printf("dihedral        min %.2f, max %.2f degrees\n", q.minDihedral, q.maxDihedral);
  std::printf("under 15 deg    %zu tets (under 5: %zu)\n", q.under15, q.under5);
  std::printf("inverted        %zu tets\n", q.inverted);
  std::printf("\n%6s %12s %14s\n", "label", "tets", "volume mm3");
  for (const auto& [label, n] : q.tetsPerLabel) std::printf("%6d %12zu %14.2f\n", label, n, q.volumePerLabel.at(label));
}

}  // namespace

void addInfoCommand(CLI::App& app) {
  auto o = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand("info", "Describe a label grid or a tet mesh");
  cmd->add_option("input", o->input, "Grid (.nii .nii.gz .mha .mhd .nrrd .nhdr .inr) or mesh (.mesh .vtu .msh)");
  cmd->add_option("--organs", o->organs, "Organ table (ID name tissue density), for names and masses");
  cmd->add_flag("--json", o->json, "Print JSON instead of text");
  cmd->add_flag("--cpu", o->cpu, "Compute label statistics on the CPU only");
  auto* verify = cmd->add_flag("--verify", o->verify, "Compute on GPU and CPU and fail unless they are equal");
  cmd->add_flag("--devices", o->devices, "List the Vulkan devices and exit");
  cmd->add_option("--max-memory", o->maxMemoryMb,
                  "Stream the grid under this budget (MB) instead of holding it: CPU statistics, slab by slab")
      ->check(CLI::Range(std::int64_t(16), std::int64_t(1) << 30))
      ->excludes(verify);
  cmd->callback([o, cmd] {
    if (o->devices) {
      for (const auto& d : gpu::listDevices()) std::printf("%s\n", d.c_str());
      return;
    }
    if (o->input.empty()) throw CLI::RequiredError("input");
    if (hasTetMeshExtension(o->input)) meshInfo(*o);
    else gridInfo(*o);
  });
}

}  // namespace vox::app
