// Rasterization of the deformed grid: GPU kernel vs CPU reference vs a plain
// memcpy of the output's bytes (the bandwidth peer), on the AF phantom
// upsampled to over 120 M voxels posed by its pose file through the
// deformation pipeline, and (posed by a smooth bend) on the AF phantom
// upsampled 2 x 2 x 2.2 and a synthetic figure of the same size. Also the
// field interpolation kernel.
// Every GPU output is compared with the CPU reference once: the run aborts
// when more than 1e-5 of the voxels differ.
//
//   build/release/bench/rasterize_bench [--benchmark_filter=...]
//   VOXMORPH_BENCH_TM_CUBE=8 (voxels per transfer-mesh cube edge, default 12)

#include "geometry/raster/field_interpolation.h"
#include "geometry/deform/pipeline.h"
#include "geometry/raster/rasterize.h"
#include "geometry/io/grid_io.h"
#include "geometry/synth.h"
#include "gpu/context.h"
#include "gpu/kernels/field_interpolation.h"
#include "gpu/kernels/rasterize.h"
#include "tests/support/deformation_fixtures.h"

#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

using vox::LabelGrid;

vox::gpu::Context& context() {
  static vox::gpu::Context ctx;
  return ctx;
}

// Nearest-neighbour upsampling by per-axis factors; voxel corners of the
// result tile the source's box.
LabelGrid upsample(const LabelGrid& src, const Eigen::Vector3d& factor) {
  vox::GridGeometry g = src.geometry();
  for (int a = 0; a < 3; ++a) g.dims[std::size_t(a)] = std::int64_t(std::floor(double(src.dims()[std::size_t(a)]) * factor[a]));
  g.spacing = src.spacing().cwiseQuotient(factor);
  g.origin = src.origin() - 0.5 * src.spacing() + 0.5 * g.spacing;
  LabelGrid out(g);
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i)
        out.at(i, j, k) = src.at(std::int64_t(double(i) / factor[0]), std::int64_t(double(j) / factor[1]),
                                 std::int64_t(double(k) / factor[2]));
  return out;
}

int cubeVoxels() {
  const char* v = std::getenv("VOXMORPH_BENCH_TM_CUBE");
  return v ? std::max(2, std::atoi(v)) : 12;
}

struct Case {
  LabelGrid source;
  vox::TetMesh tm;
  std::vector<Eigen::Vector3d> deformed;
};

const Case& benchCase(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Case>> cache;
  auto& c = cache[name];
  if (!c) {
    c = std::make_unique<Case>();
    if (name == "af_pose_x2x2x3") {
      // The AF pose of assets/poses through the deformation pipeline (on the
      // phantom itself, as `voxmorph deform` runs it on a working grid), and
      // the posed TM rasterized from the phantom upsampled 2 x 2 x 3 (171 M
      // voxels; same box, so the TM's mm coordinates hold).
      const LabelGrid af = vox::readGrid(std::string(VOX_ASSETS_DIR) + "/icrp110_af.nii.gz");
      const std::string pose = std::string(VOX_ASSETS_DIR) + "/poses/af_head_turned_20.json";
      vox::PipelineOptions options = vox::poseOptions(vox::readPose(pose), pose, std::nullopt);
      options.envelope = false;
      vox::DeformationPipeline pipeline(af, options);
      pipeline.deform();
      c->tm = pipeline.transferMesh();
      c->deformed = pipeline.deformedTransferMesh();
      c->source = upsample(af, {2.0, 2.0, 3.0});
      const vox::GridGeometry& g = c->source.geometry();
      std::fprintf(stderr, "%s: %lld x %lld x %lld voxels, pipeline transfer mesh %zu vertices %zu tets\n", name.c_str(),
                   (long long)g.dims[0], (long long)g.dims[1], (long long)g.dims[2], c->tm.vertexCount(), c->tm.tetCount());
      return *c;
    }
    if (name == "af_x2x2x2.2") {
      c->source = upsample(vox::readGrid(std::string(VOX_ASSETS_DIR) + "/icrp110_af.nii.gz"), {2.0, 2.0, 2.2});
    } else {
      c->source = vox::synthesize(vox::SynthKind::StickFigure, 880);
    }
    c->tm = vox::test::coveringTransferMesh(c->source, cubeVoxels());
    const vox::GridGeometry& g = c->source.geometry();
    const double height = g.boxMax().z() - g.boxMin().z();
    c->deformed = vox::test::deformPositions(c->tm.positions, vox::test::bend(vox::test::gridCentre(g), 1.2 * height));
    std::fprintf(stderr, "%s: %lld x %lld x %lld voxels, transfer mesh %zu vertices %zu tets (cube %d)\n", name.c_str(),
                 (long long)g.dims[0], (long long)g.dims[1], (long long)g.dims[2], c->tm.vertexCount(), c->tm.tetCount(),
                 cubeVoxels());
  }
  return *c;
}

void setCounters(benchmark::State& state, const LabelGrid& out) {
  state.counters["output_voxels"] = double(out.voxelCount());
  state.counters["voxels_per_s"] = benchmark::Counter(double(out.voxelCount()), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["bytes_per_s"] =
      benchmark::Counter(double(out.voxelCount()) * sizeof(vox::Label), benchmark::Counter::kIsIterationInvariantRate);
}

void checkAgainstCpu(const std::string& key, const Case& c, const LabelGrid& gpu, int samples) {
  static std::map<std::string, bool> checked;
  if (checked[key]) return;
  checked[key] = true;
  const LabelGrid cpu = vox::rasterizeDeformedGrid(c.source, c.tm, c.deformed, {.samples = samples});
  std::int64_t differ = 0;
  for (std::size_t v = 0; v < cpu.labels().size(); ++v) differ += cpu.labels()[v] != gpu.labels()[v];
  std::fprintf(stderr, "%s: %lld of %lld voxels differ from the CPU reference\n", key.c_str(), (long long)differ,
               (long long)cpu.voxelCount());
  if (cpu.dims() != gpu.dims() || double(differ) > 1e-5 * double(cpu.voxelCount())) std::abort();
}

void BM_RasterizeGpu(benchmark::State& state, std::string name, int samples) {
  const Case& c = benchCase(name);
  vox::gpu::RasterizeKernel kernel(context(), c.source, c.tm, {.samples = samples});
  LabelGrid out;
  const double cpu0 = vox::processCpuSeconds();
  for (auto _ : state) {
    out = kernel.rasterize(c.deformed);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["process_cpu_s"] = (vox::processCpuSeconds() - cpu0) / double(state.iterations());
  checkAgainstCpu(name + "/k" + std::to_string(samples), c, out, samples);
  state.counters["gpu_ms"] = kernel.gpuMs();
  state.counters["locate_ms"] = kernel.locateMs();
  state.counters["resolve_ms"] = kernel.resolveMs();
  setCounters(state, out);
  state.SetLabel(context().info().name);
}

void BM_RasterizeCpu(benchmark::State& state, std::string name, int samples) {
  const Case& c = benchCase(name);
  LabelGrid out;
  const double cpu0 = vox::processCpuSeconds();
  for (auto _ : state) {
    out = vox::rasterizeDeformedGrid(c.source, c.tm, c.deformed, {.samples = samples});
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["process_cpu_s"] = (vox::processCpuSeconds() - cpu0) / double(state.iterations());
  setCounters(state, out);
}

void BM_Memcpy(benchmark::State& state, std::string name) {
  const Case& c = benchCase(name);
  const vox::GridGeometry g = vox::deformedGridGeometry(c.source.geometry(), c.deformed);
  std::vector<vox::Label> from(std::size_t(g.voxelCount()), 1), to(from.size());
  for (auto _ : state) {
    std::memcpy(to.data(), from.data(), to.size() * sizeof(vox::Label));
    benchmark::ClobberMemory();
  }
  LabelGrid shape(g);
  setCounters(state, shape);
}

// Error-field style interpolation: per-vertex values of the deformed TM onto
// the source grid's geometry.
void BM_FieldInterpolation(benchmark::State& state, std::string name, bool gpu) {
  const Case& c = benchCase(name);
  vox::TetMesh mesh = c.tm;
  std::vector<double> values;
  for (const auto& p : mesh.positions) values.push_back(std::sin(0.01 * p.x()) + 0.001 * p.z());
  vox::gpu::FieldInterpolationKernel kernel(context());
  vox::ScalarGrid field;
  for (auto _ : state) {
    field = gpu ? kernel.run(mesh, values, c.source.geometry()) : vox::interpolateVertexField(mesh, values, c.source.geometry());
    benchmark::DoNotOptimize(field.values.data());
  }
  state.counters["voxels_per_s"] =
      benchmark::Counter(double(field.values.size()), benchmark::Counter::kIsIterationInvariantRate);
}

// Writing the posed grid (.nii.gz, streamed gzip): with the rasterization,
// the post-process this benchmark's case stands for.
void BM_WriteNiftiGz(benchmark::State& state, std::string name) {
  const Case& c = benchCase(name);
  vox::gpu::RasterizeKernel kernel(context(), c.source, c.tm);
  const LabelGrid out = kernel.rasterize(c.deformed);
  const std::string path = (std::filesystem::temp_directory_path() / ("rasterize_bench_" + name + ".nii.gz")).string();
  for (auto _ : state) vox::writeGrid(path, out);
  std::filesystem::remove(path);
  setCounters(state, out);
}

// Effect of supersampling on per-label volume change (AM phantom, bend):
// counters over the labels of at least 1000 voxels.
void BM_SupersamplingVolumeChange(benchmark::State& state, int samples) {
  static const LabelGrid source = vox::readGrid(std::string(VOX_ASSETS_DIR) + "/icrp110_am.nii.gz");
  static const vox::TetMesh tm = vox::test::coveringTransferMesh(source, 4);
  const vox::GridGeometry& g = source.geometry();
  const auto deformed =
      vox::test::deformPositions(tm.positions, vox::test::bend(vox::test::gridCentre(g), 1.2 * (g.boxMax().z() - g.boxMin().z())));
  vox::gpu::RasterizeKernel kernel(context(), source, tm, {.samples = samples});
  LabelGrid out;
  for (auto _ : state) out = kernel.rasterize(deformed);
  std::vector<double> before(65536, 0.0), after(65536, 0.0);
  for (vox::Label l : source.labels()) before[l] += 1.0;
  for (vox::Label l : out.labels()) after[l] += 1.0;
  double sumAbs = 0.0, maxAbs = 0.0, body0 = 0.0, body1 = 0.0;
  int labels = 0, over5 = 0;
  for (std::size_t l = 1; l < before.size(); ++l) {
    body0 += before[l];
    body1 += after[l];
    if (before[l] < 1000.0) continue;
    const double change = 100.0 * std::abs(after[l] - before[l]) / before[l];
    sumAbs += change;
    maxAbs = std::max(maxAbs, change);
    ++labels;
    over5 += change > 5.0;
  }
  state.counters["labels"] = labels;
  state.counters["mean_abs_change_pct"] = sumAbs / labels;
  state.counters["max_abs_change_pct"] = maxAbs;
  state.counters["labels_over_5pct"] = over5;
  state.counters["body_change_pct"] = 100.0 * (body1 - body0) / body0;
}

}  // namespace

int main(int argc, char** argv) {
  for (int samples : {1, 2, 3})
    benchmark::RegisterBenchmark(("SupersamplingVolumeChange/am_bend/k" + std::to_string(samples)).c_str(),
                                 BM_SupersamplingVolumeChange, samples)
        ->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();
  {
    const std::string n("af_pose_x2x2x3");
    benchmark::RegisterBenchmark(("Rasterize/gpu/" + n).c_str(), BM_RasterizeGpu, n, 1)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();
    benchmark::RegisterBenchmark(("Rasterize/cpu/" + n).c_str(), BM_RasterizeCpu, n, 1)->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();
    benchmark::RegisterBenchmark(("Rasterize/memcpy/" + n).c_str(), BM_Memcpy, n)->Unit(benchmark::kMillisecond)->Iterations(5)->UseRealTime();
    benchmark::RegisterBenchmark(("Write/nii.gz/" + n).c_str(), BM_WriteNiftiGz, n)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();
  }
  for (const char* name : {"af_x2x2x2.2", "stick_figure_880"}) {
    const std::string n(name);
    benchmark::RegisterBenchmark(("Rasterize/gpu/" + n).c_str(), BM_RasterizeGpu, n, 1)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();
    benchmark::RegisterBenchmark(("Rasterize/cpu/" + n).c_str(), BM_RasterizeCpu, n, 1)->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();
    benchmark::RegisterBenchmark(("Rasterize/memcpy/" + n).c_str(), BM_Memcpy, n)->Unit(benchmark::kMillisecond)->Iterations(5)->UseRealTime();
    benchmark::RegisterBenchmark(("Write/nii.gz/" + n).c_str(), BM_WriteNiftiGz, n)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();
    benchmark::RegisterBenchmark(("Rasterize/gpu_k3/" + n).c_str(), BM_RasterizeGpu, n, 3)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();
    benchmark::RegisterBenchmark(("FieldInterpolation/gpu/" + n).c_str(), BM_FieldInterpolation, n, true)->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();
    benchmark::RegisterBenchmark(("FieldInterpolation/cpu/" + n).c_str(), BM_FieldInterpolation, n, false)->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
