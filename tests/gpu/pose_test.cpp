// Every pose of assets/poses on its phantom: the GPU rasterization of the
// posed grid equals the CPU reference up to float ties (at most 1e-5 of the
// voxels, each shown to be a tie); the adult male poses keep the whole
// body's volume within 3 % and every organ of 1000 voxels or more within
// 10 % of its mass; on the arm pose the transfer-mesh vertices outside the
// cage, placed by the rigidity propagation, stay within twice the median
// edge-length distortion of the vertices inside the cage around them. (The
// mean is not bounded: a few tets where the hand touches the thigh stretch
// with the arm; the test prints it.)

#include "geometry/deform/deformation_report.h"
#include "gpu/context.h"
#include "gpu/kernels/rasterize.h"
#include "tests/support/pose_fixtures.h"
#include "tests/support/raster_compare.h"

#include <gtest/gtest.h>

#include <cmath>
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

TEST(PoseFiles, GpuRasterizationEqualsTheCpuReferenceOnEveryPose) {
  for (const std::string& pose : test::poseFiles()) {
    const test::PosedPhantom& p = test::posedPhantom(pose);
    gpu::RasterizeKernel kernel(context(), p.source, p.rest);
    const LabelGrid gpu = kernel.rasterize(p.deformed);
    test::expectEquivalent(pose, kernel.plan(), p.cpu, gpu);
  }
}

TEST(PoseFiles, AdultMalePosesKeepVolumeAndOrganMasses) {
  for (const std::string& pose : test::poseFiles()) {
    if (test::phantomOfPose(pose) != "icrp110_am") continue;
    const test::PosedPhantom& p = test::posedPhantom(pose);
    const std::vector<LabelChange> labels =
        labelChanges(test::labelCounts(p.source), test::labelCounts(p.cpu), p.source.geometry().voxelVolume(), &p.organs);
    const WholeBodyChange body = wholeBodyChange(labels);
    EXPECT_LE(std::abs(body.volumeChangePercent), 3.0) << pose;
    double worst = 0.0;
    std::string worstName;
    int small = 0;
    for (const LabelChange& l : labels) {
      if (l.before < kSmallOrganVoxels) {
        ++small;
        continue;
      }
      EXPECT_LE(std::abs(l.volumeChangePercent), 10.0) << pose << ": label " << l.label << " (" << l.name << ")";
      if (std::abs(l.volumeChangePercent) > std::abs(worst)) {
        worst = l.volumeChangePercent;
        worstName = l.name;
      }
    }
    std::cout << "[ stats    ] " << pose << ": whole body " << body.volumeChangePercent << " % volume, "
              << body.massChangePercent << " % mass; largest organ change " << worst << " % (" << worstName << "); "
              << small << " labels under " << kSmallOrganVoxels << " voxels exempt\n";
  }
}

TEST(PoseFiles, ArmPosePropagationStaysWithinTwiceTheInsideDistortion) {
  const test::PosedPhantom& p = test::posedPhantom("am_right_arm_raised_45.json");
  EXPECT_GT(p.outsideVertices, 0u) << "the arm pose's inset cage leaves transfer-mesh vertices outside";
  const OutlierDistortion d = outlierEdgeDistortion(p.rest, p.deformed, p.inside);
  std::cout << "[ stats    ] " << p.outsideVertices << " TM vertices outside the cage; edge-length distortion |ln(l'/l)|: "
            << "outside edges " << d.outside.edges << " median " << d.outside.median << " mean " << d.outside.mean << " p95 "
            << d.outside.p95 << " max " << d.outside.max << "; inside edges near them " << d.insideNearby.edges << " median "
            << d.insideNearby.median << " mean " << d.insideNearby.mean << " p95 " << d.insideNearby.p95 << "\n";
  ASSERT_GT(d.outside.edges, 0u);
  ASSERT_GT(d.insideNearby.edges, 0u);
  EXPECT_LE(d.outside.median, 2.0 * d.insideNearby.median);
}

}  // namespace
}  // namespace vox
