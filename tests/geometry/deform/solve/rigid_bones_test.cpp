// Rigid bones and collisions. The fit reproduces a rigid motion exactly and
// yields to a given motion; on the synthetic skeleton figure a joint pose
// with rigid bones puts every vertex of the upper arm's rigid group exactly
// where the forward kinematics send it (8 mm off without the constraint); the bone measures of the report see the difference.
// Collisions: tissue of two parts moved onto each other is counted, per
// pair and in the mask; at rest there is none.

#include "geometry/deform/report/collisions.h"
#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/deform/solve/rigid_bones.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/io/grid_io.h"
#include "geometry/parallel.h"
#include "geometry/synth.h"
#include "geometry/voxel_tetrahedralization.h"
#include "tests/support/pose_fixtures.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <filesystem>
#include <limits>
#include <random>

namespace vox::skeleton {
namespace {

TEST(RigidBones, FitReproducesARigidMotionAndYieldsToAGivenOne) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  std::vector<Eigen::Vector3d> rest(40);
  for (Eigen::Vector3d& p : rest) p = {u(rng), u(rng), u(rng)};
  // Group 0: vertices 0..19 (10..19 not fitted, e.g. outside the cage); group 1: 20..29; 30..39 none.
  std::vector<std::int32_t> group(rest.size(), -1);
  std::vector<std::uint8_t> fitted(rest.size(), 1);
  for (int v = 0; v < 20; ++v) group[std::size_t(v)] = 0;
  for (int v = 10; v < 20; ++v) fitted[std::size_t(v)] = 0;
  for (int v = 20; v < 30; ++v) group[std::size_t(v)] = 1;
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  motion.translation() = Eigen::Vector3d(5, -3, 12);
  std::vector<Eigen::Vector3d> positions(rest.size());
  for (std::size_t v = 0; v < rest.size(); ++v) positions[v] = motion * rest[v];
  // The unfitted members start anywhere.
  for (int v = 10; v < 20; ++v) positions[std::size_t(v)] = Eigen::Vector3d::Zero();
  RigidBoneFit fit;
  fit.precompute(group, fitted, rest);
  EXPECT_EQ(fit.groups(), 2u);
  fit.apply(positions);
  for (int v = 0; v < 30; ++v) EXPECT_LT((positions[std::size_t(v)] - motion * rest[std::size_t(v)]).norm(), 1e-9) << v;
  // A given motion wins over the fit.
  std::vector<Eigen::Isometry3d> given(2, Eigen::Isometry3d::Identity());
  given[1].translation() = Eigen::Vector3d(0, 0, 7);
  fit.apply(positions, given);
  for (int v = 0; v < 20; ++v) EXPECT_LT((positions[std::size_t(v)] - rest[std::size_t(v)]).norm(), 1e-12);
  for (int v = 20; v < 30; ++v) EXPECT_LT((positions[std::size_t(v)] - (rest[std::size_t(v)] + Eigen::Vector3d(0, 0, 7))).norm(), 1e-12);
  // Fewer than four fitted vertices: the group is dropped, not guessed.
  std::fill(fitted.begin(), fitted.end(), 0);
  fitted[0] = fitted[1] = fitted[2] = 1;
  fit.precompute(group, fitted, rest);
  EXPECT_EQ(fit.droppedGroups(), 2u);
  EXPECT_EQ(std::count(fit.placed().begin(), fit.placed().end(), 1), 0);
}

TEST(RigidBones, GroupsAreTheSameOnAnyThreadCountAndCountEveryHeldVoxel) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 41);
  LabelGrid keys(grid.geometry(), 0);
  std::int64_t keyed = 0;
  for (std::size_t v = 0; v < keys.labels().size(); ++v)
    if (const Label l = grid.labels()[v]; l != 0) {
      keys.labels()[v] = Label((1 + l % 2) * kBoneKeyStride + l);
      ++keyed;
    }
  // A mesh that leaves some voxel centres out: the six tets of every seventh
  // voxel (tets 6 v to 6 v + 5) dropped.
  const TetMesh all = tetrahedralizeVoxels(grid, {.includeBackground = false});
  TetMesh tm;
  tm.positions = all.positions;
  for (std::size_t t = 0; t < all.tetCount(); ++t)
    if (t / 6 % 7 != 3) {
      tm.tets.push_back(all.tets[t]);
      tm.labels.push_back(all.labels[t]);
    }
  RigidBoneGroups one;
  {
    const ScopedWorkerThreads scope(1);
    one = rigidBoneGroups(tm, keys, 1);
  }
  const ScopedWorkerThreads scope(3);
  const RigidBoneGroups three = rigidBoneGroups(tm, keys, 1);
  EXPECT_GT(one.uncoveredVoxels, 0);
  EXPECT_EQ(three.uncoveredVoxels, one.uncoveredVoxels);
  EXPECT_EQ(three.vertexGroup, one.vertexGroup);
  EXPECT_EQ(three.groupPart, one.groupPart);
  ASSERT_EQ(three.tetVoxels.size(), one.tetVoxels.size());
  std::int64_t held = 0;
  for (std::size_t k = 0; k < one.tetVoxels.size(); ++k) {
    const RigidBoneGroups::TetVoxels &a = one.tetVoxels[k], &b = three.tetVoxels[k];
    ASSERT_EQ(a.tet, b.tet);
    ASSERT_EQ(a.key, b.key);
    ASSERT_EQ(a.voxels, b.voxels);
    if (k > 0) {
      const RigidBoneGroups::TetVoxels& p = one.tetVoxels[k - 1];
      ASSERT_TRUE(p.tet < a.tet || (p.tet == a.tet && p.key < a.key)) << k;
    }
    held += a.voxels;
  }
  EXPECT_EQ(held + one.uncoveredVoxels, keyed);
}

// The largest distance of a part's rigid TM vertices from where its motion sends them.
double rigidError(const DeformationPipeline& pipeline, const PartMotions& motions, Part part, std::size_t& count) {
  const RigidBoneGroups& g = pipeline.rigidBones();
  const TetMesh& tm = pipeline.transferMesh();
  double worst = 0.0;
  count = 0;
  for (std::size_t v = 0; v < tm.vertexCount(); ++v) {
    const std::int32_t k = g.vertexGroup[v];
    if (k < 0 || g.groupPart[std::size_t(k)] != Label(part)) continue;
    ++count;
    worst = std::max(worst, (pipeline.deformedTransferMesh()[v] - motions[std::size_t(part)] * tm.positions[v]).norm());
  }
  return worst;
}

TEST(RigidBones, JointPoseMovesEachPartsBonesWithItsKinematics) {
  const LabelGrid grid = synthesize(SynthKind::SkeletonFigure, 128);
  const OrganTable organs = synthOrganTable(SynthKind::SkeletonFigure);
  const Pose pose = parsePose(R"({"joints": {"right_shoulder": {"abduction": 30}, "right_elbow": {"flexion": 45}}})", "pose.json");
  const Skeleton s = buildSkeleton(grid, organs, {});
  const PartMotions motions = partMotions(s.joints, pose.joints);
  double soft = 0.0;
  for (const bool rigid : {false, true}) {
    PipelineOptions options = skeletalPoseOptions(pose, "pose.json", grid, organs, {}, std::nullopt);
    options.envelope = false;
    options.rigidBones = rigid;
    options.sizingFraction = 0.02;  // a TM that resolves the figure's bones
    DeformationPipeline pipeline(grid, options);
    pipeline.deform();
    ASSERT_FALSE(pipeline.rigidBones().empty());
    for (const Part part : {Part::RightUpperArm, Part::RightForearm, Part::RightHand}) {
      std::size_t count = 0;
      const double error = rigidError(pipeline, motions, part, count);
      if (part == Part::RightUpperArm) {
        EXPECT_GT(count, 3u);
      }
      if (rigid) {
        EXPECT_LT(error, 1e-9) << partName(part) << ", " << count << " vertices";
      } else {
        soft = std::max(soft, error);
      }
    }
    // Half-way, the rigid parts are half-way along their screw.
    if (rigid) {
      pipeline.deform(0.5);
      const PoseTransform t = options.partMotions[std::size_t(Part::RightUpperArm)];
      const TetMesh& tm = pipeline.transferMesh();
      for (std::size_t v = 0; v < tm.vertexCount(); ++v) {
        const std::int32_t k = pipeline.rigidBones().vertexGroup[v];
        if (k >= 0 && pipeline.rigidBones().groupPart[std::size_t(k)] == Label(Part::RightUpperArm)) {
          EXPECT_LT((pipeline.deformedTransferMesh()[v] - t.apply(tm.positions[v], 0.5)).norm(), 1e-9);
        }
      }
    }
    const std::vector<BoneRigidity> bones = measureBoneRigidity(pipeline.rigidBones(), pipeline.transferMesh(), pipeline.deformedTransferMesh());
    ASSERT_FALSE(bones.empty());
    for (const BoneRigidity& b : bones) {
      EXPECT_GT(b.vertices, 3u);
      EXPECT_GT(b.restVolumeMm3, 0.0);
    }
  }
  // Without the constraint the soft deformation bends the bones' tets.
  EXPECT_GT(soft, 0.05);
}

TEST(Collisions, TissueOfTwoPartsMovedOntoEachOtherIsCounted) {
  GridGeometry g;
  g.dims = {30, 12, 12};
  LabelGrid parts(g, 0);
  for (std::int64_t k = 1; k < 11; ++k)
    for (std::int64_t j = 1; j < 11; ++j)
      for (std::int64_t i = 1; i < 29; ++i) parts.at(i, j, k) = i < 15 ? 1 : 2;
  TetMesh tm;
  // One tet in each part.
  tm.positions = {{2, 2, 2}, {12, 2, 2}, {2, 10, 2}, {2, 2, 10}, {17, 2, 2}, {27, 2, 2}, {17, 10, 2}, {17, 2, 10}};
  tm.tets = {{0, 1, 2, 3}, {4, 5, 6, 7}};
  tm.labels = {1, 1};
  const Collisions atRest = findCollisions(tm, tm.positions, parts, g, true);
  EXPECT_EQ(atRest.voxels, 0);
  EXPECT_GT(atRest.bodyVoxels, 100);
  EXPECT_TRUE(atRest.pairs.empty());
  // Part 2's tet slid onto part 1's.
  std::vector<Eigen::Vector3d> moved = tm.positions;
  for (std::size_t v = 4; v < 8; ++v) moved[v].x() -= 15.0;
  const Collisions c = findCollisions(tm, moved, parts, g, true);
  EXPECT_GT(c.voxels, 50);
  ASSERT_EQ(c.pairs.size(), 1u);
  EXPECT_EQ(c.pairs[0].partA, 1);
  EXPECT_EQ(c.pairs[0].partB, 2);
  EXPECT_EQ(c.pairs[0].voxels, c.voxels);
  EXPECT_EQ(std::count(c.mask.labels().begin(), c.mask.labels().end(), Label(1)), c.voxels);
  EXPECT_GT(c.bodyFraction(), 0.0);
  EXPECT_LE(c.bodyFraction(), 1.0);
}

// Two blocks of 10 x 10 x 10 voxels (1 mm), 5 voxels apart, each covered by
// a box of six tets: at rest they do not meet; part 2 slid against part 1,
// they meet over one 10 x 10 face, 100 mm2 of contact. Blocks that touch at
// rest (a joint's interface) meet on no contact however they turn.
TEST(Collisions, PartsMovedAgainstEachOtherMeetOnAContact) {
  GridGeometry g;
  g.dims = {30, 12, 12};
  LabelGrid parts(g, 0);
  for (std::int64_t k = 1; k < 11; ++k)
    for (std::int64_t j = 1; j < 11; ++j)
      for (std::int64_t i = 0; i < 30; ++i)
        if (i >= 2 && i < 12) parts.at(i, j, k) = 1;
        else if (i >= 17 && i < 27) parts.at(i, j, k) = 2;
  TetMesh tm;
  // A box [lo, hi] as six tets about its diagonal.
  const auto box = [&](const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    const std::int32_t base = std::int32_t(tm.positions.size());
    for (int c = 0; c < 8; ++c) tm.positions.push_back({c & 1 ? hi.x() : lo.x(), c & 2 ? hi.y() : lo.y(), c & 4 ? hi.z() : lo.z()});
    for (const Tet& t : std::vector<Tet>{{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}}) {
      tm.tets.push_back({base + t[0], base + t[1], base + t[2], base + t[3]});
      tm.labels.push_back(1);
    }
  };
  box({1.5, 0.5, 0.5}, {11.5, 10.5, 10.5});
  box({16.5, 0.5, 0.5}, {26.5, 10.5, 10.5});
  EXPECT_TRUE(findCollisions(tm, tm.positions, parts, g).contacts.empty());
  std::vector<Eigen::Vector3d> moved = tm.positions;
  for (std::size_t v = 8; v < 16; ++v) moved[v].x() -= 5.0;
  for (const int threads : {1, 3}) {
    const Collisions c = findCollisions(tm, moved, parts, g, false, threads);
    EXPECT_EQ(c.voxels, 0);
    ASSERT_EQ(c.contacts.size(), 1u);
    EXPECT_EQ(c.contacts[0].partA, 1);
    EXPECT_EQ(c.contacts[0].partB, 2);
    EXPECT_DOUBLE_EQ(c.contacts[0].areaMm2, 100.0);
  }
  // One block of two parts (x below 7: part 1), one box of tets turned a
  // quarter turn about z: the interface between the parts turns with it
  // and is no contact.
  LabelGrid joined(g, 0);
  for (std::int64_t k = 1; k < 11; ++k)
    for (std::int64_t j = 1; j < 11; ++j)
      for (std::int64_t i = 2; i < 12; ++i) joined.at(i, j, k) = i < 7 ? 1 : 2;
  tm = TetMesh{};
  box({1.5, 0.5, 0.5}, {11.5, 10.5, 10.5});
  const Eigen::Vector3d centre(6.5, 5.5, 5.5);
  std::vector<Eigen::Vector3d> turned = tm.positions;
  for (Eigen::Vector3d& p : turned) p = centre + Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitZ()) * (p - centre);
  EXPECT_TRUE(findCollisions(tm, turned, joined, g).contacts.empty());
}

}  // namespace
}  // namespace vox::skeleton

namespace vox::skeleton {
namespace {

// The hard postures of assets/poses (docs/POSES.md) stay valid pose
// files that compile against their phantom's skeleton (am_*, af_*), press
// no bones through each other, and the phone call puts the right hand
// beside the head by its kinematics: above the shoulder, clear of the head,
// near its side.
void expectHardPostures(const std::string& phantom) {
  const LabelGrid grid = readGrid(test::assetPath("icrp110_" + phantom + ".nii.gz"));
  const OrganTable organs = OrganTable::read(test::assetPath("icrp110_" + phantom + "_organs.dat"));
  const Skeleton s = buildSkeleton(grid, organs, {});
  std::vector<std::string> files;
  for (const std::string& name : test::articulatedPoseFiles())
    if (name.rfind(phantom + "_", 0) == 0) files.push_back(test::assetPath("poses/" + name));
  ASSERT_GE(files.size(), 2u) << phantom;
  for (const std::string& f : files) {
    const Pose pose = readPose(f);
    EXPECT_FALSE(pose.joints.empty()) << f;
    EXPECT_TRUE(pose.articulated) << f;
    const Pose compiled = compileJointPose(pose, s, f);
    EXPECT_FALSE(compiled.selections.empty()) << f;
    const auto fault = bonesThroughEachOther(s, posedJoints(s, pose.joints, f), pose.joints, 2.0);
    EXPECT_FALSE(fault) << f << ": " << *fault;
  }
  const Pose phone = readPose(test::assetPath("poses/" + phantom + "_phone_call_joints.json"));
  const PartMotions m = partMotions(posedJoints(s, phone.joints, "phone"), phone.joints);
  const GridGeometry& g = grid.geometry();
  std::vector<Eigen::Vector3d> hand, head;
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const Part p = Part(s.parts.parts.at(i, j, k));
        if (p == Part::RightHand) hand.push_back(m[std::size_t(p)] * g.voxelCenter(i, j, k));
        if (p == Part::Head) head.push_back(g.voxelCenter(i, j, k));
      }
  ASSERT_FALSE(hand.empty());
  ASSERT_FALSE(head.empty());
  Eigen::Vector3d handCentre = Eigen::Vector3d::Zero(), headCentre = Eigen::Vector3d::Zero();
  for (const auto& p : hand) handCentre += p / double(hand.size());
  for (const auto& p : head) headCentre += p / double(head.size());
  double gap = std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < hand.size(); a += 7)
    for (std::size_t b = 0; b < head.size(); b += 7) gap = std::min(gap, (hand[a] - head[b]).norm());
  std::cout << phantom << " phone call: hand centre " << (handCentre - headCentre).norm() << " mm from the head's, gap " << gap << " mm\n";
  EXPECT_GT(handCentre.z(), s.joint(JointId::RightShoulder)->centre.z()) << phantom;
  // Between the hand and the head, room for a phone and little more.
  EXPECT_GT(gap, 10.0) << phantom;
  EXPECT_LT(gap, 40.0) << phantom;
  EXPECT_LT((handCentre - headCentre).norm(), 200.0) << phantom << ": hand centre " << handCentre.transpose() << ", head centre "
                                                     << headCentre.transpose() << ", gap " << gap;
}

TEST(HardPostures, CompileOnTheAdultMaleAndThePhoneCallReachesTheHead) { expectHardPostures("am"); }
TEST(HardPostures, CompileOnTheAdultFemaleAndThePhoneCallReachesTheHead) { expectHardPostures("af"); }

}  // namespace
}  // namespace vox::skeleton
