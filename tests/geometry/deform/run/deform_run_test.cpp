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

}  // namespace
}  // namespace vox
