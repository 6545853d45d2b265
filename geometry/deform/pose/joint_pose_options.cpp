// The pipeline options of a joint pose: the compiled pose (joint_pose.cpp)
// handed to the deformation pipeline. Apart from the compiler so that the
// compiler links without the pipeline (the joint-pose fuzz harness).

#include "geometry/deform/pose/joint_pose.h"

namespace vox::skeleton {

PipelineOptions skeletalPoseOptions(const Pose& pose, const std::string& poseSource, const LabelGrid& grid,
                                    const std::optional<OrganTable>& organs, const SkeletonSources& sources,
                                    std::optional<LabelGrid> userParts, const JointPoseOptions& options) {
  if (pose.joints.empty() && !usesBodyParts(pose) && !userParts) return poseOptions(pose, poseSource, organs);
  requireOrganTable(organs.has_value(), OrganTableNeed::Bones, poseSource);
  return skeletalPoseOptions(pose, poseSource, buildSkeleton(grid, *organs, sources, std::move(userParts)), organs, options);
}

PipelineOptions skeletalPoseOptions(const Pose& pose, const std::string& poseSource, const Skeleton& skeleton,
                                    const std::optional<OrganTable>& organs, const JointPoseOptions& options) {
  PipelineOptions o =
      poseOptions(compileJointPose(pose, skeleton, poseSource, jointPoseOptions(pose.jointOptions, options)), poseSource, organs);
  if (!pose.joints.empty()) {
    o.partMotions = partTransforms(pose, skeleton, poseSource);
  }
  o.bodyParts = skeleton.parts.parts;
  o.groupsFromParts = pose.jointOptions.groups.value_or("parts") == "parts";
  return o;
}

}  // namespace vox::skeleton
