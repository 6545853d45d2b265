#include "geometry/distance_transform.h"

#include "geometry/parallel.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace vox {
namespace {

GridGeometry anisotropicGeometry() {
  GridGeometry g;
  g.dims = {13, 9, 7};
  g.spacing = {2.137, 1.5, 8.0};
  g.origin = {-3.0, 1.0, 5.0};
  return g;
}

TEST(DistanceTransform, MatchesBruteForceOnAnisotropicGrid) {
  const GridGeometry g = anisotropicGeometry();
  std::mt19937 rng(7);
  std::vector<std::uint8_t> seeds(std::size_t(g.voxelCount()), 0);
  for (auto& s : seeds) s = rng() % 23 == 0;
  const DistanceTransform dt = euclideanDistanceTransform(g, seeds, true);
  ASSERT_EQ(dt.nearest.size(), seeds.size());
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
    const Index3 a = g.ijk(v);
    double best = std::numeric_limits<double>::infinity();
    for (std::int64_t w = 0; w < g.voxelCount(); ++w) {
      if (!seeds[w]) continue;
      const Index3 b = g.ijk(w);
      best = std::min(best, (g.voxelCenter(a[0], a[1], a[2]) - g.voxelCenter(b[0], b[1], b[2])).norm());
    }
    EXPECT_NEAR(dt.distance.values[v], best, 1e-4 * (1.0 + best)) << v;
    // The feature transform names a seed at exactly that distance.
    const std::int64_t n = dt.nearest[v];
    ASSERT_GE(n, 0);
    ASSERT_TRUE(seeds[n]);
    const Index3 b = g.ijk(n);
    EXPECT_NEAR((g.voxelCenter(a[0], a[1], a[2]) - g.voxelCenter(b[0], b[1], b[2])).norm(), best, 1e-4 * (1.0 + best));
  }
}

// The passes' lines run on the parallel loop: the same distances and
// nearest seeds, bit for bit, on one thread and on several.
TEST(DistanceTransform, TheSameOnAnyThreadCount) {
  GridGeometry g = anisotropicGeometry();
  g.dims = {41, 37, 29};
  std::mt19937 rng(11);
  std::vector<std::uint8_t> seeds(std::size_t(g.voxelCount()), 0);
  for (auto& s : seeds) s = rng() % 97 == 0;
  const auto run = [&](int threads) {
    ScopedWorkerThreads scope(threads);
    return euclideanDistanceTransform(g, seeds, true);
  };
  const DistanceTransform one = run(1), many = run(5);
  EXPECT_EQ(one.distance.values, many.distance.values);
  EXPECT_EQ(one.nearest, many.nearest);
}

TEST(DistanceTransform, NoSeedsGivesInfinity) {
  const GridGeometry g = anisotropicGeometry();
  const DistanceTransform dt = euclideanDistanceTransform(g, std::vector<std::uint8_t>(std::size_t(g.voxelCount()), 0), true);
  for (const float d : dt.distance.values) EXPECT_TRUE(std::isinf(d));
  for (const std::int64_t n : dt.nearest) EXPECT_EQ(n, -1);
}

TEST(DistanceTransform, PaddingKeepsPositions) {
  const GridGeometry g = anisotropicGeometry();
  const Index3 pad = padForDistance(g, 10.0, 2);
  EXPECT_EQ(pad, (Index3{2 + 5, 2 + 7, 2 + 2}));
  const GridGeometry p = padGeometry(g, pad);
  LabelGrid grid(g, 0);
  grid.at(3, 4, 5) = 9;
  const LabelGrid padded = padLabels(grid, p);
  EXPECT_EQ(padded.at(3 + pad[0], 4 + pad[1], 5 + pad[2]), 9);
  EXPECT_TRUE(p.voxelCenter(3 + pad[0], 4 + pad[1], 5 + pad[2]).isApprox(g.voxelCenter(3, 4, 5)));
  std::int64_t nonzero = 0;
  for (const Label l : padded.labels()) nonzero += l != 0;
  EXPECT_EQ(nonzero, 1);
}

}  // namespace
}  // namespace vox
