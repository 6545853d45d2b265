#pragma once
// The joint pose on the transfer mesh that resolves the skeleton, in the
// viewer: `deform --articulated`'s solve (poseArticulatedSteps) of the pose
// being edited runs on a worker thread, and once it ends its steps are shown
// one at a time, from the first step of the way to the posed mesh, through a
// ray caster of their own (the cage's live frames are not that solve). The
// solution belongs to the joint angles it was solved for: when they change,
// it is no longer shown.

#include "geometry/deform/pose/pose.h"
#include "geometry/deform/run/deform_run.h"
#include "geometry/label_grid.h"
#include "geometry/organ_table.h"

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace vox {
struct RaycastMesh;
namespace gpu {
class Context;
class RaycastKernel;
}  // namespace gpu
}  // namespace vox

namespace vox::app {

class ArticulatedView {
public:
  ArticulatedView();
  ~ArticulatedView();
  ArticulatedView(const ArticulatedView&) = delete;
  ArticulatedView& operator=(const ArticulatedView&) = delete;

  // Starts solving the joints of `pose` (grid frame) on `grid`, which must
  // outlive the solve; a running solve is cancelled first.
  void start(const LabelGrid& grid, const OrganTable& organs, const Pose& pose, const std::string& gridSource,
             const std::string& organsSource);
  bool running() const { return running_; }
  void cancel();
  void wait();
  // Steps done by the running solve, and of how many.
  int stepsDone() const { return stepsDone_; }
  int stepCount() const { return stepCount_; }

  // On the frame loop's thread, after a solve ended: takes its result and
  // builds its ray caster (the GPU context's). True when this call did.
  bool collect(gpu::Context& context, const LabelGrid& grid);
  // A solution is held and shown: its joints are `joints` (the pose being
  // edited) and showing was not turned off.
  bool shows(const std::vector<PoseJoint>& joints) const { return result_ && shown_ && joints == solvedJoints_; }
  bool held() const { return result_ != nullptr; }
  bool& shown() { return shown_; }
  // The step shown, 1 to steps() (the last: the posed mesh).
  int& step() { return step_; }
  int steps() const;
  const RaycastMesh& mesh() const;
  gpu::RaycastKernel& kernel();
  const std::vector<Eigen::Vector3d>& positions() const;
  // How the last solve ended: "articulated: N steps, ..." or its failure.
  std::string message() const;

private:
  struct Result;
  std::thread thread_;
  std::atomic<bool> running_{false}, cancel_{false};
  std::atomic<int> stepsDone_{0};
  int stepCount_ = 0;
  mutable std::mutex mutex_;
  std::unique_ptr<ArticulatedSteps> solved_;  // handed from the worker
  std::vector<PoseJoint> solvingJoints_;
  std::string message_;
  std::unique_ptr<Result> result_;
  std::vector<PoseJoint> solvedJoints_;
  bool shown_ = true;
  int step_ = 0;
};

}  // namespace vox::app
