// Manual out-of-core run (not in ctest): a phantom upsampled to hundreds of
// millions of voxels, posed under a memory budget, with the time of each
// stage. Measure its peak memory with /usr/bin/time -v.
//
//   # 1. the source: AF upsampled 4 x 4 x 4 (912 M voxels), streamed to disk
//   build/release/bench/out_of_core_run make-source assets/icrp110_af.nii.gz 4 /big/af_x4.nii.gz
//   # 2. the run: downsample, transfer mesh, bend, stream the rasterization
//   /usr/bin/time -v build/release/bench/out_of_core_run deform /big/af_x4.nii.gz /big/posed.nii.gz 2048 [--cpu]
//
// The transfer mesh stands in for the deformation pipeline's (which runs on
// the downsampled grid): a six-tet mesh of the downsampled grid's foreground,
// 4 downsampled voxels per cube, bent like the rasterization benchmark.

#include "geometry/raster/out_of_core.h"
#include "geometry/io/grid_io.h"
#include "geometry/progress.h"
#include "gpu/context.h"
#include "gpu/raster_engines.h"
#include "tests/support/deformation_fixtures.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

int makeSource(const std::string& input, int factor, const std::string& output) {
  const vox::LabelGrid src = vox::readGrid(input);
  vox::GridGeometry g = src.geometry();
  for (auto& d : g.dims) d *= factor;
  g.spacing = src.spacing() / double(factor);
  g.origin = src.origin() - 0.5 * src.spacing() + 0.5 * g.spacing;
  auto writer = vox::createGridSlices(output, g, src.maxLabel());
  std::vector<vox::Label> slice(std::size_t(g.sliceVoxels()));
  for (std::int64_t k = 0; k < g.dims[2]; ++k) {
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) slice[std::size_t(j * g.dims[0] + i)] = src.at(i / factor, j / factor, k / factor);
    writer->writeSlices(slice.data(), 1);
  }
  writer->commit();
  std::printf("%s: %lld x %lld x %lld = %lld voxels\n", output.c_str(), (long long)g.dims[0], (long long)g.dims[1],
              (long long)g.dims[2], (long long)g.voxelCount());
  return 0;
}

int deform(const std::string& input, const std::string& output, std::int64_t maxMemoryMb, bool cpu) {
  const auto t0 = Clock::now();
  const std::string tempDirectory = std::filesystem::path(output).parent_path().string();
  // The pipeline's grid: at most 16 M voxels.
  vox::OutOfCoreSource source(vox::openGridSlices(input), input, vox::gridSlicesSeekable(input), std::int64_t(1) << 24, tempDirectory);
  const double readSeconds = secondsSince(t0);
  const vox::GridGeometry& g = source.geometry();
  std::printf("source %lld x %lld x %lld = %lld voxels, downsampled by %d to %lld voxels, read in %.1f s\n",
              (long long)g.dims[0], (long long)g.dims[1], (long long)g.dims[2], (long long)g.voxelCount(),
              source.downsampleFactor(), (long long)source.downsampled().voxelCount(), readSeconds);

  const auto t1 = Clock::now();
  const vox::TetMesh tm = vox::test::coveringTransferMesh(source.downsampled(), 4);
  const double height = g.boxMax().z() - g.boxMin().z();
  const auto deformed = vox::test::deformPositions(tm.positions, vox::test::bend(vox::test::gridCentre(g), 1.2 * height));
  std::printf("transfer mesh %zu vertices %zu tets, deformed in %.1f s\n", tm.vertexCount(), tm.tetCount(), secondsSince(t1));

  const auto t2 = Clock::now();
  // The path `voxmorph deform --max-memory` takes.
  const std::unique_ptr<vox::RasterEngines> engines = vox::gpu::makeRasterEngines(cpu, [](const std::string& m) { std::fprintf(stderr, "warning: %s\n", m.c_str()); });
  const auto engine = vox::makeRasterizer(*engines, {.slices = &source.slices()}, tm, deformed, 1, maxMemoryMb << 20);
  vox::writePosedGrid(*engine, *vox::createGridSlices(output, engine->outputGeometry(), source.maxLabel()));
  const vox::GridGeometry out = vox::deformedGridGeometry(g, deformed);
  const double rasterSeconds = secondsSince(t2);
  std::printf("rasterized and wrote %lld x %lld x %lld = %lld voxels (%s) in %.1f s: %.1f M voxels/s; total %.1f s\n",
              (long long)out.dims[0], (long long)out.dims[1], (long long)out.dims[2], (long long)out.voxelCount(),
              cpu ? "cpu" : "gpu", rasterSeconds, double(out.voxelCount()) / rasterSeconds * 1e-6, secondsSince(t0));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "make-source" && argc == 5) return makeSource(argv[2], std::atoi(argv[3]), argv[4]);
    if (mode == "deform" && (argc == 5 || argc == 6))
      return deform(argv[2], argv[3], std::atoll(argv[4]), argc == 6 && std::string(argv[5]) == "--cpu");
    std::fprintf(stderr,
                 "usage: out_of_core_run make-source <grid> <factor> <output>\n"
                 "       out_of_core_run deform <source> <output> <max-memory-MB> [--cpu]\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
