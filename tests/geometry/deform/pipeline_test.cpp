// The deformation pipeline on the adult male phantom: an identity pose
// reproduces the input grid voxel for voxel; a rigid pose (the whole cage
// rotated 30 degrees) moves every transfer-mesh vertex rigidly within 1e-6 of
// the grid diagonal and keeps the voxel counts: with nearest-neighbour
// resampling every label of 10,000 voxels or more within 1 %, of 1,000 or more
// within 2 %, the foreground within 0.1 %; with the label-volume correction
// (label_volumes.h) every label within 1 %.

#include "geometry/deform/solve/label_volumes.h"
#include "geometry/deform/pipeline.h"
#include "geometry/raster/rasterize.h"
#include "geometry/io/grid_io.h"
#include "geometry/label_stats.h"
#include "tests/support/pose_fixtures.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>

namespace vox {
namespace {

const LabelGrid& adultMale() {
  static const LabelGrid grid = readGrid(test::assetPath("icrp110_am.nii.gz"));
  return grid;
}

// One selection holding the whole cage.
Pose wholeCagePose(const GridGeometry& g, std::optional<PoseTransform> transform) {
  PoseSelection all;
  all.name = "whole cage";
  all.shape = SelectionShape::Box;
  all.boxMin = g.boxMin() - Eigen::Vector3d::Constant(1e3);
  all.boxMax = g.boxMax() + Eigen::Vector3d::Constant(1e3);
  all.fixed = !transform;
  if (transform) all.transform = *transform;
  Pose pose;
  pose.name = transform ? "rigid" : "identity";
  pose.selections = {all};
  return pose;
}

DeformationPipeline posedPipeline(const LabelGrid& grid, const Pose& pose) {
  PipelineOptions options;
  options.envelope = false;
  options.pose = pose;
  DeformationPipeline pipeline(grid, options);
  pipeline.deform();
  return pipeline;
}

TEST(DeformationPipeline, IdentityPoseReproducesTheAdultMaleVoxelForVoxel) {
  const LabelGrid& source = adultMale();
  const DeformationPipeline pipeline = posedPipeline(source, wholeCagePose(source.geometry(), std::nullopt));
  EXPECT_EQ(pipeline.stats().uncoveredVoxels, 0);
  EXPECT_EQ(pipeline.deformedTransferMesh(), pipeline.transferMesh().positions);
  const LabelGrid out = rasterizeDeformedGrid(source, pipeline.transferMesh(), pipeline.deformedTransferMesh());
  // G' lies on the source lattice; every voxel of either grid must agree
  // (background outside the other's extent).
  const Eigen::Vector3d offset = source.geometry().continuousIndex(out.geometry().origin);
  ASSERT_TRUE(offset.isApprox(offset.array().round().matrix(), 1e-9));
  const Index3 shift{std::lround(offset.x()), std::lround(offset.y()), std::lround(offset.z())};
  std::int64_t differing = 0;
  for (std::int64_t k = 0; k < out.dims()[2]; ++k)
    for (std::int64_t j = 0; j < out.dims()[1]; ++j)
      for (std::int64_t i = 0; i < out.dims()[0]; ++i)
        differing += out.at(i, j, k) != source.atOr(i + shift[0], j + shift[1], k + shift[2]);
  std::int64_t sourceForeground = 0, outForeground = 0;
  for (const Label l : source.labels()) sourceForeground += l != 0;
  for (const Label l : out.labels()) outForeground += l != 0;
  EXPECT_EQ(differing, 0);
  EXPECT_EQ(outForeground, sourceForeground);
  std::cout << "[ stats    ] identity: " << out.voxelCount() << " output voxels, " << differing << " differ; "
            << outForeground << " foreground voxels (source " << sourceForeground << ")\n";
}

TEST(DeformationPipeline, RigidPoseMovesTheTransferMeshRigidlyAndKeepsLabelCounts) {
  const LabelGrid& source = adultMale();
  const GridGeometry& g = source.geometry();
  PoseTransform rotation;
  rotation.axis = Eigen::Vector3d::UnitZ();
  rotation.angleDeg = 30.0;
  rotation.center = 0.5 * (g.boxMin() + g.boxMax());
  const DeformationPipeline pipeline = posedPipeline(source, wholeCagePose(g, rotation));
  const Eigen::Matrix3d r = Eigen::AngleAxisd(30.0 * std::numbers::pi / 180.0, rotation.axis).toRotationMatrix();
  double worst = 0.0;
  const TetMesh& rest = pipeline.transferMesh();
  for (std::size_t v = 0; v < rest.vertexCount(); ++v) {
    const Eigen::Vector3d expected = r * (rest.positions[v] - rotation.center) + rotation.center;
    worst = std::max(worst, (pipeline.deformedTransferMesh()[v] - expected).norm());
  }
  EXPECT_LE(worst, 1e-6 * g.diagonal());

  const LabelGrid out = rasterizeDeformedGrid(source, rest, pipeline.deformedTransferMesh());
  const std::vector<std::uint64_t> before = computeLabelStats(source).counts, after = computeLabelStats(out).counts;
  // Nearest-neighbour resampling of a rotated grid changes a label's count
  // by a fraction that grows with its surface-to-volume ratio: thin shells
  // and organs of a few hundred voxels move by several percent whatever the
  // deformation's accuracy. The 1 % bound holds from 10,000 voxels (3.6 cm^3
  // here); smaller labels are held to 2 % from 1,000 voxels and reported.
  struct Band {
    std::uint64_t minVoxels;
    double bound;
    double largest = 0.0;
    Label label = 0;
  };
  std::vector<Band> bands = {{10000, 1.0}, {1000, 2.0}, {0, 100.0}};
  std::uint64_t foregroundBefore = 0, foregroundAfter = 0;
  for (std::size_t l = 1; l < before.size(); ++l) {
    const std::uint64_t a = l < after.size() ? after[l] : 0;
    foregroundBefore += before[l];
    foregroundAfter += a;
    if (before[l] == 0) continue;
    const double change = 100.0 * (double(a) - double(before[l])) / double(before[l]);
    Band& band = *std::find_if(bands.begin(), bands.end(), [&](const Band& b) { return before[l] >= b.minVoxels; });
    EXPECT_LE(std::abs(change), band.bound) << "label " << l << ": " << before[l] << " voxels before, " << a << " after";
    if (std::abs(change) > std::abs(band.largest)) {
      band.largest = change;
      band.label = Label(l);
    }
  }
  const double foregroundChange = 100.0 * (double(foregroundAfter) - double(foregroundBefore)) / double(foregroundBefore);
  EXPECT_LE(std::abs(foregroundChange), 0.1);
  std::cout << "[ stats    ] rigid 30 deg: " << rest.vertexCount() << " TM vertices, largest deviation from the rotation "
            << worst << " mm (" << worst / g.diagonal() << " of the diagonal); foreground " << foregroundChange << " %\n";
  for (const Band& b : bands)
    std::cout << "[ stats    ]   labels >= " << b.minVoxels << " voxels: largest count change " << b.largest << " % (label "
              << b.label << ", " << before[b.label] << " voxels)\n";

  // With the correction: every label, whatever its size, within 1 %.
  LabelGrid kept = out;
  const std::vector<double> targets = deformedLabelVolumes(source, rest, pipeline.deformedTransferMesh());
  const LabelVolumeCorrection c = preserveLabelVolumes(kept, source, rest, pipeline.deformedTransferMesh(), targets);
  const std::vector<std::uint64_t> corrected = computeLabelStats(kept).counts;
  double largest = 0.0;
  Label largestLabel = 0;
  for (std::size_t l = 1; l < before.size(); ++l) {
    if (before[l] == 0) continue;
    EXPECT_NEAR(targets[l], double(before[l]), 1e-6 * double(before[l])) << "label " << l << ": rigid, det J = 1";
    const std::uint64_t a = l < corrected.size() ? corrected[l] : 0;
    const double change = 100.0 * (double(a) - double(before[l])) / double(before[l]);
    EXPECT_LE(std::abs(change), 1.0) << "label " << l << ": " << before[l] << " voxels before, " << a << " after correction";
    if (std::abs(change) > std::abs(largest)) {
      largest = change;
      largestLabel = Label(l);
    }
  }
  // Only boundary voxels change: few of the foreground.
  EXPECT_LT(double(c.relabelled), 0.01 * double(foregroundBefore));
  std::cout << "[ stats    ] label-volume correction: " << c.candidates << " boundary voxels, " << c.relabelled
            << " relabelled (" << 100.0 * double(c.relabelled) / double(foregroundBefore) << " % of the foreground) in "
            << c.sweeps << " sweeps; largest count change " << largest << " % (label " << largestLabel << ", "
            << before[largestLabel] << " voxels)\n";
}

}  // namespace
}  // namespace vox
