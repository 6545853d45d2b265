// GPU transfer-mesh-guided ray caster against its CPU reference and the
// golden images: at most 0.1% of the pixels may differ by more than 5/255.

#include "geometry/skeleton/label_groups.h"
#include "geometry/deform/transfer_mesh.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/png_io.h"
#include "geometry/organ_table.h"
#include "geometry/render/raycast_reference.h"
#include "geometry/render/raycast_scene.h"
#include "geometry/render/rest_transfer_mesh.h"
#include "geometry/synth.h"
#include "gpu/context.h"
#include "gpu/image.h"
#include "gpu/kernels/raycast.h"
#include "tests/geometry/render/fixtures.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

namespace vox {
namespace {

constexpr int kThreshold = 5;
constexpr double kFraction = 0.001;

gpu::Context& context() {
  static gpu::Context ctx;
  return ctx;
}

const LabelGrid& amPhantom() {
  static const LabelGrid grid = readGrid(test::assetPath("icrp110_am.nii.gz"));
  return grid;
}

LabelGrid stickFigure() {
  LabelGrid g = synthesize(SynthKind::StickFigure, 64);
  g.geometry().spacing = {1.5, 1.5, 4.0};
  return g;
}

struct Frame {
  RaycastFrame frame;
  RaycastView view;
};

Frame makeFrame(const RaycastMesh& mesh, const std::vector<Eigen::Vector3d>& positions, const std::string& camera, const std::string& cut,
                int w, int h) {
  Frame f;
  f.frame = prepareRaycastFrame(mesh, positions);
  CuttingPlanes cuts;
  if (!cut.empty()) cuts.add(cut);
  f.view = makeRaycastView(f.frame, parseCamera(camera, f.frame.toGrid(f.frame.cellsLo), f.frame.toGrid(f.frame.cellsHi), w, h), cuts);
  return f;
}

TEST(RaycastGpu, SyntheticPosesCutsAndHiddenLabelsEqualTheCpuReference) {
  // Through a coarse voxel TM and through the pipeline's transfer mesh, with
  // smooth and face normals.
  const LabelGrid grid = stickFigure();
  const Palette palette(grid.maxLabel());
  for (const TetMesh& rest : {coarseVoxelTransferMesh(grid, 3),
                              buildTransferMesh(binaryGroupGrid(grid), defaultSizingField(grid.geometry()))}) {
    const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
    gpu::RaycastKernel kernel(context(), grid, mesh);
    for (test::Deformation d : {test::Deformation::Rest, test::Deformation::Twist, test::Deformation::Bend})
      for (const char* cut : {"", "y<14", "plane=1,0.2,-0.5,-50"})
        for (const char* hide : {"", "1"})
          for (SurfaceNormals normals : {SurfaceNormals::Smooth, SurfaceNormals::Faces}) {
            Palette p = palette;
            if (*hide) p.hide(hide);
            RaycastShading shading;
            shading.normals = normals;
            const Frame f = makeFrame(mesh, test::deform(rest.positions, grid.geometry(), d), "azimuth=-30,elevation=15", cut, 160, 120);
            const RgbImage gpuImage = kernel.render(f.frame, f.view, p, shading);
            const RgbImage cpuImage = raycastReference(grid, mesh, f.frame, f.view, p, shading);
            const ImageDifference diff = compareImages(gpuImage, cpuImage, kThreshold);
            EXPECT_LE(diff.differingFraction(), kFraction) << rest.tetCount() << " tets, " << test::deformationName(d) << " cut '"
                                                           << cut << "' hide '" << hide << "' " << surfaceNormalsName(normals) << ": "
                                                           << diff.differing << " pixels differ";
            EXPECT_GT(countNotBackground(cpuImage, RaycastShading{}.background), 300u);
          }
  }
}

TEST(RaycastGpu, FacesCoveringTheWholeImageEqualTheCpuReference) {
  // The identity TM's six tets seen from close by: a face covers nearly every
  // pixel, more than one invocation of the entry pass may test on lavapipe.
  const LabelGrid grid = stickFigure();
  const TetMesh box = boxTransferMesh(grid);
  const RaycastMesh mesh = buildRaycastMesh(box, grid.geometry());
  gpu::RaycastKernel kernel(context(), grid, mesh);
  Palette palette(grid.maxLabel());
  palette.hide("1");
  for (const char* camera : {"azimuth=10,elevation=5,distance=0.3", "azimuth=100,distance=0.25,fov=60"}) {
    const Frame f = makeFrame(mesh, box.positions, camera, "", 640, 480);
    const RgbImage cpuImage = raycastReference(grid, mesh, f.frame, f.view, palette);
    const ImageDifference diff = compareImages(kernel.render(f.frame, f.view, palette), cpuImage, kThreshold);
    EXPECT_LE(diff.differingFraction(), kFraction) << camera << ": " << diff.differing << " pixels differ";
    EXPECT_GT(countNotBackground(cpuImage, RaycastShading{}.background), 5000u) << camera;
  }
}

TEST(RaycastGpu, RenderingIntoAGpuImageGivesTheReadBackImage) {
  // The viewer's path (renderTo a 2D image, blitted to the screen) and the
  // PNG path (render, read back) give the same pixels.
  const LabelGrid grid = stickFigure();
  const TetMesh rest = coarseVoxelTransferMesh(grid, 3);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  gpu::RaycastKernel kernel(context(), grid, mesh);
  const Palette palette(grid.maxLabel());
  const Frame f = makeFrame(mesh, test::deform(rest.positions, grid.geometry(), test::Deformation::Bend), "azimuth=40,elevation=10",
                            "y<14", 200, 150);
  const RgbImage readBack = kernel.render(f.frame, f.view, palette);
  gpu::Image2D target(context(), 200, 150);
  kernel.renderTo(target, f.frame, f.view, palette);
  const RgbImage onGpu = target.download();
  EXPECT_EQ(compareImages(readBack, onGpu, 0).differing, 0u);
  EXPECT_GT(countNotBackground(onGpu, RaycastShading{}.background), 300u);
  gpu::Image2D wrongSize(context(), 100, 150);
  EXPECT_THROW(kernel.renderTo(wrongSize, f.frame, f.view, palette), RuntimeFailure);
}

TEST(RaycastGpu, DeformedPositionsRenderTheFramesImage) {
  // The viewer's frame: placeRaycastFrame and the grid-frame positions, which
  // the kernel converts and whose BVH it refits, against the frame that
  // prepareRaycastFrame converted and refitted on the host.
  const LabelGrid grid = stickFigure();
  const TetMesh rest = buildTransferMesh(binaryGroupGrid(grid), defaultSizingField(grid.geometry()));
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  gpu::RaycastKernel kernel(context(), grid, mesh);
  const Palette palette(grid.maxLabel());
  for (test::Deformation d : {test::Deformation::Twist, test::Deformation::Rest, test::Deformation::Bend}) {
    const std::vector<Eigen::Vector3d> posed = test::deform(rest.positions, grid.geometry(), d);
    const Frame f = makeFrame(mesh, posed, "azimuth=40,elevation=10", "y<14", 200, 150);
    const RaycastFrame placed = placeRaycastFrame(mesh, posed);
    EXPECT_TRUE(placed.positions.empty() && placed.bvh.empty());
    EXPECT_EQ(placed.output.dims, f.frame.output.dims);
    EXPECT_EQ(placed.renderOrigin, f.frame.renderOrigin);
    EXPECT_EQ(placed.cellsLo, f.frame.cellsLo);
    EXPECT_EQ(placed.cellsHi, f.frame.cellsHi);
    gpu::Image2D a(context(), 200, 150), b(context(), 200, 150);
    kernel.renderTo(a, f.frame, f.view, palette);
    kernel.renderTo(b, placed, posed, f.view, palette);
    const RgbImage fromFrame = a.download();
    EXPECT_EQ(compareImages(fromFrame, b.download(), 0).differing, 0u) << test::deformationName(d);
    EXPECT_GT(countNotBackground(fromFrame, RaycastShading{}.background), 300u);
  }
  gpu::Image2D target(context(), 200, 150);
  const Frame f = makeFrame(mesh, rest.positions, "azimuth=40", "", 200, 150);
  EXPECT_THROW(kernel.renderTo(target, f.frame, std::vector<Eigen::Vector3d>(3), f.view, palette), RuntimeFailure);
  EXPECT_THROW(placeRaycastFrame(mesh, std::vector<Eigen::Vector3d>(3)), InputError);
}

TEST(RaycastGpu, FramesSubmittedBackToBackKeepTheirPoses) {
  // renderTo returns before the GPU is done: frame N+1 writes its positions
  // (into the other mapped buffer) and records its passes while frame N may
  // still run. Each image equals the waited-for rendering of its pose.
  const LabelGrid grid = stickFigure();
  const TetMesh rest = coarseVoxelTransferMesh(grid, 3);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  gpu::RaycastKernel kernel(context(), grid, mesh);
  const Palette palette(grid.maxLabel());
  const test::Deformation poses[] = {test::Deformation::Twist, test::Deformation::Rest, test::Deformation::Bend, test::Deformation::Rotate,
                                     test::Deformation::Twist};
  std::vector<gpu::Image2D> targets;
  std::vector<Frame> frames;
  for (test::Deformation d : poses) {
    const std::vector<Eigen::Vector3d> posed = test::deform(rest.positions, grid.geometry(), d);
    frames.push_back(makeFrame(mesh, posed, "azimuth=30,elevation=10", "", 128, 96));
    targets.emplace_back(context(), 128, 96);
    kernel.renderTo(targets.back(), placeRaycastFrame(mesh, posed), posed, frames.back().view, palette);
  }
  kernel.wait();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const RgbImage waited = kernel.render(frames[i].frame, frames[i].view, palette);
    EXPECT_EQ(compareImages(targets[i].download(), waited, 0).differing, 0u) << "frame " << i << ", " << test::deformationName(poses[i]);
    EXPECT_GT(countNotBackground(waited, RaycastShading{}.background), 300u);
  }
}

TEST(RaycastGpu, BvhRefitOnTheGpuHoldsTheCpuRefit) {
  // After each posed frame the GPU's boxes contain the host's refitted boxes
  // (refitBoundaryBvh in double) and exceed them by no more than the padding
  // the host gives its float boxes: the CPU refit is the GPU refit's
  // reference. On the stick figure (Mesh_3 TM) and on a crop of the AM
  // phantom (coarse voxel TM).
  const LabelGrid& am = amPhantom();
  GridGeometry crop = am.geometry();
  crop.dims = {am.dims()[0], am.dims()[1], 60};
  LabelGrid amCrop(crop);
  std::copy(am.data(), am.data() + crop.voxelCount(), amCrop.data());
  const LabelGrid stick = stickFigure();
  struct Case {
    const LabelGrid* grid;
    TetMesh rest;
  };
  const Case cases[] = {{&stick, buildTransferMesh(binaryGroupGrid(stick), defaultSizingField(stick.geometry()))},
                        {&amCrop, coarseVoxelTransferMesh(amCrop, 6)}};
  for (const Case& c : cases) {
    const RaycastMesh mesh = buildRaycastMesh(c.rest, c.grid->geometry());
    gpu::RaycastKernel kernel(context(), *c.grid, mesh);
    const Palette palette(c.grid->maxLabel());
    gpu::Image2D target(context(), 64, 48);  // outlives the frames that write it
    for (test::Deformation d : {test::Deformation::Twist, test::Deformation::Bend, test::Deformation::Rotate}) {
      const std::vector<Eigen::Vector3d> posed = test::deform(c.rest.positions, c.grid->geometry(), d);
      const Frame f = makeFrame(mesh, posed, "azimuth=20", "", 64, 48);
      kernel.renderTo(target, placeRaycastFrame(mesh, posed), posed, f.view, palette);
      const std::vector<BvhNode> gpuBvh = kernel.downloadBvh();
      ASSERT_EQ(gpuBvh.size(), f.frame.bvh.size());
      std::size_t outside = 0, loose = 0, topology = 0;
      for (std::size_t n = 0; n < gpuBvh.size(); ++n) {
        const BvhNode& g = gpuBvh[n];
        const BvhNode& h = f.frame.bvh[n];
        if (g.rightOrFirst != h.rightOrFirst || g.count != h.count) ++topology;
        const double pad = 1e-3 + 2.0 * kFaceHitTolerance * (h.hi - h.lo).maxCoeff();
        for (int a = 0; a < 3; ++a) {
          const double slack = pad + 1e-5 * (1.0 + std::abs(h.lo[a]) + std::abs(h.hi[a]));
          if (g.lo[a] > h.lo[a] || g.hi[a] < h.hi[a]) ++outside;
          if (g.lo[a] < h.lo[a] - slack || g.hi[a] > h.hi[a] + slack) ++loose;
        }
      }
      EXPECT_EQ(topology, 0u) << test::deformationName(d);
      EXPECT_EQ(outside, 0u) << test::deformationName(d) << ": GPU boxes that miss part of the host's";
      EXPECT_EQ(loose, 0u) << test::deformationName(d) << ": GPU boxes looser than the host's float boxes";
    }
  }
}

TEST(RaycastGpu, ManySlabsGiveTheSameImage) {
  // Slabs of 5 slices: the stick figure's 64 slices need 13 slabs, more than
  // the kernel binds; slabs of 8 slices need exactly 8.
  const LabelGrid grid = stickFigure();
  const std::uint64_t sliceBytes = std::uint64_t(grid.geometry().sliceVoxels()) * sizeof(Label);
  const TetMesh rest = coarseVoxelTransferMesh(grid, 3);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  EXPECT_THROW(gpu::RaycastKernel(context(), grid, mesh, {5 * sliceBytes}), RuntimeFailure);
  gpu::RaycastKernel one(context(), grid, mesh);
  gpu::RaycastKernel eight(context(), grid, mesh, {8 * sliceBytes + 7});
  EXPECT_EQ(one.slabCount(), 1u);
  EXPECT_EQ(eight.slabCount(), 8u);
  EXPECT_EQ(eight.gridUploadBytes(), std::uint64_t(grid.voxelCount()) * sizeof(Label));
  const Palette palette(grid.maxLabel());
  const Frame f = makeFrame(mesh, test::deform(rest.positions, grid.geometry(), test::Deformation::Twist), "azimuth=60,elevation=-20",
                            "x>30", 128, 96);
  const RgbImage a = one.render(f.frame, f.view, palette);
  EXPECT_EQ(compareImages(a, eight.render(f.frame, f.view, palette), 0).differing, 0u);
  EXPECT_GT(countNotBackground(a, RaycastShading{}.background), 300u);
}

TEST(RaycastGpu, RayDispatchOverSeveralRowsGivesTheSameImage) {
  // The entry pass lists the tiles and sizes the ray pass's dispatch on the
  // GPU: with 7 work groups per row the flagged tiles span many rows, the
  // last one partly filled.
  const LabelGrid grid = stickFigure();
  const TetMesh rest = coarseVoxelTransferMesh(grid, 3);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  gpu::RaycastKernel wide(context(), grid, mesh);
  gpu::RaycastKernel narrow(context(), grid, mesh, {0, 7});
  const Palette palette(grid.maxLabel());
  for (test::Deformation d : {test::Deformation::Twist, test::Deformation::Rest}) {
    const Frame f = makeFrame(mesh, test::deform(rest.positions, grid.geometry(), d), "azimuth=30,elevation=20", "", 160, 120);
    const RgbImage a = wide.render(f.frame, f.view, palette);
    EXPECT_EQ(compareImages(a, narrow.render(f.frame, f.view, palette), 0).differing, 0u) << test::deformationName(d);
    EXPECT_GT(countNotBackground(a, RaycastShading{}.background), 300u);
  }
}

TEST(RaycastGpu, OnlyPositionsChangeBetweenFrames) {
  // One kernel renders a sequence of poses (the grid and the mesh stay on the
  // GPU); each frame equals a fresh kernel's rendering of that pose.
  const LabelGrid grid = stickFigure();
  const TetMesh rest = coarseVoxelTransferMesh(grid, 4);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  const Palette palette(grid.maxLabel());
  gpu::RaycastKernel kernel(context(), grid, mesh);
  for (test::Deformation d : {test::Deformation::Bend, test::Deformation::Rest, test::Deformation::Rotate, test::Deformation::Bend}) {
    const Frame f = makeFrame(mesh, test::deform(rest.positions, grid.geometry(), d), "azimuth=15", "", 96, 72);
    gpu::RaycastKernel fresh(context(), grid, mesh);
    EXPECT_EQ(compareImages(kernel.render(f.frame, f.view, palette), fresh.render(f.frame, f.view, palette), 0).differing, 0u)
        << test::deformationName(d);
  }
  EXPECT_GT(kernel.lastTimes().totalMs, 0.0);
}

TEST(RaycastGpu, RejectsFramesAndGridsOfAnotherMesh) {
  const LabelGrid grid = stickFigure();
  const TetMesh a = coarseVoxelTransferMesh(grid, 3), b = coarseVoxelTransferMesh(grid, 4);
  const RaycastMesh meshA = buildRaycastMesh(a, grid.geometry()), meshB = buildRaycastMesh(b, grid.geometry());
  gpu::RaycastKernel kernel(context(), grid, meshA);
  const Frame f = makeFrame(meshB, b.positions, "", "", 32, 24);
  EXPECT_THROW(kernel.render(f.frame, f.view, Palette(grid.maxLabel())), RuntimeFailure);
  LabelGrid shifted = grid;
  shifted.geometry().origin[0] += 1.0;
  EXPECT_THROW(gpu::RaycastKernel(context(), shifted, meshA), RuntimeFailure);
}

TEST(RaycastGpu, GoldenImagesAndCpuReferenceOnTheAmPhantom) {
  const LabelGrid& grid = amPhantom();
  const Palette palette = Palette::fromOrgans(OrganTable::read(test::assetPath("icrp110_am_organs.dat")), grid.maxLabel());
  const TetMesh rest = coarseVoxelTransferMesh(grid, test::kGoldenTmFactor);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  gpu::RaycastKernel kernel(context(), grid, mesh);
  for (const test::GoldenScene& s : test::goldenScenes()) {
    const Frame f = makeFrame(mesh, test::deform(rest.positions, grid.geometry(), s.deformation), s.camera, s.cut, test::kGoldenWidth,
                              test::kGoldenHeight);
    const RgbImage gpuImage = kernel.render(f.frame, f.view, palette);
    const ImageDifference golden = compareImages(gpuImage, readPng(test::assetPath("golden/raycast_" + s.name + ".png")), kThreshold);
    EXPECT_LE(golden.differingFraction(), kFraction) << s.name << ": " << golden.differing << " pixels differ from the golden image";
    const ImageDifference cpu = compareImages(gpuImage, raycastReference(grid, mesh, f.frame, f.view, palette), kThreshold);
    EXPECT_LE(cpu.differingFraction(), kFraction) << s.name << ": " << cpu.differing << " pixels differ from the CPU reference";
    std::printf("%s: GPU vs golden %zu, GPU vs CPU %zu pixels of %zu differ by more than %d/255\n", s.name.c_str(), golden.differing,
                cpu.differing, cpu.pixels, kThreshold);
  }
}

}  // namespace
}  // namespace vox
