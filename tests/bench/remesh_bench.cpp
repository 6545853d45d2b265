// M-MAd remesher against its peer, CGAL 5.5's tetrahedral_isotropic_remeshing,
// side by side: the same initial mesh (the adaptive conforming decomposition
// of the grid, with its imaginary layer as CGAL's subdomain 0) and the same
// target length, 10 iterations plus 3 flip-smooth rounds for both (CGAL's
// fixed extra rounds). Quality and topology of both outputs are measured
// with the same code (mesh_quality.h, mesh_topology.h).
//
// This binary, and only this one, links CGAL: the peer is its own code.
//
//   build/release/bench/remesh_bench                       # AM phantom, l = 8 mm
//   VOX_REMESH_GRID=path.nii.gz VOX_REMESH_L=4.274 build/release/bench/remesh_bench
//   VOX_REMESH_VOXELS=2 build/release/bench/remesh_bench --benchmark_filter=MMAdRemesh/2   # l = 2 voxels
//   VOX_REMESH_SYNTH=junctions:48 VOX_REMESH_L=2.5 build/release/bench/remesh_bench
//   VOX_REMESH_CROP=60,20,100,96,64,40 build/release/bench/remesh_bench  # a box of voxels
//
// Counters: tets (domain), min/max dihedral, tets under 15 and 5 degrees,
// topology differences against the grid (0 = every label, 1-junction and
// 0-junction kept), largest per-label volume change, process CPU seconds.
// The M-MAd run is marked as an error when its output lost any label,
// junction or Euler characteristic, or holds a tet of volume <= 0 (the
// acceptance check of the full phantom at l = 2 voxels, too slow for ctest).

#include "geometry/io/grid_io.h"
#include "geometry/mesh_quality.h"
#include "geometry/remesh/adaptive_voxel_tetrahedralization.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh.h"
#include "geometry/synth.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_3/tet_soup_to_c3t3.h>
#include <CGAL/Tetrahedral_remeshing/Remeshing_triangulation_3.h>
#include <CGAL/tetrahedral_remeshing.h>

#include "geometry/deform/pipeline.h"  // processCpuSeconds

#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace {

using namespace vox;

struct Case {
  std::string name;
  LabelGrid grid;
  double targetLength = 8.0;
  TetMesh initial;  // domain and imaginary tets
  remesh::MeshTopology topology;
  TetQualitySummary initialQuality;
  double decompositionSeconds = 0.0;
};

const Case& benchCase() {
  static std::unique_ptr<Case> c = [] {
    auto k = std::make_unique<Case>();
    const char* synth = std::getenv("VOX_REMESH_SYNTH");
    const char* grid = std::getenv("VOX_REMESH_GRID");
    if (synth) {
      const std::string s = synth;
      const auto colon = s.find(':');
      k->name = s;
      k->grid = synthesize(synthKindFromName(s.substr(0, colon)), colon == std::string::npos ? 48 : std::stoi(s.substr(colon + 1)));
    } else {
      k->name = grid ? grid : std::string(VOX_ASSETS_DIR) + "/icrp110_am.nii.gz";
      k->grid = readGrid(k->name);
    }
    if (const char* crop = std::getenv("VOX_REMESH_CROP")) {
      std::int64_t b[6];
      if (std::sscanf(crop, "%ld,%ld,%ld,%ld,%ld,%ld", &b[0], &b[1], &b[2], &b[3], &b[4], &b[5]) != 6)
        throw std::runtime_error("VOX_REMESH_CROP wants x0,y0,z0,nx,ny,nz");
      GridGeometry g = k->grid.geometry();
      g.dims = {b[3], b[4], b[5]};
      g.origin = k->grid.geometry().voxelCenter(b[0], b[1], b[2]);
      LabelGrid cropped(g);
      for (std::int64_t z = 0; z < b[5]; ++z)
        for (std::int64_t y = 0; y < b[4]; ++y)
          for (std::int64_t x = 0; x < b[3]; ++x) cropped.at(x, y, z) = k->grid.atOr(b[0] + x, b[1] + y, b[2] + z);
      k->grid = std::move(cropped);
      k->name += std::string(" cropped to ") + crop;
    }
    if (const char* l = std::getenv("VOX_REMESH_L")) k->targetLength = std::atof(l);
    if (const char* v = std::getenv("VOX_REMESH_VOXELS")) k->targetLength = std::atof(v) * k->grid.spacing().minCoeff();
    const auto t0 = std::chrono::steady_clock::now();
    k->initial = remesh::tetrahedralizeVoxelsAdaptive(
        k->grid, remesh::adaptiveOptionsForTarget(k->grid.geometry(), k->targetLength));
    k->decompositionSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    k->topology = remesh::computeGridTopology(k->grid);
    k->initialQuality = summarizeTetQuality(k->initial);
    std::fprintf(stderr, "%s: l = %g mm, initial mesh %zu tets (%zu domain) in %.2f s\n", k->name.c_str(),
                 k->targetLength, k->initial.tetCount(), k->initialQuality.tets, k->decompositionSeconds);
    return k;
  }();
  return *c;
}

// Returns whether the topology is kept and every tet has a positive volume.
bool reportOutput(benchmark::State& state, const Case& c, const TetMesh& out, double cpuSeconds) {
  const TetQualitySummary q = summarizeTetQuality(out);
  const remesh::MeshTopology topology = remesh::computeMeshTopology(out);
  const auto differences = remesh::compareTopology(c.topology, topology);
  double minVolume = std::numeric_limits<double>::infinity();
  for (const Tet& t : out.tets) minVolume = std::min(minVolume, signedVolume(out.positions, t));
  double worstVolume = 0.0;
  for (const auto& [label, v] : c.initialQuality.volumePerLabel) {
    auto it = q.volumePerLabel.find(label);
    const double after = it == q.volumePerLabel.end() ? 0.0 : it->second;
    worstVolume = std::max(worstVolume, std::abs(after / v - 1.0));
  }
  state.counters["tets"] = double(q.tets);
  state.counters["min_dihedral"] = q.minDihedral;
  state.counters["max_dihedral"] = q.maxDihedral;
  state.counters["under_15"] = double(q.under15);
  state.counters["under_5"] = double(q.under5);
  state.counters["inverted"] = double(q.inverted);
  state.counters["min_volume"] = minVolume;
  state.counters["labels"] = double(topology.labels.size());
  state.counters["junction_curve_sets"] = double(topology.junctionCurves.size());
  state.counters["junction_point_sets"] = double(topology.junctionPoints.size());
  state.counters["topology_differences"] = double(differences.size());
  state.counters["max_label_volume_change"] = worstVolume;
  state.counters["process_cpu_s"] = cpuSeconds;
  for (std::size_t i = 0; i < differences.size() && i < 10; ++i) std::fprintf(stderr, "  %s\n", differences[i].c_str());
  if (differences.size() > 10) std::fprintf(stderr, "  ... %zu differences in all\n", differences.size());
  return differences.empty() && minVolume > 0.0;
}

void BM_MMAdRemesh(benchmark::State& state) {
  const Case& c = benchCase();
  for (auto _ : state) {
    remesh::RemeshOptions options;
    options.targetLength = c.targetLength;
    options.iterations = 10;
    options.flipSmoothCycles = 3;
    options.threads = int(state.range(0));
    const auto wall0 = std::chrono::steady_clock::now();
    const double cpu0 = vox::processCpuSeconds();
    const TetMesh out = remesh::remeshTetMesh(c.initial, options);
    const double cpu = vox::processCpuSeconds() - cpu0;
    state.PauseTiming();
    std::fprintf(stderr, "M-MAd (%d threads): %.1f s wall\n", options.threads,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count());
    if (!reportOutput(state, c, out, cpu)) state.SkipWithError("topology changed or a tet is not positive");
    state.ResumeTiming();
  }
}

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalTriangulation = CGAL::Tetrahedral_remeshing::Remeshing_triangulation_3<Kernel>;

void BM_CgalRemesh(benchmark::State& state) {
  const Case& c = benchCase();
  for (auto _ : state) {
    const double cpu0 = vox::processCpuSeconds();
    // The same tets, finite cells of a Triangulation_3; subdomain 0 (our
    // imaginary layer) is outside for CGAL, the convex hull is the box.
    CgalTriangulation tr;
    std::vector<CgalTriangulation::Point> points;
    points.reserve(c.initial.vertexCount());
    for (const Eigen::Vector3d& p : c.initial.positions) points.emplace_back(p[0], p[1], p[2]);
    std::vector<std::array<int, 5>> cells;
    cells.reserve(c.initial.tetCount());
    for (std::size_t t = 0; t < c.initial.tetCount(); ++t) {
      const Tet& q = c.initial.tets[t];
      cells.push_back({q[0], q[1], q[2], q[3], c.initial.labels[t]});
    }
    std::map<std::array<int, 3>, int> noPatches;
    std::vector<CgalTriangulation::Vertex_handle> handles;
    if (!CGAL::build_triangulation<CgalTriangulation, true>(tr, points, cells, noPatches, handles))
      state.SkipWithError("CGAL could not build the triangulation");
    CGAL::tetrahedral_isotropic_remeshing(tr, c.targetLength, CGAL::parameters::number_of_iterations(10));
    const double cpu = vox::processCpuSeconds() - cpu0;
    state.PauseTiming();
    TetMesh out;
    std::map<CgalTriangulation::Vertex_handle, std::int32_t> index;
    for (auto v : tr.finite_vertex_handles()) {
      index[v] = std::int32_t(out.positions.size());
      out.positions.emplace_back(v->point().x(), v->point().y(), v->point().z());
    }
    for (auto cell : tr.finite_cell_handles()) {
      if (cell->subdomain_index() <= 0) continue;
      out.tets.push_back({index[cell->vertex(0)], index[cell->vertex(1)], index[cell->vertex(2)], index[cell->vertex(3)]});
      out.labels.push_back(cell->subdomain_index());
    }
    reportOutput(state, c, out, cpu);
    state.ResumeTiming();
  }
}

BENCHMARK(BM_MMAdRemesh)->Arg(2)->Arg(1)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_CgalRemesh)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
