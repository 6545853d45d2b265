#include "geometry/label_stats.h"
#include "geometry/synth.h"
#include "geometry/tet_mesh.h"
#include "geometry/voxel_tetrahedralization.h"

#include <gtest/gtest.h>

namespace vox {
namespace {

TEST(VoxelTetrahedralization, ConformingPositiveAndVolumeExact) {
  LabelGrid grid = synthesize(SynthKind::NestedSpheres, 12);
  grid.geometry().spacing = {1.5, 2.0, 3.0};
  const TetMesh mesh = tetrahedralizeVoxels(grid);
  ASSERT_EQ(mesh.tetCount(), std::size_t(6 * grid.voxelCount()));
  EXPECT_EQ(mesh.vertexCount(), std::size_t(13 * 13 * 13));
  double total = 0.0;
  for (const Tet& t : mesh.tets) {
    const double v = signedVolume(mesh.positions, t);
    EXPECT_GT(v, 0.0);
    total += v;
  }
  EXPECT_NEAR(total, double(grid.voxelCount()) * 9.0, 1e-9);
  // Conforming: every interior face is shared by exactly two tets, and the
  // boundary faces are exactly the 2 triangles per box face square.
  const auto nb = faceNeighbors(mesh);
  std::size_t boundary = 0;
  for (const auto& n : nb)
    for (int k = 0; k < 4; ++k) boundary += n[k] < 0;
  EXPECT_EQ(boundary, std::size_t(2 * 6 * 12 * 12));
}

TEST(VoxelTetrahedralization, ForegroundOnlyKeepsLabelsAndVolumes) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 16);
  const TetMesh mesh = tetrahedralizeVoxels(grid, {.includeBackground = false});
  const LabelStats stats = computeLabelStats(grid);
  std::vector<double> volume(stats.counts.size(), 0.0);
  for (std::size_t t = 0; t < mesh.tetCount(); ++t) {
    ASSERT_GT(mesh.labels[t], 0);
    volume[std::size_t(mesh.labels[t])] += signedVolume(mesh.positions, mesh.tets[t]);
  }
  for (std::size_t l = 1; l < stats.counts.size(); ++l) EXPECT_NEAR(volume[l], double(stats.counts[l]), 1e-9) << l;
}

}  // namespace
}  // namespace vox
