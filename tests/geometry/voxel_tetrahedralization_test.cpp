#include "geometry/error.h"
#include "geometry/label_stats.h"
#include "geometry/synth.h"
#include "geometry/tet_mesh.h"
#include "geometry/voxel_tetrahedralization.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

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

// Face adjacency is mutual, each neighbour across the same three vertices;
// a face in three tets is refused naming the third of them in tet order.
TEST(VoxelTetrahedralization, FaceNeighborsAreMutualAndAFaceInThreeTetsIsRefused) {
  const TetMesh mesh = tetrahedralizeVoxels(synthesize(SynthKind::JunctionSphere, 10), {.includeBackground = false});
  const auto nb = faceNeighbors(mesh);
  std::size_t shared = 0;
  for (std::size_t t = 0; t < mesh.tetCount(); ++t)
    for (int k = 0; k < 4; ++k) {
      const std::int32_t u = nb[t][std::size_t(k)];
      if (u < 0) continue;
      ++shared;
      Tri f = tetFace(mesh.tets[t], k);
      std::sort(f.begin(), f.end());
      int back = 0;
      for (int m = 0; m < 4; ++m) {
        Tri g = tetFace(mesh.tets[std::size_t(u)], m);
        std::sort(g.begin(), g.end());
        if (g == f) {
          EXPECT_EQ(nb[std::size_t(u)][std::size_t(m)], std::int32_t(t));
          ++back;
        }
      }
      EXPECT_EQ(back, 1) << t << " " << k;
    }
  EXPECT_GT(shared, mesh.tetCount());
  TetMesh three;
  three.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, -1}, {0.2, 0.2, 1}, {1, 1, 1}};
  three.tets = {{0, 1, 2, 3}, {1, 2, 3, 6}, {0, 2, 1, 4}, {0, 1, 3, 6}, {0, 1, 2, 5}};
  three.labels.assign(three.tets.size(), 1);
  try {
    faceNeighbors(three, "three.mesh");
    ADD_FAILURE() << "a face in three tets was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("three.mesh"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("a face of tet 4 is shared by more than two tets"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vox
