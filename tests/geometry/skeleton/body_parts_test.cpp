// Bones from organ names, body parts by the geodesic nearest bone and joints
// from the bones, on the synthetic skeleton figure (where the joints are
// known) and on the ICRP 110 adult male: parts connected and on their side,
// the geodesic assignment keeping arm tissue off the trunk where the
// straight-line one does not, the shoulder centre inside the humeral head.

#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/skeleton/bone_overlap.h"
#include "geometry/skeleton/skeleton.h"
#include "geometry/synth.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace vox::skeleton {
namespace {

constexpr int kFigureSize = 160;

// Grid-frame mm of a normalized coordinate of the skeleton figure (voxel i
// has its centre at (i + 0.5) / size and at 2 i mm).
double figureMm(double normalized) { return 2.0 * (normalized * kFigureSize - 0.5); }

const Skeleton& figure() {
  static const Skeleton s = [] {
    const LabelGrid grid = synthesize(SynthKind::SkeletonFigure, kFigureSize);
    return buildSkeleton(grid, synthOrganTable(SynthKind::SkeletonFigure), {"figure", "figure organs", "figure parts"});
  }();
  return s;
}

bool isRightArm(Part p) { return labelGroupOf(p) == LabelGroup::RightArm; }
bool isLeftArm(Part p) { return labelGroupOf(p) == LabelGroup::LeftArm; }

// Voxels of the right arm's parts on the body's left of the mid-sagittal
// plane, and of the left arm's on its right; and legs whose centroid is on
// the wrong side (a thigh's inner tissue may cross the spine's plane).
std::int64_t partsOnTheWrongSide(const BodyParts& parts) {
  const GridGeometry& g = parts.parts.geometry();
  std::int64_t wrong = 0;
  std::array<double, kPartCount + 1> sum{};
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
    const Part p = Part(parts.parts.labels()[std::size_t(v)]);
    if (p == Part::None) continue;
    const Index3 c = g.ijk(v);
    const double right = (g.voxelCenter(c[0], c[1], c[2]) - parts.frame.midpoint).dot(parts.frame.right);
    sum[std::size_t(p)] += right;
    wrong += isRightArm(p) ? right < 0 : isLeftArm(p) ? right > 0 : 0;
  }
  for (const Part p : {Part::RightThigh, Part::RightLowerLeg, Part::RightFoot}) wrong += sum[std::size_t(p)] < 0;
  for (const Part p : {Part::LeftThigh, Part::LeftLowerLeg, Part::LeftFoot}) wrong += sum[std::size_t(p)] > 0;
  return wrong;
}

TEST(Bones, FromTheIcrpOrganNames) {
  for (const char* table : {"icrp110_am_organs.dat", "icrp110_af_organs.dat"}) {
    const OrganTable organs = OrganTable::read(test::assetPath(table));
    std::array<int, kBoneCount + 1> labels{};
    for (const auto& [id, organ] : organs.organs()) ++labels[std::size_t(classifyBone(organ.name))];
    for (int b = 1; b <= kBoneCount; ++b) EXPECT_GT(labels[std::size_t(b)], 0) << table << ": no label of " << boneName(Bone(b));
  }
  EXPECT_EQ(classifyBone("Humeri, upper half, spongiosa"), Bone::Humerus);
  EXPECT_EQ(classifyBone("Tibiae, fibulae and patellae, cortical"), Bone::LowerLegBones);
  EXPECT_EQ(classifyBone("Wrists and hand bones, cortical"), Bone::HandBones);
  EXPECT_EQ(classifyBone("Cervical spine, spongiosa"), Bone::CervicalSpine);
  EXPECT_EQ(classifyBone("Kidney, left, pelvis"), Bone::None);
  EXPECT_EQ(classifyBone("Cartilage, arms"), Bone::None);
  EXPECT_EQ(classifyBone("Muscle, arms"), Bone::None);
  EXPECT_EQ(classifyBone("Skin, legs"), Bone::None);
  EXPECT_EQ(sideInName("Humerus, right"), Side::Right);
  EXPECT_EQ(sideInName("Humeri, upper half, cortical"), Side::Axial);
  EXPECT_FALSE(namesBones(synthOrganTable(SynthKind::NestedSpheres)));
  EXPECT_THROW(requireBones(synthOrganTable(SynthKind::NestedSpheres), "spheres.dat"), InputError);
}

TEST(BodyParts, SkeletonFigurePartsAreConnectedAndOnTheirSide) {
  const Skeleton& s = figure();
  const BodyParts& p = s.parts;
  EXPECT_TRUE(p.frame.fromBones);
  EXPECT_NEAR(p.frame.right.x(), -1.0, 1e-12);  // the ICRP storage convention, found from the bones
  EXPECT_NEAR(p.frame.anterior.y(), -1.0, 1e-12);
  EXPECT_NEAR(p.frame.superior.z(), 1.0, 1e-12);
  const std::array<int, kPartCount + 1> components = partComponents(p.parts);
  for (int part = 1; part <= kPartCount; ++part) {
    EXPECT_GT(p.voxels[std::size_t(part)], 0) << partName(Part(part));
    EXPECT_EQ(components[std::size_t(part)], 1) << partName(Part(part));
  }
  EXPECT_EQ(partsOnTheWrongSide(p), 0);
  // Below the shoulders the arms lie against the trunk skin on skin: no
  // voxel of the trunk's box (x within 0.18..0.42) goes to an arm.
  const GridGeometry& g = p.parts.geometry();
  std::int64_t armInTrunk = 0, trunkVoxels = 0;
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const double x = (double(i) + 0.5) / kFigureSize, z = (double(k) + 0.5) / kFigureSize;
        if (x < 0.18 || x >= 0.42 || z < 0.46 || z >= 0.69) continue;
        const Part part = Part(p.parts.at(i, j, k));
        if (part == Part::None) continue;
        ++trunkVoxels;
        armInTrunk += labelGroupOf(part) == LabelGroup::RightArm || labelGroupOf(part) == LabelGroup::LeftArm;
      }
  EXPECT_GT(trunkVoxels, 10000);
  EXPECT_EQ(armInTrunk, 0);
  // Every foreground voxel has a part, and only those.
  const LabelGrid grid = synthesize(SynthKind::SkeletonFigure, kFigureSize);
  for (std::size_t v = 0; v < grid.labels().size(); ++v) ASSERT_EQ(grid.labels()[v] != 0, p.parts.labels()[v] != 0) << v;
}

TEST(Joints, SkeletonFigureJointsWhereTheyWereBuilt) {
  const Skeleton& s = figure();
  ASSERT_EQ(s.joints.size(), std::size_t(kJointCount));
  const SkeletonFigureBones truth;
  const double voxel = 2.0;
  for (int side = 0; side < 2; ++side) {
    const Joint* shoulder = s.joint(side == 0 ? JointId::RightShoulder : JointId::LeftShoulder);
    const Joint* hip = s.joint(side == 0 ? JointId::RightHip : JointId::LeftHip);
    ASSERT_TRUE(shoulder && hip);
    const Eigen::Vector3d shoulderTruth(figureMm(truth.humeralHeadX[side]), figureMm(truth.humeralHeadY), figureMm(truth.humeralHeadZ));
    const Eigen::Vector3d hipTruth(figureMm(truth.femoralHeadX[side]), figureMm(truth.femoralHeadY), figureMm(truth.femoralHeadZ));
    EXPECT_EQ(shoulder->method, "sphere fit");
    EXPECT_EQ(hip->method, "sphere fit");
    EXPECT_LT((shoulder->centre - shoulderTruth).norm(), 0.75 * voxel) << shoulder->centre.transpose();
    EXPECT_LT((hip->centre - hipTruth).norm(), 0.75 * voxel) << hip->centre.transpose();
    // Voxel centres lie inside the surface: the fit is short by up to a voxel.
    EXPECT_NEAR(shoulder->radius, 2.0 * truth.humeralHeadRadius * kFigureSize, voxel);
    EXPECT_NEAR(hip->radius, 2.0 * truth.femoralHeadRadius * kFigureSize, voxel);
    // Elbow and knee hinges from the epicondyles and condyles: left-right,
    // pointing to the body's right (-x).
    for (const JointId id : {side == 0 ? JointId::RightElbow : JointId::LeftElbow, side == 0 ? JointId::RightKnee : JointId::LeftKnee}) {
      const Joint* j = s.joint(id);
      ASSERT_TRUE(j);
      EXPECT_EQ(j->axisMethod, "bone end width") << j->kind().name;
      EXPECT_GT(-j->leftRight.x(), 0.99) << j->kind().name;
      EXPECT_LT(j->longAxis.z(), -0.99) << j->kind().name;  // limbs hang down
    }
  }
  // The elbow lies at the humerus' distal end, between it and the forearm bones.
  const Joint* elbow = s.joint(JointId::RightElbow);
  EXPECT_NEAR(elbow->centre.z(), figureMm(0.627), 2.0 * voxel);
  EXPECT_NEAR(elbow->centre.x(), figureMm(truth.humeralHeadX[0]), voxel);
}

// The distance (mm) from p to the nearest voxel centre of `bone`.
double nearestVoxelMm(const GridGeometry& g, const BoneVoxels& bone, const Eigen::Vector3d& p) {
  double d = std::numeric_limits<double>::infinity();
  for (const std::int64_t v : bone.voxels) {
    const Index3 c = g.ijk(v);
    d = std::min(d, (g.voxelCenter(c[0], c[1], c[2]) - p).norm());
  }
  return d;
}

// The wrists' centres lie in the carpus: among the hand's bones, nearer
// them than the forearm bones, which lie the joint's radius away (the
// distal-end estimate cleared over the wrist's range lay 52 mm up the
// forearm, 3 mm from the forearm bones and 45 mm from the hand's).
void expectWristsInTheCarpus(const GridGeometry& g, const Skeleton& s) {
  for (const JointId id : {JointId::RightWrist, JointId::LeftWrist}) {
    const Joint* j = s.joint(id);
    ASSERT_TRUE(j);
    EXPECT_EQ(j->method, "centroid of the carpus") << j->kind().name;
    const BoneVoxels* handBones = s.parts.find(Bone::HandBones, j->kind().side);
    const BoneVoxels* forearmBones = s.parts.find(Bone::ForearmBones, j->kind().side);
    ASSERT_TRUE(handBones && forearmBones);
    const double hand = nearestVoxelMm(g, *handBones, j->centre), forearm = nearestVoxelMm(g, *forearmBones, j->centre);
    std::cout << j->kind().name << ": " << hand << " mm from the hand's bones, " << forearm << " from the forearm's\n";
    EXPECT_LT(hand, 0.5 * g.spacing.norm()) << j->kind().name;
    EXPECT_GT(forearm, 2.0 * g.spacing.minCoeff()) << j->kind().name;
    EXPECT_NEAR(j->radius, forearm, 1e-9) << j->kind().name;
  }
}

// Each joint turned alone through its range, every 10 degrees of each of
// its degrees of freedom from the range's start, and its end: the largest overlap of its own two parts' bones
// (bone_overlap.h; a share of the smaller part's bones, %), which a pose
// refuses above 2 % (kMaxBoneOverlapPercent). Where the
// trunk itself is in the way the shoulders' abduction is left out: past 160
// degrees (the scapula stays with the trunk, and the humerus meets the
// acromion) and below 0 (the hanging arm pressed through the ribs, which
// the pose refuses: checked at -30 degrees).
void expectJointsTurnClear(const Skeleton& s, const std::string& phantom) {
  for (const Joint& j : s.joints) {
    const JointKind& k = j.kind();
    for (int d = 0; d < kDofCount; ++d) {
      if (!k.dofNames[std::size_t(d)]) continue;
      double worst = 0.0, at = 0.0, adducted = 0.0;
      for (double step = k.range[std::size_t(d)][0]; step < k.range[std::size_t(d)][1] + 10.0; step += 10.0) {
        const double deg = std::min(step, k.range[std::size_t(d)][1]);  // the range's ends too
        if (deg == 0.0) continue;
        std::array<double, kDofCount> angles{};
        angles[std::size_t(d)] = deg;
        Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
        turn.linear() = j.rotation(angles);
        turn.translation() = j.centre - turn.linear() * j.centre;
        std::array<Eigen::Isometry3d, kPartCount + 1> motions;
        motions.fill(Eigen::Isometry3d::Identity());
        for (const Part p : partSubtree(k.child)) motions[std::size_t(p)] = turn;
        for (const BoneOverlap& o : boneOverlaps(s.parts, s.joints, motions)) {
          const bool own = (o.first == k.parent && o.second == k.child) || (o.first == k.child && o.second == k.parent);
          const bool shoulder = k.parent == Part::Trunk && k.dofNames[std::size_t(d)] == std::string("abduction");
          if (own && shoulder && deg == -30.0) adducted = 100.0 * o.fractionOfSmaller;
          if (own && !(shoulder && (deg > 160.0 || deg < 0.0)) && 100.0 * o.fractionOfSmaller > worst) {
            worst = 100.0 * o.fractionOfSmaller;
            at = deg;
          }
        }
      }
      std::cout << phantom << " " << k.name << " " << k.dofNames[std::size_t(d)] << ": at most " << worst << " % of bone overlap (" << at
                << " degrees)\n";
      EXPECT_LE(worst, 2.0) << phantom << " " << k.name << " " << k.dofNames[std::size_t(d)] << " at " << at << " degrees";
      if (k.parent == Part::Trunk && k.dofNames[std::size_t(d)] == std::string("abduction")) {
        std::cout << phantom << " " << k.name << " abduction -30: " << adducted << " %\n";
        EXPECT_GT(adducted, 2.0) << phantom << " " << k.name;
      }
    }
  }
}

TEST(Joints, SphereFitRecoversASphere) {
  std::vector<Eigen::Vector3d> points;
  for (int a = 0; a < 12; ++a)
    for (int b = 1; b < 6; ++b) {
      const double theta = a * M_PI / 6.0, phi = b * M_PI / 12.0;  // a cap of 75 degrees
      points.push_back(Eigen::Vector3d(3, -2, 7) + 25.0 * Eigen::Vector3d(std::sin(phi) * std::cos(theta), std::sin(phi) * std::sin(theta), std::cos(phi)));
    }
  const auto fit = fitSphere(points);
  ASSERT_TRUE(fit);
  EXPECT_LT((fit->centre - Eigen::Vector3d(3, -2, 7)).norm(), 1e-8);
  EXPECT_NEAR(fit->radius, 25.0, 1e-8);
  EXPECT_FALSE(fitSphere(std::vector<Eigen::Vector3d>(3, Eigen::Vector3d::Zero())));
}

TEST(BodyParts, BadInput) {
  const LabelGrid grid = synthesize(SynthKind::SkeletonFigure, 96);
  const OrganTable organs = synthOrganTable(SynthKind::SkeletonFigure);
  try {
    buildSkeleton(grid, synthOrganTable(SynthKind::NestedSpheres), {"g.nii", "spheres.dat", "p.nii"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("spheres.dat: the organ table names no bones", 0), 0u) << e.what();
  }
  // A table that names bones the grid does not hold.
  OrganTable other;
  other.add({200, "Femora, cortical", 2, 1.92});
  EXPECT_THROW(buildSkeleton(grid, other, {"g.nii", "o.dat", "p.nii"}), InputError);
  LabelGrid parts = bodyParts(grid, organs, "g.nii", "o.dat").parts;
  LabelGrid small(GridGeometry{{4, 4, 4}}, 1);
  EXPECT_THROW(buildSkeleton(grid, organs, {"g.nii", "o.dat", "p.nii"}, small), InputError);
  parts.labels()[100] = 17;
  try {
    buildSkeleton(grid, organs, {"g.nii", "o.dat", "p.nii"}, parts);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("p.nii: has value 17", 0), 0u) << e.what();
  }
  // A corrected grid is taken as it is.
  parts.labels()[100] = Label(Part::Trunk);
  const Skeleton user = buildSkeleton(grid, organs, {"g.nii", "o.dat", "p.nii"}, parts);
  EXPECT_EQ(user.parts.parts.labels(), parts.labels());
  EXPECT_EQ(user.joints.size(), std::size_t(kJointCount));
}

// The adult male: 254 x 127 x 222 voxels of 2.137 x 2.137 x 8 mm, arms
// against the trunk, skin on skin, below the armpits.
TEST(BodyParts, AdultMale) {
  const LabelGrid grid = readGrid(test::assetPath("icrp110_am.nii.gz"));
  const OrganTable organs = OrganTable::read(test::assetPath("icrp110_am_organs.dat"));
  const Skeleton s = buildSkeleton(grid, organs, {"am", "am organs", "am parts"});
  std::cout << "adult male skeleton: " << s.seconds << " s\n";
  ASSERT_EQ(s.joints.size(), std::size_t(kJointCount));
  EXPECT_TRUE(s.parts.frame.fromBones);
  EXPECT_NEAR(s.parts.frame.right.x(), -1.0, 1e-12);
  const std::array<int, kPartCount + 1> components = partComponents(s.parts.parts);
  for (int part = 1; part <= kPartCount; ++part) {
    EXPECT_GT(s.parts.voxels[std::size_t(part)], 1000) << partName(Part(part));
    EXPECT_EQ(components[std::size_t(part)], 1) << partName(Part(part));
  }
  EXPECT_EQ(partsOnTheWrongSide(s.parts), 0);

  // Straight-line nearest bones put trunk tissue beside the arms (across
  // the air of the armpit, through the skin where they touch) into the
  // arms; the geodesic assignment keeps it in the trunk.
  const LabelGrid euclidean = euclideanBodyParts(grid, s.parts);
  const std::array<int, kPartCount + 1> euclideanComponents = partComponents(euclidean);
  const GridGeometry& g = grid.geometry();
  const double shoulderZ = s.joint(JointId::RightShoulder)->centre.z();
  std::int64_t differ = 0, trunkToArm = 0, belowShoulders = 0;
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
    const Label a = s.parts.parts.labels()[std::size_t(v)], b = euclidean.labels()[std::size_t(v)];
    differ += a != b;
    if (Part(a) != Part::Trunk || !(isRightArm(Part(b)) || isLeftArm(Part(b)))) continue;
    ++trunkToArm;
    const Index3 c = g.ijk(v);
    const double z = g.voxelCenter(c[0], c[1], c[2]).z();
    belowShoulders += z < shoulderZ && z > shoulderZ - 400.0;
  }
  std::cout << "adult male: " << differ << " voxels differ from the straight-line assignment, " << trunkToArm
            << " trunk voxels it puts in an arm (" << belowShoulders << " within 400 mm below the shoulders); its arm parts have";
  for (const Part p : {Part::RightUpperArm, Part::RightForearm, Part::RightHand, Part::LeftUpperArm, Part::LeftForearm, Part::LeftHand})
    std::cout << " " << euclideanComponents[std::size_t(p)];
  std::cout << " pieces\n";
  int pieces = 0;
  for (const Part p : {Part::RightUpperArm, Part::RightForearm, Part::RightHand, Part::LeftUpperArm, Part::LeftForearm, Part::LeftHand})
    pieces += euclideanComponents[std::size_t(p)];
  EXPECT_GT(pieces, 6);
  EXPECT_GT(trunkToArm, 1000);
  EXPECT_GT(belowShoulders, 0.9 * double(trunkToArm));

  // Shoulders: a sphere of 20-30 mm fitted to the humeral head, its centre
  // inside the head (within half a voxel diagonal, 4.3 mm, of a humerus
  // voxel centre), and within 5 mm of the centre the box pose
  // assets/poses/am_right_arm_raised_45.json turns the right arm about.
  const double halfDiagonal = 0.5 * grid.spacing().norm();
  for (const JointId id : {JointId::RightShoulder, JointId::LeftShoulder, JointId::RightHip, JointId::LeftHip}) {
    const Joint* j = s.joint(id);
    ASSERT_TRUE(j);
    EXPECT_EQ(j->method, "sphere fit") << j->kind().name;
    EXPECT_GT(j->radius, 20.0) << j->kind().name;
    EXPECT_LT(j->radius, 30.0) << j->kind().name;
    const bool arm = id == JointId::RightShoulder || id == JointId::LeftShoulder;
    const BoneVoxels* bone = s.parts.find(arm ? Bone::Humerus : Bone::Femur, j->kind().side);
    ASSERT_TRUE(bone);
    EXPECT_LT(nearestVoxelMm(grid.geometry(), *bone, j->centre), halfDiagonal) << j->kind().name;
  }
  EXPECT_LT((s.joint(JointId::RightShoulder)->centre - Eigen::Vector3d(97, 145, 1450)).norm(), 5.0);

  // Elbows and knees: turned about their centres through every 10 degrees
  // of the flexion range, the forearm bones and the tibiae stay out of the
  // humerus and the femur. At the humerus' and femur's distal ends (the
  // estimate before the centre is cleared) the forearm bones cut into the
  // humerus by 1 to 181 voxels per angle, the tibiae into the femur by up
  // to 496. The cleared centre lies in front of the humeral shaft and
  // behind the femoral one, as the trochlea and the condyles do.
  for (const JointId id : {JointId::RightElbow, JointId::LeftElbow, JointId::RightKnee, JointId::LeftKnee}) {
    const Joint* j = s.joint(id);
    ASSERT_TRUE(j);
    EXPECT_EQ(j->method, "distal end, cleared over flexion") << j->kind().name;
    const bool arm = isElbow(id);
    const BoneVoxels* parent = s.parts.find(arm ? Bone::Humerus : Bone::Femur, j->kind().side);
    const BoneVoxels* child = s.parts.find(arm ? Bone::ForearmBones : Bone::LowerLegBones, j->kind().side);
    ASSERT_TRUE(parent && child);
    const std::vector<std::int64_t>& parentVoxels = parent->voxels;  // sorted
    const GridGeometry& g = grid.geometry();
    int worst = 0;
    for (double deg = 10.0; deg <= j->kind().range[0][1]; deg += 10.0) {
      const Eigen::Matrix3d r = j->rotation({deg, 0.0, 0.0});
      int overlaps = 0;
      for (const std::int64_t v : child->voxels) {
        const Index3 c = g.ijk(v);
        const Eigen::Vector3d q = g.continuousIndex(j->centre + r * (g.voxelCenter(c[0], c[1], c[2]) - j->centre));
        const std::int64_t qi = std::llround(q[0]), qj = std::llround(q[1]), qk = std::llround(q[2]);
        overlaps += g.contains(qi, qj, qk) && std::binary_search(parentVoxels.begin(), parentVoxels.end(), g.index(qi, qj, qk));
      }
      worst = std::max(worst, overlaps);
    }
    std::cout << j->kind().name << ": at most " << worst << " voxels of the child's bone in the parent's over the flexion range\n";
    EXPECT_LE(worst, 3) << j->kind().name;
    // The centre in front of the parent bone's axis (its principal axis) at
    // an elbow, behind it at a knee.
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const std::int64_t v : parent->voxels) {
      const Index3 c = g.ijk(v);
      centroid += g.voxelCenter(c[0], c[1], c[2]) / double(parent->voxels.size());
    }
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const std::int64_t v : parent->voxels) {
      const Index3 c = g.ijk(v);
      const Eigen::Vector3d d = g.voxelCenter(c[0], c[1], c[2]) - centroid;
      cov += d * d.transpose();
    }
    const Eigen::Vector3d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(2);
    const Eigen::Vector3d off = (j->centre - centroid) - (j->centre - centroid).dot(axis) * axis;
    const double front = off.dot(j->anterior);
    std::cout << j->kind().name << ": centre " << front << " mm in front of the parent bone's axis\n";
    if (arm)
      EXPECT_GT(front, 0.0) << j->kind().name;
    else
      EXPECT_LT(front, 0.0) << j->kind().name;
  }

  // The ankles and the neck are cleared the same way, over every degree of
  // freedom they have.
  for (const JointId id : {JointId::RightAnkle, JointId::LeftAnkle, JointId::Neck})
    EXPECT_NE(s.joint(id)->method.find(", cleared over flexion"), std::string::npos) << s.joint(id)->kind().name << ": " << s.joint(id)->method;
  expectWristsInTheCarpus(grid.geometry(), s);
  expectJointsTurnClear(s, "adult male");
}

// The adult female: 299 x 137 x 348 voxels of 1.775 x 1.775 x 4.84 mm.
TEST(BodyParts, AdultFemale) {
  const LabelGrid grid = readGrid(test::assetPath("icrp110_af.nii.gz"));
  const OrganTable organs = OrganTable::read(test::assetPath("icrp110_af_organs.dat"));
  const Skeleton s = buildSkeleton(grid, organs, {"af", "af organs", "af parts"});
  ASSERT_EQ(s.joints.size(), std::size_t(kJointCount));
  expectWristsInTheCarpus(grid.geometry(), s);
  expectJointsTurnClear(s, "adult female");
}

}  // namespace
}  // namespace vox::skeleton
