// Bones pressed through each other: counts on a hand-built grid where the
// answer is known, and the ball joint's articular shell left out.

#include "geometry/skeleton/bone_overlap.h"

#include <gtest/gtest.h>

namespace vox::skeleton {
namespace {

// A 40 x 12 x 12 grid of 1 mm voxels (centres on whole mm): the trunk's bone fills x in [2, 10),
// the right upper arm's x in [arm, arm + 8), both y, z in [2, 10): 512
// voxels each; the right forearm's x in [30, 32), y, z in [4, 6): 8 voxels.
BodyParts blocks(std::int64_t armStart = 20) {
  BodyParts b;
  b.parts = LabelGrid(GridGeometry{{40, 12, 12}}, 0);
  const GridGeometry& g = b.parts.geometry();
  BoneVoxels trunk{Bone::Ribs, Side::Axial, {}}, arm{Bone::Humerus, Side::Right, {}}, forearm{Bone::ForearmBones, Side::Right, {}};
  for (std::int64_t k = 0; k < 12; ++k)
    for (std::int64_t j = 0; j < 12; ++j)
      for (std::int64_t i = 0; i < 40; ++i) {
        const std::int64_t v = g.index(i, j, k);
        const bool block = j >= 2 && j < 10 && k >= 2 && k < 10;
        if (block && i >= 2 && i < 10) {
          b.parts.labels()[std::size_t(v)] = Label(Part::Trunk);
          trunk.voxels.push_back(v);
        } else if (block && i >= armStart && i < armStart + 8) {
          b.parts.labels()[std::size_t(v)] = Label(Part::RightUpperArm);
          arm.voxels.push_back(v);
        } else if (i >= 30 && i < 32 && j >= 4 && j < 6 && k >= 4 && k < 6) {
          b.parts.labels()[std::size_t(v)] = Label(Part::RightForearm);
          forearm.voxels.push_back(v);
        }
      }
  b.bones = {trunk, arm, forearm};
  return b;
}

std::array<Eigen::Isometry3d, kPartCount + 1> still() {
  std::array<Eigen::Isometry3d, kPartCount + 1> m;
  m.fill(Eigen::Isometry3d::Identity());
  return m;
}

TEST(BoneOverlap, CountsBonesMovedIntoEachOther) {
  const BodyParts b = blocks();
  EXPECT_TRUE(boneOverlaps(b, {}, still()).empty());
  // The arm (and the forearm below it) 15 mm towards the trunk: the arm's
  // first 5 slabs of 8 x 8 land in the trunk's last 5.
  auto m = still();
  for (const Part p : partSubtree(Part::RightUpperArm)) m[std::size_t(p)] = Eigen::Translation3d(-15.0, 0.0, 0.0);
  const std::vector<BoneOverlap> o = boneOverlaps(b, {}, m);
  ASSERT_EQ(o.size(), 1u);
  EXPECT_EQ(o[0].first, Part::Trunk);
  EXPECT_EQ(o[0].second, Part::RightUpperArm);
  EXPECT_EQ(o[0].voxels, 5u * 64u);
  EXPECT_DOUBLE_EQ(o[0].volumeMm3, 320.0);
  EXPECT_DOUBLE_EQ(o[0].fractionOfSmaller, 320.0 / 512.0);
  // The forearm alone into the arm: the smaller part is the forearm.
  m = still();
  m[std::size_t(Part::RightForearm)] = Eigen::Translation3d(-5.0, 0.0, 0.0);
  const std::vector<BoneOverlap> f = boneOverlaps(b, {}, m);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].smaller, Part::RightForearm);
  EXPECT_EQ(f[0].voxels, 8u);
  EXPECT_DOUBLE_EQ(f[0].fractionOfSmaller, 1.0);
  // Moved apart: nothing.
  m[std::size_t(Part::RightForearm)] = Eigen::Translation3d(5.0, 0.0, 0.0);
  EXPECT_TRUE(boneOverlaps(b, {}, m).empty());
}

TEST(BoneOverlap, LeavesTheBallJointsShellOut) {
  // The arm against the trunk, turned half a turn about the z axis through
  // the middle of the face they share: each block lands on the other.
  const BodyParts b = blocks(10);
  const Eigen::Vector3d centre(9.5, 5.5, 5.5);
  auto m = still();
  const Eigen::Isometry3d turn = Eigen::Translation3d(centre) * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()) * Eigen::Translation3d(-centre);
  for (const Part p : partSubtree(Part::RightUpperArm)) m[std::size_t(p)] = turn;
  const std::vector<BoneOverlap> all = boneOverlaps(b, {}, m);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].voxels, 512u);
  // With a shoulder there whose ball has a radius of 2 mm: the voxels of
  // each block within 3 mm (the radius and a voxel) of the centre are the
  // articular surfaces, left out.
  Joint shoulder;
  shoulder.id = JointId::RightShoulder;
  shoulder.centre = centre;
  shoulder.radius = 2.0;
  std::size_t inShell = 0;
  for (const std::int64_t v : b.bones[1].voxels) {
    const Index3 c = b.parts.geometry().ijk(v);
    inShell += (b.parts.geometry().voxelCenter(c[0], c[1], c[2]) - centre).norm() <= 3.0;
  }
  EXPECT_EQ(inShell, 68u);  // 32, 24 and 12 in the three layers of voxels nearest the face
  const std::vector<BoneOverlap> o = boneOverlaps(b, std::vector<Joint>{shoulder}, m);
  ASSERT_EQ(o.size(), 1u);
  EXPECT_EQ(o[0].voxels, 512u - inShell);
  // A joint that joins other parts leaves nothing out.
  shoulder.id = JointId::RightElbow;
  EXPECT_EQ(boneOverlaps(b, std::vector<Joint>{shoulder}, m)[0].voxels, 512u);
}

TEST(BoneOverlap, PartSubtree) {
  const std::vector<Part> arm = partSubtree(Part::RightUpperArm);
  EXPECT_EQ(arm, (std::vector<Part>{Part::RightUpperArm, Part::RightForearm, Part::RightHand}));
  EXPECT_EQ(partSubtree(Part::Trunk).size(), std::size_t(kPartCount));  // the pelvis hangs from it too
  EXPECT_EQ(partSubtree(Part::LeftFoot), std::vector<Part>{Part::LeftFoot});
}

}  // namespace
}  // namespace vox::skeleton
