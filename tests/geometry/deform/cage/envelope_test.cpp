#include "geometry/deform/cage/envelope.h"

#include "geometry/deform/cage/surface_checks.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/synth.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

namespace vox {
namespace {

double foregroundVolume(const LabelGrid& grid) {
  std::int64_t n = 0;
  for (const Label l : grid.labels()) n += l != 0;
  return double(n) * grid.geometry().voxelVolume();
}

TEST(Envelope, SphereIsClosedSmoothAndOfTheRightVolume) {
  LabelGrid grid = synthesize(SynthKind::NestedSpheres, 40);
  grid.geometry().origin = {-10.0, 5.0, 2.0};
  const TriMesh envelope = extractEnvelope(grid, {.smoothingMm = 1.0, .facetSizeMm = 3.0, .facetDistanceMm = 0.2});
  const SurfaceCheck c = checkSurface(envelope);
  EXPECT_TRUE(c.validCage());
  EXPECT_EQ(c.components, 1u);
  EXPECT_EQ(c.genus, 0);
  EXPECT_NEAR(c.volume, foregroundVolume(grid), 0.05 * foregroundVolume(grid));
  // Smooth: every vertex close to the sphere of the outer shell.
  const Eigen::Vector3d centre = grid.geometry().origin + Eigen::Vector3d::Constant(19.5);
  for (const Eigen::Vector3d& p : envelope.positions) EXPECT_NEAR((p - centre).norm(), 0.42 * 40, 1.0);
}

TEST(Envelope, StickFigureAndSeparatePieces) {
  // Two pieces (figure and a detached block): both get their own surface.
  LabelGrid grid = synthesize(SynthKind::StickFigure, 64);
  for (std::int64_t k = 2; k < 6; ++k)
    for (std::int64_t j = 2; j < 6; ++j)
      for (std::int64_t i = 30; i < 34; ++i) grid.at(i, j, k) = 1;
  const TriMesh envelope = extractEnvelope(grid, {.smoothingMm = 1.0, .facetSizeMm = 4.0, .facetDistanceMm = 0.5});
  const SurfaceCheck c = checkSurface(envelope);
  EXPECT_TRUE(c.validCage());
  EXPECT_EQ(c.components, 2u);
  EXPECT_NEAR(c.volume, foregroundVolume(grid), 0.08 * foregroundVolume(grid));
}

TEST(Envelope, EmptyGridIsAnError) {
  GridGeometry g;
  g.dims = {4, 4, 4};
  EXPECT_THROW(extractEnvelope(LabelGrid(g, 0)), InputError);
}

TEST(Envelope, AdultMalePhantom) {
  const LabelGrid grid = readGrid(test::assetPath("icrp110_am.nii.gz"));
  const TriMesh envelope = extractEnvelope(grid);
  const SurfaceCheck c = checkSurface(envelope);
  EXPECT_TRUE(c.validCage());
  EXPECT_GT(envelope.vertexCount(), 10000u);
  EXPECT_LT(envelope.vertexCount(), 100000u);
  EXPECT_NEAR(c.volume, foregroundVolume(grid), 0.02 * foregroundVolume(grid));
  RecordProperty("envelope_vertices", int(envelope.vertexCount()));
  RecordProperty("envelope_genus", c.genus);
}

}  // namespace
}  // namespace vox
