// The body's projected areas and height (body_projection.h) on boxes whose
// silhouettes are known: in the grid's own axes, with the axes permuted and
// flipped by the direction matrix (front is always along world y), rotated
// about z (an oblique grid, sampled on a raster), a concave union of two
// boxes, and slabs given in any order.

#include "geometry/body_projection.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace vox {
namespace {

struct Box {
  Index3 lo, hi;  // voxel index ranges [lo, hi)
};

LabelGrid gridWith(const GridGeometry& g, std::initializer_list<Box> boxes) {
  LabelGrid grid(g);
  for (const Box& b : boxes)
    for (std::int64_t k = b.lo[2]; k < b.hi[2]; ++k)
      for (std::int64_t j = b.lo[1]; j < b.hi[1]; ++j)
        for (std::int64_t i = b.lo[0]; i < b.hi[0]; ++i) grid.at(i, j, k) = 3;
  return grid;
}

GridGeometry geometry(Index3 dims, Eigen::Vector3d spacing) {
  GridGeometry g;
  g.dims = dims;
  g.spacing = spacing;
  g.origin = {-40, 12, 300};
  return g;
}

// 10 x 20 x 30 voxels of 1 x 2 x 3 mm: 10 x 40 x 90 mm.
const Box kBox{{2, 5, 3}, {12, 25, 33}};

TEST(BodyProjection, BoxAlongTheWorldAxes) {
  const BodyProjection p = bodyProjection(gridWith(geometry({20, 30, 40}, {1, 2, 3}), {kBox}));
  EXPECT_TRUE(p.exact);
  EXPECT_EQ(p.foregroundVoxels, 10 * 20 * 30);
  EXPECT_DOUBLE_EQ(p.frontMm2, 10.0 * 90.0);  // along y: x by z
  EXPECT_DOUBLE_EQ(p.sideMm2, 40.0 * 90.0);   // along x: y by z
  EXPECT_DOUBLE_EQ(p.topMm2, 10.0 * 40.0);    // along z: x by y
  EXPECT_DOUBLE_EQ(p.heightMm, 90.0);
}

TEST(BodyProjection, DirectionPlacesTheGridAxesInTheWorld) {
  // Grid i runs along world z, j along -x, k along +y (an "LIP"-like file).
  GridGeometry g = geometry({20, 30, 40}, {1, 2, 3});
  g.direction << 0, -1, 0,  //
      0, 0, 1,              //
      1, 0, 0;
  const BodyProjection p = bodyProjection(gridWith(g, {kBox}));
  // Extents: 10 mm along world z, 40 mm along x, 90 mm along y.
  EXPECT_TRUE(p.exact);
  EXPECT_DOUBLE_EQ(p.frontMm2, 40.0 * 10.0);
  EXPECT_DOUBLE_EQ(p.sideMm2, 90.0 * 10.0);
  EXPECT_DOUBLE_EQ(p.topMm2, 40.0 * 90.0);
  EXPECT_DOUBLE_EQ(p.heightMm, 10.0);
}

TEST(BodyProjection, ConcaveUnionCountsOverlapOnce) {
  // A second box behind the first (larger y), overlapping it in x by 4
  // voxels and in z by 10: seen from the front the two overlap on 4 x 10
  // voxels; from the side they overlap on the z range only.
  const Box back{{8, 26, 23}, {18, 29, 38}};  // 10 x 3 x 15 voxels
  const BodyProjection p = bodyProjection(gridWith(geometry({20, 30, 40}, {1, 2, 3}), {kBox, back}));
  EXPECT_DOUBLE_EQ(p.frontMm2, (10.0 * 30 + 10.0 * 15 - 4.0 * 10) * 1.0 * 3.0);
  EXPECT_DOUBLE_EQ(p.sideMm2, (20.0 * 30 + 3.0 * 15) * 2.0 * 3.0);
  EXPECT_DOUBLE_EQ(p.topMm2, (10.0 * 20 + 10.0 * 3) * 1.0 * 2.0);
  EXPECT_DOUBLE_EQ(p.heightMm, (38 - 3) * 3.0);
}

TEST(BodyProjection, ObliqueGridIsSampledWithinAPercent) {
  // 30 x 16 x 20 voxels of 1 mm rotated 30 degrees about z.
  const double theta = 30.0 * M_PI / 180.0;
  GridGeometry g = geometry({40, 24, 26}, {1, 1, 1.5});
  g.direction = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const BodyProjection p = bodyProjection(gridWith(g, {{{5, 4, 3}, {35, 20, 23}}}));
  const double a = 30.0, b = 16.0, c = 30.0;  // mm along the grid's axes
  EXPECT_FALSE(p.exact);
  EXPECT_NEAR(p.frontMm2, (a * std::cos(theta) + b * std::sin(theta)) * c, 0.01 * p.frontMm2);
  EXPECT_NEAR(p.sideMm2, (a * std::sin(theta) + b * std::cos(theta)) * c, 0.01 * p.sideMm2);
  EXPECT_NEAR(p.topMm2, a * b, 0.01 * a * b);
  EXPECT_NEAR(p.heightMm, c, 1e-9);
}

TEST(BodyProjection, ObliqueHeightIsTheExtentOfTheVoxelCorners) {
  // Tilted 20 degrees about x: height = b sin + c cos of the box, exactly;
  // the front area within a pixel (a quarter voxel) along each side.
  const double theta = 20.0 * M_PI / 180.0;
  GridGeometry g = geometry({40, 30, 40}, {1, 1, 1});
  g.direction = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const BodyProjection p = bodyProjection(gridWith(g, {{{4, 5, 3}, {36, 21, 37}}}));
  const double width = 32.0, height = 16.0 * std::sin(theta) + 34.0 * std::cos(theta);
  EXPECT_NEAR(p.heightMm, height, 1e-9);
  EXPECT_NEAR(p.frontMm2, width * height, 0.25 * (width + height));
}

TEST(BodyProjection, SlabsInAnyOrderGiveTheWholeGridsResult) {
  for (const bool oblique : {false, true}) {
    GridGeometry g = geometry({20, 30, 40}, {1, 2, 3});
    if (oblique) g.direction = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    const LabelGrid grid = gridWith(g, {kBox, {{8, 26, 23}, {18, 29, 38}}});
    const BodyProjection whole = bodyProjection(grid);
    BodyProjectionAccumulator slabs(g);
    const std::int64_t slice = g.sliceVoxels();
    for (const auto& [k0, k1] : {std::pair{30, 40}, {0, 7}, {7, 8}, {8, 30}}) slabs.addSlices(k0, k1 - k0, grid.data() + k0 * slice);
    const BodyProjection p = slabs.result();
    EXPECT_EQ(p.foregroundVoxels, whole.foregroundVoxels);
    EXPECT_DOUBLE_EQ(p.frontMm2, whole.frontMm2);
    EXPECT_DOUBLE_EQ(p.sideMm2, whole.sideMm2);
    EXPECT_DOUBLE_EQ(p.topMm2, whole.topMm2);
    EXPECT_DOUBLE_EQ(p.heightMm, whole.heightMm);
  }
}

TEST(BodyProjection, EmptyGridIsZero) {
  const BodyProjection p = bodyProjection(LabelGrid(geometry({4, 4, 4}, {1, 1, 1})));
  EXPECT_EQ(p.foregroundVoxels, 0);
  EXPECT_EQ(p.frontMm2, 0.0);
  EXPECT_EQ(p.heightMm, 0.0);
}

}  // namespace
}  // namespace vox
