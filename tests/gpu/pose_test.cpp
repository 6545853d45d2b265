// Every pose of assets/poses on its phantom: the GPU rasterization of the
// posed grid equals the CPU reference up to float ties (at most 1e-5 of the
// voxels, each shown to be a tie); the adult male poses keep the whole
// body's volume within 3 % and every organ of 1000 voxels or more within
// 10 % of its mass, and with the label-volume correction every label is
// within a voxel or 1 % of its deformed volume; on the arm pose the
// transfer-mesh vertices outside the cage, placed by the rigidity
// propagation, keep a median edge-length distortion within twice that of the
// inside vertices around them (the mean is not bounded: the upper humerus,
// cut free of the trunk muscle around it up to 50 mm below the shoulder's
// centre of rotation, stretches where the cut ends; the test prints it), and
// every vertex on the cut is among them. Ray casting a pose through
// its transfer mesh shows what ray casting the rasterized posed grid through
// an identity mesh shows, except at silhouette ties, and matches golden
// images.

#include "geometry/deform/report/deformation_report.h"
#include "geometry/deform/solve/label_volumes.h"
#include "gpu/context.h"
#include "geometry/render/camera.h"
#include "geometry/render/cutting_planes.h"
#include "geometry/render/palette.h"
#include "geometry/io/png_io.h"
#include "geometry/render/raycast_reference.h"
#include "geometry/render/raycast_scene.h"
#include "geometry/render/rest_transfer_mesh.h"
#include "gpu/kernels/rasterize.h"
#include "gpu/kernels/raycast.h"
#include "geometry/label_stats.h"
#include "tests/support/pose_fixtures.h"
#include "tests/support/raster_compare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <iostream>

namespace vox {
namespace {

gpu::Context& context() {
  static gpu::Context ctx;
  return ctx;
}

TEST(PoseFiles, AssetsHoldTheAdultMaleAndFemalePoses) {
  const std::vector<std::string> poses = test::poseFiles();
  int am = 0, af = 0;
  for (const std::string& p : poses) (test::phantomOfPose(p) == "icrp110_af" ? af : am) += 1;
  EXPECT_GE(am, 3);
  EXPECT_GE(af, 1);
}

void expectGpuEqualsCpu(const test::PosedPhantom& p) {
  gpu::RasterizeKernel kernel(context(), p.source, p.rest);
  const LabelGrid gpu = kernel.rasterize(p.deformed);
  test::expectEquivalent(p.pose, kernel.plan(), p.cpu, gpu);
}

// The label of 1000 voxels or more whose volume changes most (null when none).
const LabelChange* largestOrganChange(const std::vector<LabelChange>& labels) {
  const LabelChange* worst = nullptr;
  for (const LabelChange& l : labels)
    if (l.before >= kSmallOrganVoxels && (!worst || std::abs(l.volumeChangePercent) > std::abs(worst->volumeChangePercent)))
      worst = &l;
  return worst;
}

void expectVolumesAndMassesKept(const test::PosedPhantom& p) {
  const std::vector<std::uint64_t> before = computeLabelStats(p.source).counts;
  const double voxelVolume = p.source.geometry().voxelVolume();
  {
    const std::vector<LabelChange> labels = labelChanges(before, computeLabelStats(p.cpu).counts, voxelVolume, &p.organs);
    const WholeBodyChange body = wholeBodyChange(labels);
    EXPECT_LE(std::abs(body.volumeChangePercent), 3.0) << p.pose;
    int small = 0;
    for (const LabelChange& l : labels) {
      if (l.before < kSmallOrganVoxels) ++small;
      else EXPECT_LE(std::abs(l.volumeChangePercent), 10.0) << p.pose << ": label " << l.label << " (" << l.name << ")";
    }
    const LabelChange* worst = largestOrganChange(labels);
    std::cout << "[ stats    ] " << p.pose << ": whole body " << body.volumeChangePercent << " % volume, "
              << body.massChangePercent << " % mass; largest organ change " << (worst ? worst->volumeChangePercent : 0.0)
              << " % (" << (worst ? worst->name : "") << "); " << small << " labels under " << kSmallOrganVoxels
              << " voxels exempt\n";
  }
  // With the label-volume correction (--preserve-volumes): every label within
  // a voxel or 1 % of the volume the deformation gives it.
  LabelGrid kept = p.cpu;
  const std::vector<double> volumes = deformedLabelVolumes(p.source, p.rest, p.deformed);
  const LabelVolumeCorrection c = preserveLabelVolumes(kept, p.source, p.rest, p.deformed, volumes);
  const std::vector<std::uint64_t> counts = computeLabelStats(kept).counts;
  for (std::size_t l = 1; l < volumes.size(); ++l) {
    const double n = l < counts.size() ? double(counts[l]) : 0.0;
    EXPECT_LE(std::abs(n - volumes[l]), std::max(1.0, 0.01 * volumes[l])) << p.pose << ": label " << l;
  }
  const std::vector<LabelChange> labels = labelChanges(before, counts, voxelVolume, &p.organs);
  const WholeBodyChange body = wholeBodyChange(labels);
  EXPECT_LE(std::abs(body.volumeChangePercent), 3.0) << p.pose;
  const LabelChange* worst = largestOrganChange(labels);
  std::cout << "[ stats    ] " << p.pose << " with --preserve-volumes: " << c.relabelled << " voxels relabelled; whole body "
            << body.volumeChangePercent << " % volume; largest organ change " << (worst ? worst->volumeChangePercent : 0.0)
            << " %; largest gap to a deformed volume " << c.worstPercentAfter << " % (before " << c.worstPercentBefore << " %)\n";
}

void expectPropagationDistortionBounded(const test::PosedPhantom& p) {
  EXPECT_GT(p.outsideVertices, 0u) << "the arm pose's inset cage leaves transfer-mesh vertices outside";
  const OutlierDistortion d = outlierEdgeDistortion(p.rest, p.deformed, p.inside);
  std::cout << "[ stats    ] " << p.outsideVertices << " TM vertices outside the cage; edge-length distortion |ln(l'/l)|: "
            << "outside edges " << d.outside.edges << " median " << d.outside.median << " mean " << d.outside.mean << " p95 "
            << d.outside.p95 << " max " << d.outside.max << "; inside edges near them " << d.insideNearby.edges << " median "
            << d.insideNearby.median << " mean " << d.insideNearby.mean << " p95 " << d.insideNearby.p95 << "\n";
  ASSERT_GT(d.outside.edges, 0u);
  ASSERT_GT(d.insideNearby.edges, 0u);
  // The typical (median) outside edge stays within twice the typical inside
  // edge around it. The mean and the 95th percentile are larger (the upper
  // humerus where the cut ends, 50 mm below the shoulder's centre of
  // rotation; docs/POSES.md; printed above).
  EXPECT_LE(d.outside.median, 2.0 * d.insideNearby.median);
  // The vertices on the cut (a rest position two TM vertices share) are
  // placed from their own side's tets, never by Green coordinates.
  std::map<std::array<double, 3>, std::vector<std::size_t>> at;
  for (std::size_t v = 0; v < p.rest.vertexCount(); ++v)
    at[{p.rest.positions[v].x(), p.rest.positions[v].y(), p.rest.positions[v].z()}].push_back(v);
  std::size_t onCut = 0, byGreen = 0;
  for (const auto& [position, vertices] : at)
    if (vertices.size() > 1)
      for (const std::size_t v : vertices) {
        ++onCut;
        byGreen += p.inside[v];
      }
  EXPECT_GT(onCut, 0u);
  EXPECT_EQ(byGreen, 0u) << "of " << onCut << " vertices on the cut";
}

// Ray casts the source through the posed TM, and the CPU rasterization of
// the pose through a box-shaped identity TM, with one camera.
void expectRenderEqualsRasterizedRender(const test::PosedPhantom& p) {
  {
    const std::string& pose = p.pose;
    const Palette palette(std::max(p.source.maxLabel(), p.cpu.maxLabel()));
    const RaycastMesh posedMesh = buildRaycastMesh(p.rest, p.source.geometry());
    const RaycastFrame posedFrame = prepareRaycastFrame(posedMesh, p.deformed);
    const TetMesh box = boxTransferMesh(p.cpu);
    const RaycastMesh boxMesh = buildRaycastMesh(box, p.cpu.geometry());
    const RaycastFrame boxFrame = prepareRaycastFrame(boxMesh, box.positions);
    const Eigen::Vector3d lo = posedFrame.toGrid(posedFrame.cellsLo), hi = posedFrame.toGrid(posedFrame.cellsHi);
    // Face normals: the question is which voxel each ray shows (smooth
    // normals of the rest grid mapped through the TM and those of G' differ
    // by the resampling).
    RaycastShading faces;
    faces.normals = SurfaceNormals::Faces;
    for (const char* spec : {"azimuth=0,elevation=0", "azimuth=40,elevation=25"}) {
      const Camera camera = parseCamera(spec, lo, hi, 320, 240);
      gpu::RaycastKernel posedKernel(context(), p.source, posedMesh);
      const RgbImage posed = posedKernel.render(posedFrame, makeRaycastView(posedFrame, camera, {}), palette, faces);
      gpu::RaycastKernel boxKernel(context(), p.cpu, boxMesh);
      const RgbImage rasterized = boxKernel.render(boxFrame, makeRaycastView(boxFrame, camera, {}), palette, faces);
      const ImageDifference d = compareImages(posed, rasterized, 5);
      std::size_t covered = 0;
      for (std::size_t i = 0; i < rasterized.pixels.size(); ++i) covered += !(rasterized.pixels[i] == posed.pixels.front());
      std::cout << "[ stats    ] " << pose << " " << spec << ": " << d.differing << " of " << d.pixels << " pixels ("
                << 100.0 * d.differingFraction() << " %) differ by more than 5/255; " << covered << " pixels show the body\n";
      // Silhouette ties: the posed TM's boundary crosses output voxels that
      // the rasterizer assigns by their centres; a ray may enter such a voxel
      // in one renderer and miss it in the other. Bound: 0.5 % of the image
      // (measured: under 0.1 %).
      EXPECT_LE(d.differingFraction(), 0.005) << pose << " " << spec;
      EXPECT_GT(covered, d.pixels / 20) << pose << " " << spec;
    }
  }
}

// Golden images of a pose, ray cast through its posed TM at 320 x 240 with
// and without a cutting plane: the GPU kernel against the PNGs under
// assets/golden (VOX_UPDATE_GOLDEN=1 rewrites them from the CPU
// reference) and against the CPU reference, each within 0.1 % of the pixels
// off by more than 5/255.
void expectGoldenImages(const test::PosedPhantom& p) {
  const std::string stem = p.pose.substr(0, p.pose.find('.'));
  const Palette palette = Palette::fromOrgans(p.organs, p.source.maxLabel());
  const RaycastMesh mesh = buildRaycastMesh(p.rest, p.source.geometry());
  const RaycastFrame frame = prepareRaycastFrame(mesh, p.deformed);
  const Camera camera = parseCamera("azimuth=20,elevation=10", frame.toGrid(frame.cellsLo), frame.toGrid(frame.cellsHi), 320, 240);
  gpu::RaycastKernel kernel(context(), p.source, mesh);
  for (const std::string cut : {"", "y<135mm"}) {
    CuttingPlanes planes;
    if (!cut.empty()) planes.add(cut);
    const RaycastView view = makeRaycastView(frame, camera, planes);
    const RgbImage gpuImage = kernel.render(frame, view, palette);
    const RgbImage cpuImage = raycastReference(p.source, mesh, frame, view, palette);
    const std::string golden = test::assetPath("golden/raycast_" + stem + (cut.empty() ? "" : "_cut") + ".png");
    if (std::getenv("VOX_UPDATE_GOLDEN")) writePng(golden, cpuImage);
    const ImageDifference g = compareImages(gpuImage, readPng(golden), 5);
    const ImageDifference c = compareImages(gpuImage, cpuImage, 5);
    std::cout << "[ stats    ] " << stem << (cut.empty() ? "" : " cut " + cut) << ": GPU vs golden " << g.differing
              << ", GPU vs CPU " << c.differing << " of " << c.pixels << " pixels differ by more than 5/255\n";
    EXPECT_LE(g.differingFraction(), 0.001) << golden;
    EXPECT_LE(c.differingFraction(), 0.001) << golden;
  }
}

class PoseFile : public testing::TestWithParam<std::string> {};

TEST_P(PoseFile, RunsEndToEnd) {
  const test::PosedPhantom& p = test::posedPhantom(GetParam());
  expectGpuEqualsCpu(p);
  if (p.phantom == "icrp110_am") expectVolumesAndMassesKept(p);
  if (p.pose == "am_right_arm_raised_45.json") expectPropagationDistortionBounded(p);
  if (p.pose == "am_right_arm_raised_45.json" || p.pose == "am_left_knee_bent_30.json") {
    expectRenderEqualsRasterizedRender(p);
    expectGoldenImages(p);
  }
  if (p.pose == "am_right_arm_raised_45_joints.json") expectGoldenImages(p);
}

INSTANTIATE_TEST_SUITE_P(Assets, PoseFile, testing::ValuesIn(test::poseFiles()), [](const testing::TestParamInfo<std::string>& info) {
  std::string name = info.param.substr(0, info.param.find('.'));
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
});

}  // namespace
}  // namespace vox
