// libFuzzer harness: a joint pose (the pose JSON with "joints" and
// "joint_options") parsed from arbitrary bytes and compiled against the
// skeleton of the synthetic stick figure, as deform does before the work:
// the range checks, forward kinematics, the compiled selections and
// separations, and each part's transform.

#include "geometry/deform/pose/joint_pose.h"
#include "geometry/error.h"
#include "geometry/synth.h"

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The figure of the seeds (tests/fuzz/make_corpus.sh: synth skeleton --size 24).
  static const vox::skeleton::Skeleton skeleton = vox::skeleton::buildSkeleton(
      vox::synthesize(vox::SynthKind::SkeletonFigure, 24), vox::synthOrganTable(vox::SynthKind::SkeletonFigure), {});
  try {
    const vox::Pose pose = vox::parsePose(std::string(reinterpret_cast<const char*>(data), size), "pose.json");
    const auto options = vox::skeleton::jointPoseOptions(pose.jointOptions);
    const vox::Pose compiled = vox::skeleton::compileJointPose(pose, skeleton, "pose.json", options);
    if (!pose.joints.empty()) vox::skeleton::partTransforms(pose, skeleton, "pose.json");
    (void)compiled;
  } catch (const vox::InputError&) {
  }
  return 0;
}
