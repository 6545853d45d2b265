// The skin over the tissue a pose bares: a box of muscle under a skin
// layer, with a bone under it and a patch of skin missing at rest. Through an
// identity map nothing changes; with a patch of the posed skin stripped, the
// muscle under it becomes skin, the bone keeps its voxel under a skin laid
// over it, the tissue bare at rest stays, the same for any thread count.

#include "geometry/deform/solve/skin_cover.h"
#include "geometry/raster/rasterize.h"
#include "geometry/error.h"
#include "tests/support/deformation_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace vox {
namespace {

constexpr Label kSkin = 1, kMuscle = 2, kBone = 3;
constexpr int kN = 24, kLo = 4, kHi = 20;  // the body: [kLo, kHi)^3, its outer layer skin

LabelGrid body() {
  LabelGrid g(GridGeometry{{kN, kN, kN}, {2.0, 2.0, 3.0}, Eigen::Vector3d::Zero()});
  for (int k = kLo; k < kHi; ++k)
    for (int j = kLo; j < kHi; ++j)
      for (int i = kLo; i < kHi; ++i) {
        const bool outer = i == kLo || j == kLo || k == kLo || i == kHi - 1 || j == kHi - 1 || k == kHi - 1;
        g.at(i, j, k) = outer ? kSkin : kMuscle;
      }
  g.at(12, 12, kLo + 1) = kBone;  // under the patch the pose strips
  // The phantom's own bare patch on top: 5 x 5 skin voxels missing.
  for (int j = 10; j < 15; ++j)
    for (int i = 10; i < 15; ++i) g.at(i, j, kHi - 1) = 0;
  return g;
}

const std::vector<std::uint8_t> kSkinFlags = {0, 1, 0, 0};
const std::vector<std::uint8_t> kBoneFlags = {0, 0, 0, 1};

// The voxel of `posed` (G', cropped to the posed mesh) at the source's (i, j, k).
Label& at(LabelGrid& posed, const LabelGrid& source, int i, int j, int k) {
  const Eigen::Vector3d offset = (source.origin() - posed.origin()).cwiseQuotient(source.spacing());
  return posed.at(i + std::lround(offset.x()), j + std::lround(offset.y()), k + std::lround(offset.z()));
}

// G' equals the source wherever either has a voxel.
void expectSourceLabels(LabelGrid& posed, const LabelGrid& source) {
  std::uint64_t posedBody = 0, sourceBody = 0;
  for (const Label l : posed.labels()) posedBody += l != 0;
  for (int k = 0; k < kN; ++k)
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i)
        if (source.at(i, j, k) != 0) {
          ++sourceBody;
          EXPECT_EQ(at(posed, source, i, j, k), source.at(i, j, k)) << i << " " << j << " " << k;
        }
  EXPECT_EQ(posedBody, sourceBody);
}

std::uint64_t flaggedCount(const std::vector<std::uint8_t>& flags) {
  return std::uint64_t(std::count(flags.begin(), flags.end(), std::uint8_t(1)));
}

TEST(SkinCover, AMapThatMovesNothingChangesNothing) {
  const LabelGrid source = body();
  const TetMesh rest = test::coveringTransferMesh(source, 2);
  LabelGrid posed = rasterizeDeformedGrid(source, rest, rest.positions);
  expectSourceLabels(posed, source);
  EXPECT_EQ(flaggedCount(bareVoxels(source, kSkinFlags)), 9u);  // the 3 x 3 under the patch's middle
  const SkinCover cover = coverBareTissue(posed, source, rest, rest.positions, kSkinFlags, kBoneFlags);
  EXPECT_EQ(cover.bareVoxels, 9u);
  EXPECT_EQ(cover.bareAtRest, 9u);
  EXPECT_EQ(cover.covered, 0u);
  expectSourceLabels(posed, source);
}

TEST(SkinCover, TissueThePoseBaresBecomesSkinButNotBone) {
  const LabelGrid source = body();
  const TetMesh rest = test::coveringTransferMesh(source, 2);
  LabelGrid stripped = rasterizeDeformedGrid(source, rest, rest.positions);
  for (int j = 10; j < 15; ++j)
    for (int i = 10; i < 15; ++i) at(stripped, source, i, j, kLo) = 0;  // a patch of the underside's skin torn off
  for (const int threads : {1, 2}) {
    LabelGrid posed = stripped;
    const SkinCover cover = coverBareTissue(posed, source, rest, rest.positions, kSkinFlags, kBoneFlags, threads);
    EXPECT_EQ(cover.bareVoxels, 18u) << threads;  // 9 on top, 9 under the torn patch
    EXPECT_EQ(cover.bareAtRest, 9u);
    EXPECT_EQ(cover.boneVoxels, 1u);
    EXPECT_EQ(cover.covered, 8u);
    ASSERT_GT(cover.from.size(), std::size_t(kMuscle));
    EXPECT_EQ(cover.overBone, 1u);
    EXPECT_EQ(cover.from[kMuscle], 8u);
    EXPECT_EQ(cover.to[kSkin], 9u);
    for (int j = 11; j < 14; ++j)
      for (int i = 11; i < 14; ++i) EXPECT_EQ(at(posed, source, i, j, kLo + 1), i == 12 && j == 12 ? kBone : kSkin) << i << " " << j;
    EXPECT_EQ(at(posed, source, 12, 12, kLo), kSkin);        // over the bone
    EXPECT_EQ(at(posed, source, 11, 12, kLo), Label(0));     // beside it: the air stays
    EXPECT_EQ(at(posed, source, 12, 12, kHi - 2), kMuscle);  // bare at rest: left
    // What is left bare: the rest's own patch.
    EXPECT_EQ(flaggedCount(bareVoxels(posed, kSkinFlags)), 9u);
  }
}

TEST(SkinCover, NoSkinLabelNoCoverAndAnotherGridRefused) {
  const LabelGrid source = body();
  const TetMesh rest = test::coveringTransferMesh(source, 2);
  LabelGrid posed = rasterizeDeformedGrid(source, rest, rest.positions);
  EXPECT_EQ(coverBareTissue(posed, source, rest, rest.positions, std::vector<std::uint8_t>{0, 0, 0, 0}, kBoneFlags).bareVoxels, 0u);
  LabelGrid other(GridGeometry{{kN + 1, kN, kN}, {2.0, 2.0, 3.0}, Eigen::Vector3d::Zero()});
  EXPECT_THROW(coverBareTissue(other, source, rest, rest.positions, kSkinFlags, kBoneFlags), InputError);
}

}  // namespace
}  // namespace vox
