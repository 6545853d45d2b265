// GPU rasterization and field interpolation equal their CPU references:
// every voxel where they differ is shown to be a float/double tie (a voxel
// centre within 1e-6 barycentric of a tet face, or a source position within
// float rounding of a source voxel boundary). Chunking (slabs, source
// windows) does not change the GPU output.

#include "geometry/raster/field_interpolation.h"
#include "geometry/raster/out_of_core.h"
#include "geometry/raster/rasterize.h"
#include "geometry/io/grid_io.h"
#include "geometry/synth.h"
#include "geometry/voxel_tetrahedralization.h"
#include "gpu/context.h"
#include "gpu/kernels/field_interpolation.h"
#include "gpu/kernels/rasterize.h"
#include "gpu/raster_engines.h"
#include "tests/support/deformation_fixtures.h"
#include "tests/support/raster_compare.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <map>

namespace vox {
namespace {

using test::compare;
using test::Disagreement;
using test::expectEquivalent;
using test::kFaceTie;

gpu::Context& context() {
  static gpu::Context ctx;
  return ctx;
}

LabelGrid stickFigure(int size) {
  LabelGrid grid = synthesize(SynthKind::StickFigure, size);
  grid.geometry().spacing = {1.5, 1.25, 2.0};
  grid.geometry().origin = {-20.0, 7.0, 3.0};
  return grid;
}

std::map<std::string, test::Deformation> deformations(const GridGeometry& g) {
  const Eigen::Vector3d c = test::gridCentre(g);
  const double height = g.boxMax().z() - g.boxMin().z();
  return {
      {"bend", test::bend(c, 0.8 * height)},
      {"twist", test::twist(c, 60.0 / height)},
      {"rotation", test::rotation(c, {0.2, 0.3, 1.0}, 33.0)},
  };
}

TEST(RasterizeGpu, SynthFigureEqualsCpuReference) {
  const LabelGrid source = stickFigure(72);
  const TetMesh tm = test::coveringTransferMesh(source, 4);
  gpu::RasterizeKernel kernel(context(), source, tm);
  for (const auto& [name, f] : deformations(source.geometry())) {
    const auto deformed = test::deformPositions(tm.positions, f);
    const LabelGrid gpu = kernel.rasterize(deformed);
    const LabelGrid cpu = rasterizeDeformedGrid(source, tm, deformed);
    expectEquivalent("stick figure " + name, kernel.plan(), cpu, gpu);
  }
}

TEST(RasterizeGpu, IcrpPhantomsEqualCpuReference) {
  for (const char* name : {"icrp110_am.nii.gz", "icrp110_af.nii.gz"}) {
    const LabelGrid source = readGrid(test::assetPath(name));
    const TetMesh tm = test::coveringTransferMesh(source, 4);
    gpu::RasterizeKernel kernel(context(), source, tm);
    for (const auto& [pose, f] : deformations(source.geometry())) {
      const auto deformed = test::deformPositions(tm.positions, f);
      const LabelGrid gpu = kernel.rasterize(deformed);
      const LabelGrid cpu = rasterizeDeformedGrid(source, tm, deformed);
      expectEquivalent(std::string(name) + " " + pose, kernel.plan(), cpu, gpu);
    }
  }
}

TEST(RasterizeGpu, FloatTiesAreTheOnlyDifferences) {
  // Overlapping tets decided by the lowest index, with a face of the lower
  // cube 1e-9 voxel beyond a row of voxel centres: double excludes them from
  // it, float rounds the face onto them. A conforming mesh maps both sides of
  // a face to the same source point, so this needs an overlap to show.
  GridGeometry g;
  g.dims = {12, 4, 4};
  LabelGrid source(g);
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) source.labels()[std::size_t(v)] = Label(1 + g.ijk(v)[0] / 4);
  GridGeometry cube;
  cube.dims = {4, 4, 4};
  cube.origin = {8, 0, 0};
  const TetMesh a = tetrahedralizeVoxels(LabelGrid(cube, 3));  // rest x in [7.5, 11.5], lower indices
  cube.origin = {0, 0, 0};
  const TetMesh b = tetrahedralizeVoxels(LabelGrid(cube, 1));  // rest x in [-0.5, 3.5]
  TetMesh tm = a;
  for (const Tet& t : b.tets) tm.tets.push_back({t[0] + std::int32_t(a.vertexCount()), t[1] + std::int32_t(a.vertexCount()),
                                                 t[2] + std::int32_t(a.vertexCount()), t[3] + std::int32_t(a.vertexCount())});
  tm.positions.insert(tm.positions.end(), b.positions.begin(), b.positions.end());
  tm.labels.assign(tm.tets.size(), 1);
  auto deformed = tm.positions;
  for (std::size_t i = 0; i < a.vertexCount(); ++i) deformed[i].x() -= 5.5 - 1e-9;  // cube a now spans x in [2 + 1e-9, 6 + 1e-9]
  gpu::RasterizeKernel kernel(context(), source, tm);
  const LabelGrid gpu = kernel.rasterize(deformed);
  const LabelGrid cpu = rasterizeDeformedGrid(source, tm, deformed);
  const Disagreement d = compare(kernel.plan(), cpu, gpu);
  // The 4 x 4 centres at x = 2: label 1 through cube b (double), 2 through
  // cube a (float). At x = 6, 1e-9 inside cube a's far face, the source
  // position 11.5 - 1e-9 rounds to voxel 11 in double and off the grid in float.
  EXPECT_EQ(d.voxels, 32);
  EXPECT_EQ(d.faceTies, 32);
  EXPECT_LT(d.maxFaceMargin, 1e-9);
  EXPECT_EQ(d.unexplained, 0);
}

TEST(RasterizeGpu, SupersamplingEqualsCpuReference) {
  const LabelGrid source = stickFigure(48);
  const TetMesh tm = test::coveringTransferMesh(source, 3);
  const auto deformed = test::deformPositions(tm.positions, deformations(source.geometry()).at("bend"));
  for (int samples : {2, 3}) {
    gpu::RasterizeKernel kernel(context(), source, tm, {.samples = samples});
    const LabelGrid gpu = kernel.rasterize(deformed);
    const LabelGrid cpu = rasterizeDeformedGrid(source, tm, deformed, {.samples = samples});
    expectEquivalent("samples " + std::to_string(samples), kernel.plan(), cpu, gpu);
  }
}

// Foreground voxels of `source` whose label differs in `out` (a grid on the
// source lattice, shifted by an integer offset).
std::int64_t foregroundMismatches(const LabelGrid& source, const LabelGrid& out) {
  const Eigen::Vector3d offset = source.geometry().continuousIndex(out.geometry().origin);
  EXPECT_TRUE(offset.isApprox(offset.array().round().matrix(), 1e-9));
  std::int64_t mismatched = 0;
  for (std::int64_t k = 0; k < source.dims()[2]; ++k)
    for (std::int64_t j = 0; j < source.dims()[1]; ++j)
      for (std::int64_t i = 0; i < source.dims()[0]; ++i)
        if (source.at(i, j, k) != 0)
          mismatched += out.atOr(i - std::lround(offset.x()), j - std::lround(offset.y()), k - std::lround(offset.z())) != source.at(i, j, k);
  return mismatched;
}

TEST(RasterizeGpu, IdentityReproducesSourceExactly) {
  // Every voxel centre lies on six tets' shared diagonal: the hardest tie
  // case, and GPU and CPU must agree exactly (the planes are exact here).
  const LabelGrid source = stickFigure(40);
  const TetMesh tm = test::coveringTransferMesh(source, 1);
  gpu::RasterizeKernel kernel(context(), source, tm);
  const LabelGrid gpu = kernel.rasterize(tm.positions);
  EXPECT_EQ(gpu.labels(), rasterizeDeformedGrid(source, tm, tm.positions).labels());
  EXPECT_EQ(foregroundMismatches(source, gpu), 0);
}

TEST(RasterizeGpu, IdentityReproducesTheAmPhantom) {
  const LabelGrid source = readGrid(test::assetPath("icrp110_am.nii.gz"));
  const TetMesh tm = test::coveringTransferMesh(source, 4);
  gpu::RasterizeKernel kernel(context(), source, tm);
  const LabelGrid gpu = kernel.rasterize(tm.positions);
  EXPECT_EQ(foregroundMismatches(source, gpu), 0);
  std::int64_t foreground = 0;
  for (Label l : gpu.labels()) foreground += l != 0;
  std::int64_t sourceForeground = 0;
  for (Label l : source.labels()) sourceForeground += l != 0;
  EXPECT_EQ(foreground, sourceForeground);
}

TEST(RasterizeGpu, SlabsAndWindowsDoNotChangeTheOutput) {
  const LabelGrid source = stickFigure(48);
  const TetMesh tm = test::coveringTransferMesh(source, 3);
  for (int samples : {1, 2}) {
    const auto deformed = test::deformPositions(tm.positions, deformations(source.geometry()).at("twist"));
    gpu::RasterizeKernel whole(context(), source, tm, {.samples = samples});
    const LabelGrid expected = whole.rasterize(deformed);
    // Slabs of a few output slices, windows of 3 source slices (several per
    // slab), read through the streaming interface.
    LabelGridSlices reader(source);
    const std::uint64_t slice = std::uint64_t(source.geometry().sliceVoxels());
    gpu::RasterizeKernel chunked(context(), reader, tm,
                                 {.samples = samples, .maxSlabSamples = 3000, .maxWindowVoxels = 3 * slice});
    const LabelGrid got = chunked.rasterize(deformed);
    EXPECT_LT(chunked.slabSlices(), got.dims()[2] / 4);
    EXPECT_EQ(got.labels(), expected.labels()) << "samples " << samples;
  }
}

TEST(RasterizeGpu, OutOfCoreEqualsInCore) {
  const std::string dir = test::tempDir();
  const LabelGrid grid = stickFigure(64);
  writeGrid(dir + "/source.nii.gz", grid);
  const std::string sourcePath = dir + "/source.nii.gz";
  OutOfCoreSource source(openGridSlices(sourcePath), sourcePath, gridSlicesSeekable(sourcePath), grid.voxelCount() / 27, dir);
  const TetMesh tm = tetrahedralizeVoxels(source.downsampled(), {.includeBackground = false});
  const auto deformed = test::deformPositions(tm.positions, deformations(grid.geometry()).at("bend"));
  // Device memory staged as on a discrete GPU, through a staging buffer of
  // three source slices: the windows go in chunks of whole slices.
  static gpu::Context staged({.stageDeviceMemory = true, .stagingBytes = std::uint64_t(3 * grid.geometry().sliceVoxels()) * sizeof(Label)});
  for (int samples : {1, 2}) {
    gpu::RasterizeKernel kernel(context(), grid, tm, {.samples = samples});
    const LabelGrid inCore = kernel.rasterize(deformed);
    for (gpu::Context* ctx : {&context(), &staged}) {
      // 64 KiB: several slabs, several windows per slab; the path `deform
      // --max-memory` takes.
      gpu::GpuRasterEngines engines(*ctx);
      const auto engine = makeRasterizer(engines, {.slices = &source.slices()}, tm, deformed, samples, 64 << 10);
      writePosedGrid(*engine, *createGridSlices(dir + "/posed.nii.gz", engine->outputGeometry(), source.maxLabel()));
      const LabelGrid got = readGrid(dir + "/posed.nii.gz");
      ASSERT_EQ(got.dims(), inCore.dims());
      EXPECT_EQ(got.labels(), inCore.labels()) << "samples " << samples << (ctx == &staged ? ", staged" : "");
    }
  }
}

TEST(FieldInterpolationGpu, EqualsCpuReference) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 40);
  TetMesh mesh = test::coveringTransferMesh(grid, 3);
  mesh.positions = test::deformPositions(mesh.positions, test::twist(test::gridCentre(grid.geometry()), 2.0));
  std::vector<double> values;
  for (const auto& p : mesh.positions) values.push_back(std::sin(0.2 * p.x()) + 0.01 * p.y() * p.z());
  GridGeometry target = grid.geometry();
  target.spacing = {0.7, 0.8, 0.9};
  target.dims = {70, 60, 55};
  target.origin = grid.geometry().origin - Eigen::Vector3d(3, 2, 1);
  const float fill = -7.0f;
  const ScalarGrid cpu = interpolateVertexField(mesh, values, target, {.fill = fill});
  for (std::uint64_t slab : {0ull, 5000ull}) {
    gpu::FieldInterpolationKernel kernel(context(), {.maxSlabPoints = slab});
    const ScalarGrid gpu = kernel.run(mesh, values, target, fill);
    ASSERT_EQ(gpu.values.size(), cpu.values.size());
    const std::vector<LatticeTet> tets = latticeTets(target, mesh.positions, mesh.tets);
    std::int64_t inside = 0, coverage = 0;
    double maxError = 0.0;
    for (std::int64_t v = 0; v < target.voxelCount(); ++v) {
      const float a = cpu.values[std::size_t(v)], b = gpu.values[std::size_t(v)];
      if ((a == fill) != (b == fill)) {
        // Inside for one, outside for the other: must be on the mesh boundary.
        const Index3 q = target.ijk(v);
        double margin = 1e300;
        for (const LatticeTet& t : tets)
          if (!t.empty() && q[0] >= t.lo[0] && q[0] <= t.hi[0] && q[1] >= t.lo[1] && q[1] <= t.hi[1] && q[2] >= t.lo[2] && q[2] <= t.hi[2])
            margin = std::min(margin, std::abs(t.barycentric(std::int32_t(q[0]), std::int32_t(q[1]), std::int32_t(q[2])).minCoeff()));
        EXPECT_LE(margin, kFaceTie) << v;
        ++coverage;
        continue;
      }
      if (a == fill) continue;
      ++inside;
      maxError = std::max(maxError, double(std::abs(a - b)));
    }
    std::cout << "[ stats    ] field slab " << slab << ": " << inside << " inside, " << coverage
              << " coverage ties, max |gpu - cpu| " << maxError << "\n";
    EXPECT_GT(inside, target.voxelCount() / 20);
    EXPECT_LT(maxError, 1e-5);
  }
}

}  // namespace
}  // namespace vox
