// The injective soft-tissue solve (geometry/deform/solve/injective_solve.h)
// on a limb of transfer-mesh size: 60 x 18 x 18 voxels in six tets each
// (22,021 vertices, 116,640 tets), a bone (the 5 x 5 vertices around the
// centre line) in each end's 22 voxels, the rest soft tissue; the lower bone
// turns about a hinge at mid-length, perpendicular to the limb.
//  - Frame: the interactive mode (prefactorized rest system), `iterations`
//    per frame (argument), the bone turning 1.5 degrees per frame between 0
//    and 90 degrees and back, warm-started from the previous frame. The
//    factorization (once per constraint set) is timed apart.
//  - SlimIteration: one SLIM iteration (local step, assembly, CHOLMOD
//    factorization of the 3 #free system, solve, line search), the bone
//    turned 5 degrees from rest.
//  - Solve: the full SLIM solve from rest to `degrees` (first argument) in
//    `steps` steps (second).
// Counters: milliseconds per frame (mean and fastest), iterations, the
// smallest det J over every step, inverted tets (0 by construction).

#include "geometry/deform/solve/injective_solve.h"
#include "geometry/voxel_tetrahedralization.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

namespace vox {
namespace {

struct Limb {
  TetMesh mesh;
  std::vector<std::int32_t> constrained;
  std::vector<std::int32_t> motionOf;  // 0 the fixed bone, 1 the turned one
  Eigen::Vector3d hinge;

  Limb() {
    constexpr int nx = 60, ny = 18, nz = 18, bone = 22;
    constexpr double boneHalfWidth = 2.0;
    GridGeometry g;
    g.dims = {nx, ny, nz};
    mesh = tetrahedralizeVoxels(LabelGrid(g, 1), {.includeBackground = false});
    hinge = Eigen::Vector3d(0.5 * (nx - 1), 0.5 * (ny - 1), 0.5 * (nz - 1));
    for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
      const Eigen::Vector3d& p = mesh.positions[v];
      if (std::abs(p.y() - hinge.y()) > boneHalfWidth + 1e-9 || std::abs(p.z() - hinge.z()) > boneHalfWidth + 1e-9) continue;
      const double x = p.x() + 0.5;
      if (x <= bone + 1e-9 || x >= nx - bone - 1e-9) {
        constrained.push_back(std::int32_t(v));
        motionOf.push_back(x <= bone + 1e-9 ? 0 : 1);
      }
    }
  }

  Eigen::Isometry3d turn(double degrees) const {
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.translate(hinge);
    m.rotate(Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()));
    m.translate(-hinge);
    return m;
  }
  std::vector<Eigen::Vector3d> targets(double degrees) const {
    const Eigen::Isometry3d m = turn(degrees);
    std::vector<Eigen::Vector3d> out(constrained.size());
    for (std::size_t k = 0; k < constrained.size(); ++k) {
      const Eigen::Vector3d& p = mesh.positions[std::size_t(constrained[k])];
      out[k] = motionOf[k] ? Eigen::Vector3d(m * p) : p;
    }
    return out;
  }
};

const Limb& limb() {
  static const Limb instance;
  return instance;
}

double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void BM_InjectiveFrame(benchmark::State& state) {
  const Limb& l = limb();
  InjectiveSolveOptions options;
  options.frameIterations = int(state.range(0));
  InjectiveSolver solver;
  auto start = std::chrono::steady_clock::now();
  solver.precompute(l.mesh.positions, l.mesh.tets, l.constrained, {}, {}, options);
  const double precomputeMs = millisecondsSince(start);
  start = std::chrono::steady_clock::now();
  solver.frame(l.targets(0.0));  // the first frame factorizes the rest system
  const double factorMs = millisecondsSince(start);
  double degrees = 0.0, step = 1.5, total = 0.0, fastest = 1e300, least = 1.0;
  std::int64_t frames = 0, reached = 0;
  for (auto _ : state) {
    if (degrees + step > 90.0 || degrees + step < 0.0) step = -step;
    degrees += step;
    const auto targets = l.targets(degrees);
    start = std::chrono::steady_clock::now();
    const InjectiveStepReport report = solver.frame(targets);
    const double ms = millisecondsSince(start);
    total += ms;
    fastest = std::min(fastest, ms);
    least = std::min(least, report.minRelativeVolume);
    reached += report.reachedTargets ? 1 : 0;
    ++frames;
  }
  std::size_t inverted = 0;
  for (const double v : solver.relativeVolumes(solver.positions())) inverted += v > 0.0 ? 0 : 1;
  state.counters["frame_ms"] = total / double(frames);
  state.counters["frame_min_ms"] = fastest;
  state.counters["precompute_ms"] = precomputeMs;
  state.counters["first_frame_with_factor_ms"] = factorMs;
  state.counters["frames_at_targets"] = double(reached) / double(frames);
  state.counters["min_det_J"] = least;
  state.counters["inverted"] = double(inverted);
  state.counters["vertices"] = double(l.mesh.vertexCount());
  state.counters["tets"] = double(l.mesh.tetCount());
}
BENCHMARK(BM_InjectiveFrame)->Arg(1)->Arg(2)->Iterations(120)->Unit(benchmark::kMillisecond);

void BM_InjectiveSlimIteration(benchmark::State& state) {
  const Limb& l = limb();
  InjectiveSolveOptions options;
  options.maxIterations = 1;
  InjectiveSolver solver;
  solver.precompute(l.mesh.positions, l.mesh.tets, l.constrained, {}, {}, options);
  const auto targets = l.targets(5.0);
  for (auto _ : state) {
    state.PauseTiming();
    solver.resetToRest();
    state.ResumeTiming();
    benchmark::DoNotOptimize(solver.solveStep(targets));
  }
}
BENCHMARK(BM_InjectiveSlimIteration)->Iterations(3)->Unit(benchmark::kMillisecond);

void BM_InjectiveSolve(benchmark::State& state) {
  const Limb& l = limb();
  const double degrees = double(state.range(0));
  InjectiveSolveOptions options;
  options.steps = int(state.range(1));
  const std::vector<Eigen::Isometry3d> motions{Eigen::Isometry3d::Identity(), l.turn(degrees)};
  InjectiveSolveResult result;
  for (auto _ : state)
    result = solveInjective(l.mesh.positions, l.mesh.tets, l.constrained,
                            rigidStepTargets(l.mesh.positions, l.constrained, l.motionOf, motions), options);
  state.counters["iterations"] = result.iterations;
  state.counters["min_det_J"] = result.minRelativeVolume;
  state.counters["inverted"] = double(result.invertedTets);
  state.counters["converged"] = result.converged ? 1 : 0;
  int reached = 0, convergedSteps = 0;
  for (const InjectiveStepReport& step : result.steps) {
    reached += step.reachedTargets ? 1 : 0;
    convergedSteps += step.converged ? 1 : 0;
  }
  state.counters["steps_at_targets"] = reached;
  state.counters["steps_converged"] = convergedSteps;
  state.counters["energy"] = result.energy;
}
BENCHMARK(BM_InjectiveSolve)->Args({90, 8})->Args({120, 8})->Args({120, 16})->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace vox

BENCHMARK_MAIN();
