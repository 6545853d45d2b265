// Per-label counts and boxes: GPU kernel vs CPU reference vs a plain memcpy of
// the same bytes (the bandwidth peer), on the ICRP phantoms and a synthetic
// grid of over 300 M voxels. Every GPU result is checked against the CPU's:
// the run aborts on a mismatch.
//
//   build/release/bench/label_stats_bench [--benchmark_filter=...]

#include "geometry/io/grid_io.h"
#include "geometry/label_stats.h"
#include "geometry/synth.h"
#include "gpu/context.h"
#include "gpu/kernels/label_stats.h"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

vox::gpu::Context& context() {
  static vox::gpu::Context ctx;
  return ctx;
}

const vox::LabelGrid& grid(const std::string& name) {
  static std::map<std::string, std::unique_ptr<vox::LabelGrid>> cache;
  auto& g = cache[name];
  if (!g) {
    if (name == "synthetic_311M") g = std::make_unique<vox::LabelGrid>(vox::synthesize(vox::SynthKind::StickFigure, 1200));
    else g = std::make_unique<vox::LabelGrid>(vox::readGrid(std::string(VOX_ASSETS_DIR) + "/" + name));
  }
  return *g;
}

void checkEqual(const std::string& name, const vox::LabelStats& gpu) {
  static std::map<std::string, bool> checked;
  if (checked[name]) return;
  const vox::LabelStats cpu = vox::computeLabelStats(grid(name));
  if (!(cpu == gpu)) {
    std::fprintf(stderr, "%s: GPU label statistics differ from the CPU reference\n", name.c_str());
    std::abort();
  }
  checked[name] = true;
}

void setCounters(benchmark::State& state, const vox::LabelGrid& g) {
  state.counters["voxels"] = double(g.voxelCount());
  state.counters["voxels_per_s"] = benchmark::Counter(double(g.voxelCount()), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["bytes_per_s"] =
      benchmark::Counter(double(g.voxelCount()) * sizeof(vox::Label), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_LabelStatsGpu(benchmark::State& state, std::string name) {
  const vox::LabelGrid& g = grid(name);
  vox::gpu::LabelStatsKernel kernel(context());
  vox::LabelStats stats;
  for (auto _ : state) {
    stats = kernel.run(g);
    benchmark::DoNotOptimize(stats.counts.data());
  }
  checkEqual(name, stats);
  state.counters["kernel_ms"] = kernel.lastGpuMs();
  setCounters(state, g);
  state.SetLabel(context().info().name);
}

void BM_LabelStatsCpu(benchmark::State& state, std::string name) {
  const vox::LabelGrid& g = grid(name);
  for (auto _ : state) {
    vox::LabelStats stats = vox::computeLabelStats(g);
    benchmark::DoNotOptimize(stats.counts.data());
  }
  setCounters(state, g);
}

void BM_Memcpy(benchmark::State& state, std::string name) {
  const vox::LabelGrid& g = grid(name);
  std::vector<vox::Label> copy(g.labels().size());
  for (auto _ : state) {
    std::memcpy(copy.data(), g.data(), copy.size() * sizeof(vox::Label));
    benchmark::ClobberMemory();
  }
  setCounters(state, g);
}

}  // namespace

int main(int argc, char** argv) {
  for (const char* name : {"icrp110_am.nii.gz", "icrp110_af.nii.gz", "synthetic_311M"}) {
    const int iters = std::strcmp(name, "synthetic_311M") == 0 ? 2 : 10;
    benchmark::RegisterBenchmark((std::string("LabelStats/gpu/") + name).c_str(), BM_LabelStatsGpu, std::string(name))
        ->Unit(benchmark::kMillisecond)->Iterations(iters)->UseRealTime();
    benchmark::RegisterBenchmark((std::string("LabelStats/cpu/") + name).c_str(), BM_LabelStatsCpu, std::string(name))
        ->Unit(benchmark::kMillisecond)->Iterations(iters)->UseRealTime();
    benchmark::RegisterBenchmark((std::string("LabelStats/memcpy/") + name).c_str(), BM_Memcpy, std::string(name))
        ->Unit(benchmark::kMillisecond)->Iterations(iters)->UseRealTime();
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
