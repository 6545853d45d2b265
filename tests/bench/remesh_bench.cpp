// M-MAd remesher against its peer, CGAL 5.5's tetrahedral_isotropic_remeshing,
// side by side on the same input and target length, the same number of
// rounds for both (`voxmorph mesh`'s default, 5, or VOX_REMESH_ROUNDS) plus
// 3 flip-smooth rounds (CGAL's fixed extra rounds). Two inputs:
//   - the grid (default): M-MAd starts from the adaptive conforming
//     decomposition with its imaginary shell, as `voxmorph mesh` does; CGAL,
//     whose triangulation must fill a convex hull, from the same
//     decomposition with the imaginary layer filling the box (its
//     subdomain 0);
//   - VOX_REMESH_INPUT=mesh3: a CGAL Mesh_3 mesh of the grid with cells of
//     about l and facets within l / 4 of the labels' interfaces (facet
//     distance VOX_REMESH_MESH3_DISTANCE mm to change it; half a voxel gives
//     7.5 M tets on the AM at l = 8 mm; VOX_REMESH_MESH3_EXUDE=0 leaves out
//     the sliver exudation); M-MAd gets its domain tets, as a user's file
//     holds them, CGAL the Mesh_3 triangulation (outside cells subdomain 0).
// Quality and topology of both outputs are measured with the same code
// (mesh_quality.h, mesh_topology.h), topology against the grid, or against
// the Mesh_3 mesh for that input.
//
// This binary, and only this one, links CGAL: the peer is its own code.
//
//   build/release/bench/remesh_bench                       # AM phantom, l = 8 mm
//   VOX_REMESH_INPUT=mesh3 build/release/bench/remesh_bench # Mesh_3 mesh of the AM, l = 8 mm
//   VOX_REMESH_INPUT=mesh3 VOX_REMESH_MESH3_FILE=am_mesh3.mesh ...  # that mesh made once, then read
//   VOX_REMESH_GRID=path.nii.gz VOX_REMESH_L=4.274 build/release/bench/remesh_bench
//   VOX_REMESH_VOXELS=2 build/release/bench/remesh_bench --benchmark_filter=MMAdRemesh/2   # l = 2 voxels
//   VOX_REMESH_SYNTH=junctions:48 VOX_REMESH_L=2.5 build/release/bench/remesh_bench
//   VOX_REMESH_CROP=60,20,100,96,64,40 build/release/bench/remesh_bench  # a box of voxels
//   VOX_REMESH_PEER_OUTPUT=out.mesh ... --benchmark_filter=BM_PeerOutput  # measure another
//     remesher's output (MMG3D's: tests/bench/mmg3d_peer.sh) against the case's reference
//
// Counters: tets (domain), min/max dihedral, tets under 15, 10 and 5 degrees,
// topology differences against the reference (0 = every label, 1-junction
// and 0-junction kept), largest per-label volume change, process CPU
// seconds, peak RSS of the process so far (MB; run one benchmark per
// process for each remesher's own peak).
// The M-MAd run is marked as an error when its output lost any label,
// junction or Euler characteristic, or holds a tet of volume <= 0 (the
// acceptance check of the full phantom at l = 2 voxels, too slow for ctest).

#include "geometry/deform/cage/restricted_delaunay.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/mesh_io.h"
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

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <sys/resource.h>

namespace {

using namespace vox;

// Rounds for both remeshers: VOX_REMESH_ROUNDS, else `voxmorph mesh`'s default.
int rounds() {
  if (const char* r = std::getenv("VOX_REMESH_ROUNDS")) return std::max(1, std::atoi(r));
  return remesh::RemeshOptions{}.iterations;
}

struct Case {
  std::string name;
  LabelGrid grid;
  double targetLength = 8.0;
  TetMesh initial;      // M-MAd's input: domain and imaginary tets, or Mesh_3's domain tets
  TetMesh cgalInitial;  // CGAL's input: tets filling a convex hull, label 0 outside the domain
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
    const char* input = std::getenv("VOX_REMESH_INPUT");
    if (input && std::string(input) == "mesh3") {
      // Mesh_3 needs background on the border voxels: pad by one voxel.
      GridGeometry g = k->grid.geometry();
      g.dims = {g.dims[0] + 2, g.dims[1] + 2, g.dims[2] + 2};
      g.origin = k->grid.geometry().voxelCenter(-1, -1, -1);
      LabelGrid padded(g, 0);
      for (std::int64_t z = 0; z < k->grid.dims()[2]; ++z)
        for (std::int64_t y = 0; y < k->grid.dims()[1]; ++y)
          for (std::int64_t x = 0; x < k->grid.dims()[0]; ++x) padded.at(x + 1, y + 1, z + 1) = k->grid.at(x, y, z);
      SampledDomain domain;
      domain.labels = &padded;
      domain.labelAt = [&padded](const Eigen::Vector3d& p) {
        Index3 c;
        return padded.geometry().voxelAt(p, c) ? int(padded.at(c[0], c[1], c[2])) : 0;
      };
      const ScalarGrid sizing(padded.geometry(), float(k->targetLength));
      VolumeCriteria criteria;
      criteria.sizing = &sizing;
      criteria.facetDistanceMm = 0.25 * k->targetLength;
      if (const char* d = std::getenv("VOX_REMESH_MESH3_DISTANCE")) criteria.facetDistanceMm = std::atof(d);
      if (const char* e = std::getenv("VOX_REMESH_MESH3_EXUDE")) criteria.exude = std::string(e) != "0";
      criteria.keepOutside = true;
      // The Mesh_3 run can take longer than either remesher: with
      // VOX_REMESH_MESH3_FILE it is read from that file when present, else
      // made and written there, so that runs (one per remesher) share it.
      const char* cache = std::getenv("VOX_REMESH_MESH3_FILE");
      const bool read = cache && std::filesystem::exists(cache);
      if (read) {
        k->cgalInitial = readTetMesh(cache);
      } else {
        k->cgalInitial = restrictedDelaunayVolume(domain, criteria);
        if (cache) writeTetMesh(cache, k->cgalInitial);
      }
      for (std::size_t t = 0; t < k->cgalInitial.tetCount(); ++t)
        if (k->cgalInitial.labels[t] > 0) {
          k->initial.tets.push_back(k->cgalInitial.tets[t]);
          k->initial.labels.push_back(k->cgalInitial.labels[t]);
        }
      k->initial.positions = k->cgalInitial.positions;  // unused vertices are dropped by the remesher
      k->topology = remesh::computeMeshTopology(k->initial);
      // A file made by another run says nothing of its facet distance.
      k->name += read ? std::string(" (Mesh_3 read from ") + cache + ")"
                      : " (Mesh_3, facet distance " + std::to_string(criteria.facetDistanceMm) + " mm" +
                            (criteria.exude ? "" : ", not exuded") + ")";
    } else {
      remesh::AdaptiveTetrahedralizationOptions options = remesh::adaptiveOptionsForTarget(k->grid.geometry(), k->targetLength);
      k->initial = remesh::tetrahedralizeVoxelsAdaptive(k->grid, options);
      options.shell = false;
      k->cgalInitial = remesh::tetrahedralizeVoxelsAdaptive(k->grid, options);
      k->topology = remesh::computeGridTopology(k->grid);
    }
    k->decompositionSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    k->initialQuality = summarizeTetQuality(k->initial);
    std::fprintf(stderr, "%s: l = %g mm, %d rounds + 3, initial mesh %zu tets (%zu domain), CGAL's %zu tets, in %.2f s\n",
                 k->name.c_str(), k->targetLength, rounds(), k->initial.tetCount(), k->initialQuality.tets,
                 k->cgalInitial.tetCount(), k->decompositionSeconds);
    return k;
  }();
  return *c;
}

double peakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;
}

// Returns whether the topology is kept and every tet has a positive volume.
bool reportOutput(benchmark::State& state, const Case& c, const TetMesh& out, double cpuSeconds) {
  const TetQualitySummary q = summarizeTetQuality(out);
  const remesh::MeshTopology topology = remesh::computeMeshTopology(out);
  const auto differences = remesh::compareTopology(c.topology, topology);
  double minVolume = std::numeric_limits<double>::infinity();
  std::size_t under10 = 0;
  for (std::size_t t = 0; t < out.tetCount(); ++t) {
    const Tet& q = out.tets[t];
    minVolume = std::min(minVolume, signedVolume(out.positions, q));
    if (out.labels[t] <= 0) continue;
    const auto angles = dihedralAngles(out.positions[std::size_t(q[0])], out.positions[std::size_t(q[1])],
                                       out.positions[std::size_t(q[2])], out.positions[std::size_t(q[3])]);
    under10 += *std::min_element(angles.begin(), angles.end()) < 10.0;
  }
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
  state.counters["under_10"] = double(under10);
  state.counters["under_5"] = double(q.under5);
  state.counters["inverted"] = double(q.inverted);
  state.counters["min_volume"] = minVolume;
  state.counters["labels"] = double(topology.labels.size());
  state.counters["junction_curve_sets"] = double(topology.junctionCurves.size());
  state.counters["junction_point_sets"] = double(topology.junctionPoints.size());
  state.counters["topology_differences"] = double(differences.size());
  state.counters["max_label_volume_change"] = worstVolume;
  state.counters["process_cpu_s"] = cpuSeconds;
  state.counters["peak_rss_mb"] = peakRssMb();
  for (std::size_t i = 0; i < differences.size() && i < 10; ++i) std::fprintf(stderr, "  %s\n", differences[i].c_str());
  if (differences.size() > 10) std::fprintf(stderr, "  ... %zu differences in all\n", differences.size());
  return differences.empty() && minVolume > 0.0;
}

void BM_MMAdRemesh(benchmark::State& state) {
  const Case& c = benchCase();
  for (auto _ : state) {
    remesh::RemeshOptions options;
    options.targetLength = c.targetLength;
    options.iterations = rounds();
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

// The output of a remesher run outside this process (MMG3D's mmg3d_O3; its
// time is measured by the script that ran it), read from
// VOX_REMESH_PEER_OUTPUT and measured by the same code, topology against the
// case's reference. Without the variable, only the case is made (and its
// Mesh_3 file written, with VOX_REMESH_MESH3_FILE).
void BM_PeerOutput(benchmark::State& state) {
  const Case& c = benchCase();
  const char* path = std::getenv("VOX_REMESH_PEER_OUTPUT");
  for (auto _ : state) {
    if (!path) {
      state.SkipWithError("no VOX_REMESH_PEER_OUTPUT to measure");
      break;
    }
    const TetMesh out = readTetMesh(path);
    state.PauseTiming();
    reportOutput(state, c, out, 0.0);
    state.ResumeTiming();
  }
}

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalTriangulation = CGAL::Tetrahedral_remeshing::Remeshing_triangulation_3<Kernel>;

void BM_CgalRemesh(benchmark::State& state) {
  const Case& c = benchCase();
  for (auto _ : state) {
    const double cpu0 = vox::processCpuSeconds();
    // The input's tets as the finite cells of a Triangulation_3; subdomain 0
    // (the imaginary box, or Mesh_3's outside cells) is outside for CGAL.
    CgalTriangulation tr;
    std::vector<CgalTriangulation::Point> points;
    const TetMesh& in = c.cgalInitial;
    points.reserve(in.vertexCount());
    for (const Eigen::Vector3d& p : in.positions) points.emplace_back(p[0], p[1], p[2]);
    std::vector<std::array<int, 5>> cells;
    cells.reserve(in.tetCount());
    for (std::size_t t = 0; t < in.tetCount(); ++t) {
      const Tet& q = in.tets[t];
      // CGAL wants positively oriented cells.
      if (signedVolume(in.positions, q) < 0.0)
        cells.push_back({q[0], q[1], q[3], q[2], in.labels[t]});
      else
        cells.push_back({q[0], q[1], q[2], q[3], in.labels[t]});
    }
    std::map<std::array<int, 3>, int> noPatches;
    std::vector<CgalTriangulation::Vertex_handle> handles;
    if (!CGAL::build_triangulation<CgalTriangulation, true>(tr, points, cells, noPatches, handles))
      state.SkipWithError("CGAL could not build the triangulation");
    CGAL::tetrahedral_isotropic_remeshing(tr, c.targetLength, CGAL::parameters::number_of_iterations(unsigned(rounds())));
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
BENCHMARK(BM_PeerOutput)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
