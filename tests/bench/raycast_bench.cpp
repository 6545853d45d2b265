// Frame time of the transfer-mesh-guided ray caster at 640x480 (and other
// sizes) on the AM and AF phantoms and on AF upsampled to 171 M voxels, at
// rest and in two poses, with and without a cutting plane; and, in the same
// run, what the renderer avoids: rasterizing the deformed grid after every
// pose change and uploading it again.
//
// A frame is what a pose change costs. Raycast/... is `voxmorph render`'s
// frame: prepareRaycastFrame (render-frame positions, and the host's BVH
// refit, which the CPU reference reads and the kernel does not), then the
// GPU passes and the image read back to the host (what `render` and a
// screenshot need). RaycastToImage/... is the
// viewer's frame: placeRaycastFrame and the deformed positions written
// straight into the kernel's mapped buffer, the BVH refitted on the GPU,
// the image left in a GPU image (gpu::RaycastKernel::renderTo), which
// returns once the frame is submitted: the next frame waits for it after
// writing its positions, so a frame's time is the larger of the host's and
// the GPU's. Counters:
// cpu_ms is the process's CPU time per frame (all lavapipe threads), which
// on a loaded machine says more than wall time; frame_prep_cpu_ms the part
// in prepareRaycastFrame or placeRaycastFrame; gpu_ms the kernels'
// timestamps (RaycastToImage: those of the frame before, finished while
// the host prepared the next). Google Benchmark's CPU column is the calling thread's time
// alone: the host's share of the frame.
//
// The transfer mesh is the pipeline's (buildTransferMesh: CGAL Mesh_3 of the
// foreground, default sizing field, built once per phantom on the original
// grid and used for the upsampled grid too: it lives in millimetres), or the
// Medit file named by VOXMORPH_BENCH_TM_AM / VOXMORPH_BENCH_TM_AF; with
// VOXMORPH_BENCH_TM=coarse, a coarse voxel TM (the six-tet decomposition of
// the grid downsampled by kTmFactor), whose air layer around the body makes
// every ray longer.
//
// VOXMORPH_BENCH_SHADING=faces lights each voxel face with its own normal
// instead of the smooth normals (RaycastShading's default).
//
//   build/release/bench/raycast_bench [--benchmark_filter=...]
//   VOXMORPH_BENCH_SIZE=1920x1080 build/release/bench/raycast_bench

#include "geometry/skeleton/label_groups.h"
#include "geometry/deform/transfer_mesh.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/mesh_io.h"
#include "geometry/organ_table.h"
#include "geometry/render/camera.h"
#include "geometry/render/raycast_scene.h"
#include "geometry/render/rest_transfer_mesh.h"
#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/image.h"
#include "gpu/kernels/rasterize.h"
#include "gpu/kernels/raycast.h"
#include "tests/geometry/render/fixtures.h"

#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>

namespace {

using namespace vox;

constexpr int kTmFactor = 6;

gpu::Context& context() {
  static gpu::Context ctx;
  return ctx;
}

double cpuMs() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) * 1e3 + double(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-3;
}

// Nearest-neighbour upsampling that keeps the grid's box: voxel (i,j,k)
// becomes f0 x f1 x f2 voxels.
LabelGrid upsample(const LabelGrid& g, Index3 f) {
  GridGeometry u = g.geometry();
  for (int a = 0; a < 3; ++a) {
    u.dims[a] *= f[a];
    u.spacing[a] /= double(f[a]);
    u.origin[a] += g.spacing()[a] * (-0.5 + 0.5 / double(f[a]));
  }
  LabelGrid out(u);
  for (std::int64_t k = 0; k < u.dims[2]; ++k)
    for (std::int64_t j = 0; j < u.dims[1]; ++j) {
      const Label* src = g.data() + g.geometry().index(0, j / f[1], k / f[2]);
      Label* dst = out.data() + u.index(0, j, k);
      for (std::int64_t i = 0; i < u.dims[0]; ++i) dst[i] = src[i / f[0]];
    }
  return out;
}

struct Scene {
  LabelGrid grid;
  TetMesh rest;
  GridGeometry restGrid;  // the grid the TM and poses were made for
  RaycastMesh mesh;
  Palette palette;
  std::unique_ptr<gpu::RaycastKernel> kernel;
  double setupMs = 0.0;  // grid and mesh to the GPU, once
};

Scene& scene(const std::string& name) {
  // The context first, so that it outlives the scenes' kernels at exit.
  context();
  static std::map<std::string, std::unique_ptr<Scene>> cache;
  auto& s = cache[name];
  if (s) return *s;
  s = std::make_unique<Scene>();
  const std::string phantom = name.rfind("am", 0) == 0 ? "am" : "af";
  const LabelGrid original = readGrid(std::string(VOX_ASSETS_DIR) + "/icrp110_" + phantom + ".nii.gz");
  const std::string envName = "VOXMORPH_BENCH_TM_" + std::string(phantom == "am" ? "AM" : "AF");
  const char* tmFile = std::getenv(envName.c_str());
  const char* tmKind = std::getenv("VOXMORPH_BENCH_TM");
  const bool coarse = tmKind && std::string(tmKind) == "coarse";
  const std::string tmName = tmFile ? tmFile : coarse ? "coarse voxel TM" : "buildTransferMesh";
  static std::map<std::string, TetMesh> meshes;  // one TM per phantom, shared by its upsampled grid
  if (!meshes.count(phantom)) {
    if (tmFile) meshes[phantom] = readTetMesh(tmFile);
    else if (coarse) meshes[phantom] = coarseVoxelTransferMesh(original, kTmFactor);
    else meshes[phantom] = buildTransferMesh(binaryGroupGrid(original), defaultSizingField(original.geometry()));
  }
  s->rest = meshes[phantom];
  s->restGrid = original.geometry();
  s->grid = name.find("upsampled") != std::string::npos ? upsample(original, {2, 2, 3}) : original;
  const OrganTable organs = OrganTable::read(std::string(VOX_ASSETS_DIR) + "/icrp110_" + phantom + "_organs.dat");
  s->palette = Palette::fromOrgans(organs, s->grid.maxLabel());
  s->mesh = buildRaycastMesh(s->rest, s->grid.geometry());
  const auto w0 = std::chrono::steady_clock::now();
  s->kernel = std::make_unique<gpu::RaycastKernel>(context(), s->grid, s->mesh);
  s->setupMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - w0).count();
  std::fprintf(stderr, "%s: %lld voxels, TM %zu tets (%s), %zu label slabs, setup %.0f ms\n", name.c_str(),
               (long long)s->grid.voxelCount(), s->mesh.tets.size(), tmName.c_str(), s->kernel->slabCount(), s->setupMs);
  return *s;
}

void imageSize(int& w, int& h) {
  w = 640;
  h = 480;
  if (const char* size = std::getenv("VOXMORPH_BENCH_SIZE")) parseImageSize(size, w, h);
}

RaycastShading benchShading() {
  RaycastShading shading;
  if (const char* normals = std::getenv("VOXMORPH_BENCH_SHADING")) shading.normals = parseSurfaceNormals(normals, "VOXMORPH_BENCH_SHADING");
  return shading;
}

void BM_RaycastFrame(benchmark::State& state, std::string name, test::Deformation pose, std::string cut, bool readBack) {
  Scene& s = scene(name);
  int w = 0, h = 0;
  imageSize(w, h);
  const RaycastShading shading = benchShading();
  const std::vector<Eigen::Vector3d> posed = test::deform(s.rest.positions, s.restGrid, pose);
  CuttingPlanes cuts;
  if (!cut.empty()) cuts.add(cut);
  // The camera frames the rest pose and stays put while the pose changes.
  const RaycastFrame restFrame = prepareRaycastFrame(s.mesh, s.rest.positions);
  const Camera camera =
      parseCamera("azimuth=20,elevation=10", restFrame.toGrid(restFrame.cellsLo), restFrame.toGrid(restFrame.cellsHi), w, h);
  s.kernel->render(restFrame, makeRaycastView(restFrame, camera, cuts), s.palette, shading);  // pipelines compiled
  gpu::Image2D target;
  if (!readBack) target = gpu::Image2D(context(), std::uint32_t(w), std::uint32_t(h));
  double cpu = 0.0, gpu = 0.0, frameCpu = 0.0;
  RgbImage image;
  for (auto _ : state) {
    const double c0 = cpuMs();
    const RaycastFrame frame = readBack ? prepareRaycastFrame(s.mesh, posed) : placeRaycastFrame(s.mesh, posed);
    frameCpu += cpuMs() - c0;
    if (readBack) image = s.kernel->render(frame, makeRaycastView(frame, camera, cuts), s.palette, shading);
    else s.kernel->renderTo(target, frame, posed, makeRaycastView(frame, camera, cuts), s.palette, shading);
    cpu += cpuMs() - c0;
    const gpu::RaycastFrameTimes& t = s.kernel->lastTimes();
    gpu += t.prepareGpuMs + t.entriesGpuMs + t.raycastGpuMs;
    benchmark::DoNotOptimize(image.pixels.data());
  }
  s.kernel->wait();
  if (!readBack) image = target.download();  // after the timed frames, for the pixel count
  const std::size_t visible = countNotBackground(image, RaycastShading{}.background);
  const double n = double(state.iterations());
  state.counters["cpu_ms"] = cpu / n;
  state.counters["frame_prep_cpu_ms"] = frameCpu / n;
  state.counters["gpu_ms"] = gpu / n;
  state.counters["fps"] = benchmark::Counter(1.0, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["voxels_M"] = double(s.grid.voxelCount()) * 1e-6;
  state.counters["tets"] = double(s.mesh.tets.size());
  state.counters["visible_px"] = double(visible);
  state.SetLabel(std::to_string(w) + "x" + std::to_string(h) + " " + context().info().name);
}

// What the ray caster avoids: after each pose change, rasterize the deformed
// grid G' on the GPU (gpu::RasterizeKernel; its source grid stays on the
// GPU), read it back, and upload it into label slabs of one storage binding
// each, as the ray caster's setup uploads its grid once. Counters split the
// time into the rasterization and the upload.
void BM_RerasterizeAndUpload(benchmark::State& state, std::string name, test::Deformation pose) {
  Scene& s = scene(name);
  const std::vector<Eigen::Vector3d> posed = test::deform(s.rest.positions, s.restGrid, pose);
  gpu::RasterizeKernel rasterizer(context(), s.grid, s.rest);
  rasterizer.rasterize(posed);  // source upload and pipelines, once
  double cpu = 0.0, rasterMs = 0.0, uploadMs = 0.0;
  std::int64_t voxels = 0;
  for (auto _ : state) {
    const double c0 = cpuMs();
    const auto w0 = std::chrono::steady_clock::now();
    const LabelGrid deformed = rasterizer.rasterize(posed);
    const auto w1 = std::chrono::steady_clock::now();
    const std::uint64_t bytes = std::uint64_t(deformed.voxelCount()) * sizeof(Label);
    const std::uint64_t slab = context().maxBindingBytes();
    std::vector<gpu::Buffer> slabs;
    for (std::uint64_t off = 0; off < bytes; off += slab) {
      slabs.emplace_back(context(), std::min(slab, bytes - off), gpu::MemoryIntent::Device);
      slabs.back().upload(reinterpret_cast<const char*>(deformed.data()) + off, slabs.back().size());
    }
    const auto w2 = std::chrono::steady_clock::now();
    cpu += cpuMs() - c0;
    rasterMs += std::chrono::duration<double, std::milli>(w1 - w0).count();
    uploadMs += std::chrono::duration<double, std::milli>(w2 - w1).count();
    voxels = deformed.voxelCount();
  }
  const double n = double(state.iterations());
  state.counters["cpu_ms"] = cpu / n;
  state.counters["rasterize_ms"] = rasterMs / n;
  state.counters["upload_ms"] = uploadMs / n;
  state.counters["output_voxels_M"] = double(voxels) * 1e-6;
  state.SetLabel(context().info().name);
}

}  // namespace

int main(int argc, char** argv) {
  for (const char* name : {"am", "af", "af_upsampled_171M"}) {
    for (test::Deformation pose : {test::Deformation::Rest, test::Deformation::Twist, test::Deformation::Bend})
      for (const char* cut : {"", "y<135mm"})
        for (bool readBack : {true, false}) {
          const std::string label = std::string(readBack ? "Raycast/" : "RaycastToImage/") + name + "/" + test::deformationName(pose) +
                                    (*cut ? "/cut" : "");
          benchmark::RegisterBenchmark(label.c_str(), BM_RaycastFrame, std::string(name), pose, std::string(cut), readBack)
              ->Unit(benchmark::kMillisecond)
              ->Iterations(5)
              ->UseRealTime();
        }
    for (test::Deformation pose : {test::Deformation::Twist, test::Deformation::Bend})
      benchmark::RegisterBenchmark((std::string("RerasterizeAndUpload/") + name + "/" + test::deformationName(pose)).c_str(),
                                   BM_RerasterizeAndUpload, std::string(name), pose)
          ->Unit(benchmark::kMillisecond)
          ->Iterations(2)
          ->UseRealTime();
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
