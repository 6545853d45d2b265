#pragma once
// Joint poses: a pose file's "joints" (pose.h: angles per joint, optional
// centre and axis overrides) compiled against a grid's skeleton into what
// the deformation pipeline takes, so that box and sphere poses and joint
// poses run the same code:
//  - forward kinematics: each part's rigid motion is its parent's composed
//    with its joint's rotation about the joint centre (the trunk and pelvis
//    stay; a shoulder turn carries the forearm and hand);
//  - selections, all restricted to the cage vertices nearest some body parts
//    (PoseSelection::bodyParts): the parts at rest, fixed; then per turned
//    joint, down the tree, the parts that move with it (and no deeper turned
//    joint): their cage vertices near the joint take the parent part's
//    motion (JointZone::Parent: a shoulder cap stays with the trunk), and
//    those below the joint zone the joint's motion. The joint zone ends
//    jointMarginMm down the limb from the joint centre (a box, the "region
//    below the joint"). The pose's own selections follow, so they win where
//    they overlap;
//  - separations: per limb, below its highest turned joint, the limb's label
//    group (from the body parts: skeleton::labelGroupsOfParts) is separated
//    from every other group within nearMm of its moving parts (the cage
//    would wrap them together), inside the region below
//    the joint, so the tissue at the joint stays joined in the cage and the
//    transfer mesh. The pose's own separations follow.
// A pose's "joint_options" (pose.h) override the zone, the margin, and the
// separations' label groups ("organs": from the organ names, as box poses).

#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/skeleton/bone_overlap.h"
#include "geometry/skeleton/skeleton.h"

#include <Eigen/Geometry>
#include <array>
#include <optional>
#include <string>
#include <vector>

namespace vox::skeleton {

// Where the cage vertices of a moving part near its turned joint go.
enum class JointZone {
  Parent,  // with the parent part (a shoulder cap stays with the trunk)
  Free,    // no handle: the cage ARAP places them
  Child,   // with the moving part (the whole part turns)
};

struct JointPoseOptions {
  // Below a turned joint, the zone near it ends this far down the limb from
  // its centre, or at this fraction of the moving parts' reach when that is
  // less; separations and the moving selection start there.
  double jointMarginMm = 50.0;
  double jointMarginFraction = 0.25;
  double regionPaddingMm = 60.0;  // regions grow by this across the limb (the cage lies ~20 mm out, the inset wedge needs room)
  double nearMm = 40.0;           // groups this near the moving parts are separated from them (twice the cage's default dilation)
  JointZone jointZone = JointZone::Parent;
};

// A pose whose bones overlap (bone_overlap.h) by more than this percent of
// the smaller part's bone voxels is physically wrong (bonesThroughEachOther
// below): the deform run's default bound, and the viewer's.
inline constexpr double kMaxBoneOverlapPercent = 2.0;

// The skeleton's joints with the pose's overrides applied (a "center"
// replaces the estimated centre; an "axis" the left-right axis, made
// perpendicular to the bone and pointing to the body's right). Throws
// InputError(source, ...) for a joint the skeleton lacks or an axis along
// the bone.
std::vector<Joint> posedJoints(const Skeleton& skeleton, const std::vector<PoseJoint>& angles, const std::string& source);

// Forward kinematics: per part (index = Part), the rigid motion that takes
// its rest position to its posed one (identity for the trunk and pelvis).
using PartMotions = std::array<Eigen::Isometry3d, kPartCount + 1>;
PartMotions partMotions(const std::vector<Joint>& joints, const std::vector<PoseJoint>& angles);

// Bones the pose presses through each other: the pair of parts whose bones
// overlap most (boneOverlaps, as a share of the smaller part's bones) when
// that share exceeds maxPercent, as one line naming the two parts, the
// overlap and the turned joints between them; nullopt otherwise.
std::optional<std::string> bonesThroughEachOther(const Skeleton& skeleton, const std::vector<Joint>& joints, const std::vector<PoseJoint>& angles,
                                                 double maxPercent);
// The same with the skeleton's bones indexed once (the viewer's session).
std::optional<std::string> bonesThroughEachOther(const BoneOverlapIndex& bones, const std::vector<Joint>& joints,
                                                 const std::vector<PoseJoint>& angles, double maxPercent);

// A rigid motion as a pose transform: a screw about an axis through the
// point nearest `near` (so a single joint's rotation has its centre on the
// joint's axis and no translation).
PoseTransform screwTransform(const Eigen::Isometry3d& motion, const Eigen::Vector3d& near);

// Per part (index = Part): its forward-kinematics motion as a pose
// transform (screwTransform about the part's own joint centre), applied
// partially with the pose's fraction; the rigid bones (rigid_bones.h) follow
// it. Throws InputError(source, ...) as posedJoints.
std::vector<PoseTransform> partTransforms(const Pose& pose, const Skeleton& skeleton, const std::string& source);

// The pose without joints: compiled selections and separations (above),
// then the pose's own. Throws InputError(source, ...) as posedJoints.
Pose compileJointPose(const Pose& pose, const Skeleton& skeleton, const std::string& source, const JointPoseOptions& options = {});

// The pipeline options of a pose on `grid` (the working grid): poseOptions()
// for a pose that neither has joints nor selects by body part and gets no
// user parts grid; otherwise the skeleton is built (buildSkeleton: from the
// bones of `organs`, or `userParts`), the pose compiled against it and the
// body parts set. Throws InputError(poseSource, ...) for a joint pose
// without an organ table; buildSkeleton's and compileJointPose's errors.
PipelineOptions skeletalPoseOptions(const Pose& pose, const std::string& poseSource, const LabelGrid& grid,
                                    const std::optional<OrganTable>& organs, const SkeletonSources& sources,
                                    std::optional<LabelGrid> userParts, const JointPoseOptions& options = {});
// The same against a skeleton already built (the viewer keeps its skeleton
// to compile the joint poses loaded later): always compiles.
PipelineOptions skeletalPoseOptions(const Pose& pose, const std::string& poseSource, const Skeleton& skeleton,
                                    const std::optional<OrganTable>& organs, const JointPoseOptions& options = {});
// `base` with a pose's "joint_options" (zone, margin) applied.
JointPoseOptions jointPoseOptions(const PoseJointOptions& given, JointPoseOptions base = {});

}  // namespace vox::skeleton
