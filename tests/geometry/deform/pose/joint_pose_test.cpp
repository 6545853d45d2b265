// Joint poses on the synthetic skeleton figure: forward kinematics composes
// down the chain (a shoulder turn carries the forearm and hand, the elbow's
// turn happens about the turned elbow), the angle conventions hold on both
// sides, the compiled pose fixes the parts at rest and moves the others, and
// the pipeline places the hand where the kinematics say. Bad input: angles
// out of range, joints and degrees of freedom that do not exist, a joint
// the skeleton lacks, bones pressed through each other (the figure's legs
// crossed; on the adult male the bundled poses pass and crossed legs do not).

#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/error.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/io/grid_io.h"
#include "geometry/synth.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace vox::skeleton {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

const Skeleton& figure() {
  static const Skeleton s = buildSkeleton(synthesize(SynthKind::SkeletonFigure, 128), synthOrganTable(SynthKind::SkeletonFigure),
                                          {"figure", "figure organs", "figure parts"});
  return s;
}

PoseJoint joint(const std::string& name, double flexion, double abduction = 0, double rotation = 0) {
  PoseJoint j;
  j.name = name;
  j.degrees = {flexion, abduction, rotation};
  return j;
}

Eigen::Vector3d turnAbout(const Eigen::Vector3d& x, const Eigen::Vector3d& axis, double degrees, const Eigen::Vector3d& centre) {
  return Eigen::AngleAxisd(degrees * kDeg, axis.normalized()) * (x - centre) + centre;
}

TEST(JointPose, ForwardKinematicsComposesDownTheChain) {
  const Skeleton& s = figure();
  const Joint& shoulder = *s.joint(JointId::RightShoulder);
  const Joint& elbow = *s.joint(JointId::RightElbow);
  const Joint& wrist = *s.joint(JointId::RightWrist);
  // Right shoulder abducted 90 degrees, elbow flexed 90: in the ICRP frame
  // (right = -x, anterior = -y) abduction of the right arm turns about +y
  // and the elbow's flexion about its hinge, pointing to -x.
  const std::vector<PoseJoint> angles = {joint("right_shoulder", 0, 90), joint("right_elbow", 90)};
  const PartMotions m = partMotions(s.joints, angles);
  const auto shoulderTurn = [&](const Eigen::Vector3d& x) { return turnAbout(x, Eigen::Vector3d::UnitY(), 90, shoulder.centre); };
  const auto elbowTurn = [&](const Eigen::Vector3d& x) { return turnAbout(x, elbow.leftRight, 90, elbow.centre); };
  for (const Part p : {Part::Trunk, Part::Pelvis, Part::Head, Part::LeftUpperArm, Part::RightThigh})
    EXPECT_TRUE(m[std::size_t(p)].matrix().isIdentity(0.0)) << partName(p);
  const Eigen::Vector3d probe(10, 20, 30);
  EXPECT_LT((m[std::size_t(Part::RightUpperArm)] * probe - shoulderTurn(probe)).norm(), 1e-9);
  // The forearm: the elbow's turn first (in the rest pose), then the shoulder's.
  EXPECT_LT((m[std::size_t(Part::RightForearm)] * probe - shoulderTurn(elbowTurn(probe))).norm(), 1e-9);
  EXPECT_TRUE(m[std::size_t(Part::RightHand)].isApprox(m[std::size_t(Part::RightForearm)], 0.0));
  // Where that puts the wrist: the upper arm points out to the body's right
  // (-x), the forearm forward (-y) from the turned elbow.
  const Eigen::Vector3d elbowPosed = m[std::size_t(Part::RightUpperArm)] * elbow.centre;
  const Eigen::Vector3d wristPosed = m[std::size_t(Part::RightForearm)] * wrist.centre;
  EXPECT_LT((elbowPosed - shoulder.centre).normalized().x(), -0.97);
  EXPECT_LT((wristPosed - elbowPosed).normalized().y(), -0.97);
  EXPECT_NEAR((wristPosed - elbowPosed).norm(), (wrist.centre - elbow.centre).norm(), 1e-9);

  // A shoulder turn alone carries the forearm and hand rigidly.
  const PartMotions carried = partMotions(s.joints, {joint("right_shoulder", 40, 20, 10)});
  EXPECT_TRUE(carried[std::size_t(Part::RightForearm)].isApprox(carried[std::size_t(Part::RightUpperArm)], 0.0));
  EXPECT_TRUE(carried[std::size_t(Part::RightHand)].isApprox(carried[std::size_t(Part::RightUpperArm)], 0.0));
}

TEST(JointPose, AngleConventionsOnBothSides) {
  const Skeleton& s = figure();
  // The posed minus the rest position of a point, for one joint's angles.
  const auto moves = [&](const std::string& name, Part part, const Eigen::Vector3d& point, double f, double a, double r) {
    const PartMotions m = partMotions(s.joints, {joint(name, f, a, r)});
    return Eigen::Vector3d(m[std::size_t(part)] * point - point);
  };
  const Eigen::Vector3d right = s.parts.frame.right, anterior = s.parts.frame.anterior;
  for (const bool isRight : {true, false}) {
    const std::string side = isRight ? "right_" : "left_";
    const double outward = isRight ? 1.0 : -1.0;  // along `right`, away from the midline
    const Joint& elbow = *s.joint(isRight ? JointId::RightElbow : JointId::LeftElbow);
    const Joint& wrist = *s.joint(isRight ? JointId::RightWrist : JointId::LeftWrist);
    const Joint& knee = *s.joint(isRight ? JointId::RightKnee : JointId::LeftKnee);
    const Joint& ankle = *s.joint(isRight ? JointId::RightAnkle : JointId::LeftAnkle);
    const Part upperArm = isRight ? Part::RightUpperArm : Part::LeftUpperArm;
    const Part forearm = isRight ? Part::RightForearm : Part::LeftForearm;
    const Part thigh = isRight ? Part::RightThigh : Part::LeftThigh;
    const Part lowerLeg = isRight ? Part::RightLowerLeg : Part::LeftLowerLeg;
    // Shoulder: abduction out to the side, flexion forward; hip the same.
    EXPECT_GT(outward * moves(side + "shoulder", upperArm, elbow.centre, 0, 30, 0).dot(right), 10.0) << side;
    EXPECT_GT(moves(side + "shoulder", upperArm, elbow.centre, 30, 0, 0).dot(anterior), 10.0) << side;
    EXPECT_GT(outward * moves(side + "hip", thigh, knee.centre, 0, 30, 0).dot(right), 10.0) << side;
    EXPECT_GT(moves(side + "hip", thigh, knee.centre, 30, 0, 0).dot(anterior), 10.0) << side;
    // Elbow flexion brings the wrist forward; knee flexion the ankle back.
    EXPECT_GT(moves(side + "elbow", forearm, wrist.centre, 60, 0, 0).dot(anterior), 10.0) << side;
    EXPECT_LT(moves(side + "knee", lowerLeg, ankle.centre, 60, 0, 0).dot(anterior), -10.0) << side;
    // Internal rotation turns a point in front of the elbow towards the midline.
    const Eigen::Vector3d front = elbow.centre + 10.0 * anterior;
    EXPECT_LT(outward * moves(side + "shoulder", upperArm, front, 0, 0, 30).dot(right), -2.0) << side;
  }
  // Neck and head: flexion brings the face down and forward, rotation turns
  // it to the right, lateral flexion tilts the head to the right.
  const Joint& head = *s.joint(JointId::Head);
  const Eigen::Vector3d nose = head.centre + 30.0 * s.parts.frame.superior + 30.0 * anterior;
  const Eigen::Vector3d top = head.centre + 40.0 * s.parts.frame.superior;
  EXPECT_LT(moves("head", Part::Head, nose, 20, 0, 0).dot(s.parts.frame.superior), -5.0);
  EXPECT_GT(moves("neck", Part::Head, top, 20, 0, 0).dot(anterior), 5.0);
  EXPECT_GT(moves("neck", Part::Head, nose, 0, 0, 30).dot(right), 5.0);
  EXPECT_GT(moves("head", Part::Head, top, 0, 10, 0).dot(right), 3.0);
}

TEST(JointPose, ScrewTransformReproducesTheMotion) {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  m.translation() = Eigen::Vector3d(10, -4, 25);
  const PoseTransform t = screwTransform(m, Eigen::Vector3d(5, 5, 5));
  for (const Eigen::Vector3d& x : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(100, -50, 20), Eigen::Vector3d(-3, 8, 1e3)})
    EXPECT_LT((t.apply(x) - m * x).norm(), 1e-9);
  // A joint's rotation: the centre on the joint's axis, no translation.
  const Joint& shoulder = *figure().joint(JointId::RightShoulder);
  const PartMotions turn = partMotions(figure().joints, {joint("right_shoulder", 0, 45)});
  const PoseTransform u = screwTransform(turn[std::size_t(Part::RightUpperArm)], shoulder.centre);
  EXPECT_NEAR(u.angleDeg, 45.0, 1e-9);
  EXPECT_LT((u.center - shoulder.centre).norm(), 1e-9);
  EXPECT_LT(u.translation.norm(), 1e-9);
}

TEST(JointPose, CompiledPoseAndThePipelineFollowTheKinematics) {
  const LabelGrid grid = synthesize(SynthKind::SkeletonFigure, 128);
  const OrganTable organs = synthOrganTable(SynthKind::SkeletonFigure);
  const Pose pose = parsePose(R"({"joints": {"right_shoulder": {"abduction": 30}, "right_elbow": {"flexion": 45}}})", "pose.json");
  const Skeleton s = buildSkeleton(grid, organs, {});
  const Pose compiled = compileJointPose(pose, s, "pose.json");
  EXPECT_TRUE(compiled.joints.empty());
  ASSERT_GE(compiled.selections.size(), 3u);
  const PoseSelection& still = compiled.selections.front();
  EXPECT_TRUE(still.fixed);
  for (const Part p : {Part::Trunk, Part::Pelvis, Part::Head, Part::LeftUpperArm, Part::RightFoot})
    EXPECT_NE(std::find(still.bodyParts.begin(), still.bodyParts.end(), Label(p)), still.bodyParts.end()) << partName(p);
  EXPECT_EQ(std::find(still.bodyParts.begin(), still.bodyParts.end(), Label(Part::RightForearm)), still.bodyParts.end());
  // Separations: the right arm from the trunk it lies against, below the shoulder.
  ASSERT_FALSE(compiled.separations.empty());
  EXPECT_EQ(compiled.separations[0].cage.groupA, Label(LabelGroup::RightArm));
  EXPECT_EQ(compiled.separations[0].cage.groupB, Label(LabelGroup::Trunk));
  EXPECT_LT(compiled.separations[0].cage.region->max().z(), s.joint(JointId::RightShoulder)->centre.z());

  // Through the pipeline: transfer-mesh vertices in the right hand, beyond
  // the turned joints' zones, end where the kinematics send them (the cage
  // moves their region rigidly).
  PipelineOptions options = skeletalPoseOptions(pose, "pose.json", grid, organs, {}, std::nullopt);
  options.envelope = false;
  DeformationPipeline pipeline(grid, options);
  pipeline.deform();
  const PartMotions m = partMotions(s.joints, pose.joints);
  const TetMesh& tm = pipeline.transferMesh();
  std::vector<double> error;
  double moved = 0.0;
  for (std::size_t v = 0; v < tm.vertexCount(); ++v) {
    Index3 c;
    if (!grid.geometry().voxelAt(tm.positions[v], c)) continue;
    const Part part = Part(s.parts.parts.at(c[0], c[1], c[2]));
    if (part != Part::RightHand) continue;
    const Eigen::Vector3d expected = m[std::size_t(part)] * tm.positions[v];
    error.push_back((pipeline.deformedTransferMesh()[v] - expected).norm());
    moved = std::max(moved, (expected - tm.positions[v]).norm());
  }
  ASSERT_GT(error.size(), 3u);
  std::sort(error.begin(), error.end());
  EXPECT_GT(moved, 30.0);
  EXPECT_LT(error[error.size() / 2], 2.0) << "median of " << error.size() << " hand vertices, moved up to " << moved << " mm";
}

TEST(JointPose, BadInput) {
  const auto fault = [](const std::string& json) {
    try {
      parsePose(json, "p.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(fault(R"({"joints": {"right_elbow": {"flexion": 170}}})"),
            "p.json: joint 'right_elbow' flexion 170 is outside its range [0, 150] degrees");
  EXPECT_EQ(fault(R"({"joints": {"right_knee": {"flexion": -10}}})"), "p.json: joint 'right_knee' flexion -10 is outside its range [0, 140] degrees");
  EXPECT_NE(fault(R"({"joints": {"right_elbow": {"abduction": 10}}})").find("joint 'right_elbow' has no 'abduction'"), std::string::npos);
  EXPECT_NE(fault(R"({"joints": {"right_finger": {"flexion": 10}}})").find("unknown joint 'right_finger'"), std::string::npos);
  EXPECT_NE(fault(R"({"joints": {"right_hip": {"flexion": "10"}}})").find("must be a number"), std::string::npos);
  EXPECT_NE(fault(R"({"joints": {"right_hip": {"axis": [0, 0, 0]}}})").find("zero 'axis'"), std::string::npos);
  EXPECT_NE(fault(R"({"joints": []})").find("'joints' must be an object"), std::string::npos);
  EXPECT_NE(fault(R"({"joints": {"neck": {"flexion": 10}}, "joint_options": {"zone": "elbow"}})").find("'zone'"), std::string::npos);
  EXPECT_NE(fault(R"({"selections": [{"body_parts": ["right_wing"], "fixed": true}]})").find("unknown body part 'right_wing'"),
            std::string::npos);
  EXPECT_NE(fault(R"({"name": "no joints"})").find("missing 'selections' (or 'joints')"), std::string::npos);

  // A joint the skeleton lacks: the figure without hand bones has no wrists.
  LabelGrid grid = synthesize(SynthKind::SkeletonFigure, 48);
  const OrganTable organs = synthOrganTable(SynthKind::SkeletonFigure);
  for (Label& l : grid.labels())
    if (classifyBone(organs.find(l) ? organs.find(l)->name : "") == Bone::HandBones) l = 3;  // arm muscle
  const Skeleton s = buildSkeleton(grid, organs, {});
  EXPECT_EQ(s.joint(JointId::RightWrist), nullptr);
  try {
    compileJointPose(parsePose(R"({"joints": {"right_wrist": {"flexion": 10}}})", "p.json"), s, "p.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("p.json: the grid's skeleton has no joint 'right_wrist'", 0), 0u) << e.what();
  }
  // A joint pose without an organ table.
  EXPECT_THROW(skeletalPoseOptions(parsePose(R"({"joints": {"neck": {"flexion": 10}}})", "p.json"), "p.json", grid, std::nullopt, {},
                                   std::nullopt),
               InputError);
  // The pipeline refuses a pose whose joints were not compiled.
  PipelineOptions raw;
  raw.pose = parsePose(R"({"joints": {"neck": {"flexion": 10}}})", "p.json");
  EXPECT_THROW(DeformationPipeline(grid, raw), InputError);
}

TEST(JointPose, BonesThroughEachOther) {
  const Skeleton& s = figure();
  const auto fault = [&](const std::string& json, double maxPercent = 2.0) {
    const Pose pose = parsePose(json, "p.json");
    return bonesThroughEachOther(s, posedJoints(s, pose.joints, "p.json"), pose.joints, maxPercent);
  };
  EXPECT_FALSE(fault(R"({"joints": {"right_hip": {"flexion": 0}}})"));
  EXPECT_FALSE(fault(R"({"joints": {"right_hip": {"abduction": 20}, "right_knee": {"flexion": 30}}})"));
  // The right leg turned 30 degrees across the left.
  const auto crossed = fault(R"({"joints": {"right_hip": {"abduction": -30}, "left_shoulder": {"flexion": 10}}})");
  ASSERT_TRUE(crossed);
  EXPECT_EQ(crossed->rfind("the bones of the right_", 0), 0u) << *crossed;
  EXPECT_NE(crossed->find(" and the left_"), std::string::npos) << *crossed;
  EXPECT_NE(crossed->find("more than 2 %) with right_hip as posed"), std::string::npos) << *crossed;  // not the shoulder
  EXPECT_FALSE(fault(R"({"joints": {"right_hip": {"abduction": -30}}})", 100.0));
}

TEST(JointPose, AdultMaleBonesClearInTheBundledPosesNotWithCrossedLegs) {
  const LabelGrid grid = readGrid(test::assetPath("icrp110_am.nii.gz"));
  const OrganTable organs = OrganTable::read(test::assetPath("icrp110_am_organs.dat"));
  const Skeleton s = buildSkeleton(grid, organs, {"am", "am organs", "am parts"});
  // (The hard postures: HardPostures.*.)
  for (const std::string name : {"am_head_turned_20_joints.json", "am_left_knee_bent_30_joints.json", "am_right_arm_raised_45_joints.json"}) {
    const Pose pose = readPose(test::assetPath("poses/" + name));
    const auto fault = bonesThroughEachOther(s, posedJoints(s, pose.joints, name), pose.joints, 2.0);
    EXPECT_FALSE(fault) << name << ": " << *fault;
  }
  // Legs straight, the right hip adducted 20 degrees: the thighs pass
  // through each other by about a seventh of a thigh's bones.
  const Pose crossed = parsePose(R"({"joints": {"right_hip": {"abduction": -20}}})", "crossed.json");
  const auto fault = bonesThroughEachOther(s, posedJoints(s, crossed.joints, "crossed.json"), crossed.joints, 2.0);
  ASSERT_TRUE(fault);
  std::cout << *fault << "\n";
  EXPECT_EQ(fault->rfind("the bones of the right_thigh and the left_thigh pass through each other", 0), 0u) << *fault;
}

TEST(JointPose, RoundTrip) {
  const Pose pose = parsePose(R"({
    "joints": {"right_shoulder": {"abduction": 45, "flexion": 20, "center": [1, 2, 3]}, "left_knee": {"flexion": 30, "axis": [1, 0, 0]}},
    "joint_options": {"zone": "free", "margin_mm": 30, "groups": "organs"},
    "selections": [{"name": "hand", "body_parts": ["right_hand"], "sphere": {"center": [0, 0, 0], "radius": 5}, "fixed": true}]
  })", "p.json");
  const Pose again = parsePose(poseToJson(pose), "again.json");
  ASSERT_EQ(again.joints.size(), 2u);
  std::vector<PoseJoint> a = pose.joints, b = again.joints;
  const auto byName = [](const PoseJoint& x, const PoseJoint& y) { return x.name < y.name; };
  std::sort(a.begin(), a.end(), byName);
  std::sort(b.begin(), b.end(), byName);
  EXPECT_EQ(a, b);
  EXPECT_EQ(again.jointOptions, pose.jointOptions);
  ASSERT_EQ(again.selections.size(), 1u);
  EXPECT_EQ(again.selections[0].bodyParts, std::vector<Label>{Label(Part::RightHand)});
  EXPECT_EQ(again.selections[0].shape, SelectionShape::Sphere);
}

// "articulated": true marks a joint pose for the transfer mesh that
// resolves the skeleton; it round-trips, and a pose with selections or
// separations, or without joints, cannot carry it.
TEST(JointPose, ArticulatedKey) {
  const Pose pose = parsePose(R"({"articulated": true, "joints": {"right_elbow": {"flexion": 90}}})", "p.json");
  EXPECT_TRUE(pose.articulated);
  EXPECT_TRUE(parsePose(poseToJson(pose), "again.json").articulated);
  EXPECT_FALSE(parsePose(R"({"joints": {"right_elbow": {"flexion": 90}}})", "p.json").articulated);
  EXPECT_FALSE(parsePose(R"({"articulated": false, "joints": {"right_elbow": {"flexion": 90}}})", "p.json").articulated);
  const auto fault = [](const std::string& json) {
    try {
      parsePose(json, "p.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(fault(R"({"articulated": 1, "joints": {"right_elbow": {"flexion": 90}}})"), "p.json: 'articulated' must be true or false");
  EXPECT_EQ(fault(R"({"articulated": true, "selections": [{"box": {"min": [0,0,0], "max": [1,1,1]}, "fixed": true}]})"),
            "p.json: 'articulated' poses joints: the pose has no 'joints'");
  EXPECT_EQ(fault(R"({"articulated": true, "joints": {"right_elbow": {"flexion": 90}},
                      "selections": [{"body_parts": ["right_hand"], "fixed": true}]})"),
            "p.json: 'articulated' poses joints only: the pose's selections and separations have no place there");
}

}  // namespace
}  // namespace vox::skeleton
