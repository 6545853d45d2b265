// deformGrid builds what the posed grid needs: the envelope, which only the
// interactive display draws, is neither built nor embedded.

#include "geometry/deform/run/deform_run.h"

#include "geometry/io/grid_io.h"
#include "geometry/raster/raster_engines.h"
#include "geometry/synth.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>

namespace vox {
namespace {

TEST(DeformGrid, BuildsNoEnvelope) {
  const std::string dir = test::tempDir();
  DeformGridRequest request;
  request.input = dir + "/stick.mha";
  request.output = dir + "/posed.nii.gz";
  writeGrid(request.input, synthesize(SynthKind::StickFigure, 32));
  request.organs = synthOrganTable(SynthKind::StickFigure);
  request.pose = parsePose(R"({"selections": [
      {"name": "body", "box": {"min": [-1000, -1000, -1000], "max": [1000, 1000, 1000]}, "fixed": true},
      {"name": "head", "box": {"min": [-1000, -1000, 50], "max": [1000, 1000, 1000]},
       "transform": {"rotation": {"axis": [0, 0, 1], "angle_deg": 20, "center": [14, 10, 55]}}}]})",
                           "head");
  request.poseSource = "head";
  request.force = true;
  CpuRasterEngines engines;
  const DeformationReport report = deformGrid(request, engines);
  EXPECT_TRUE(std::filesystem::exists(request.output));
  EXPECT_GT(report.tmTets, 0u);
  EXPECT_EQ(report.envelopeVertices, 0u);
  EXPECT_TRUE(std::none_of(report.stages.begin(), report.stages.end(), [](const StageTime& t) { return t.name == "envelope"; }));
}

// The deform run checks a joint pose's bones against the skeleton it compiles
// the pose with; the pipeline's options themselves (shared by render, prepare
// and the viewer) carry no such check.
TEST(DeformGrid, ChecksTheBonesOfAJointPoseWhereItCompilesIt) {
  DeformGridRequest request;
  const LabelGrid grid = synthesize(SynthKind::SkeletonFigure, 128);
  request.organs = synthOrganTable(SynthKind::SkeletonFigure);
  request.poseSource = "crossed.json";
  request.pose = parsePose(R"({"joints": {"right_hip": {"abduction": -30}}})", request.poseSource);
  std::optional<std::string> fault;
  deformPipelineOptions(request, grid, 1, nullptr, &fault);
  ASSERT_TRUE(fault);
  EXPECT_EQ(fault->rfind("the bones of the right_", 0), 0u) << *fault;
  EXPECT_NE(fault->find("with right_hip as posed"), std::string::npos) << *fault;
  request.maxBoneOverlapPercent = 100.0;
  deformPipelineOptions(request, grid, 1, nullptr, &fault);
  EXPECT_FALSE(fault);
  request.maxBoneOverlapPercent = skeleton::kMaxBoneOverlapPercent;
  request.pose = parsePose(R"({"joints": {"right_hip": {"abduction": 20}}})", request.poseSource);
  deformPipelineOptions(request, grid, 1, nullptr, &fault);
  EXPECT_FALSE(fault);
}

// The transfer mesh is built beside the cage, unless a memory limit sized
// the working grid for one stage's grids at a time.
TEST(DeformGrid, BuildsTheTransferMeshBesideTheCageUnlessMemoryIsLimited) {
  DeformGridRequest request;
  const LabelGrid grid = synthesize(SynthKind::StickFigure, 32);
  request.organs = synthOrganTable(SynthKind::StickFigure);
  request.poseSource = "still";
  EXPECT_TRUE(deformPipelineOptions(request, grid, 1).concurrentTransferMesh);
  request.maxMemoryMb = 512;
  EXPECT_FALSE(deformPipelineOptions(request, grid, 1).concurrentTransferMesh);
}

}  // namespace
}  // namespace vox
