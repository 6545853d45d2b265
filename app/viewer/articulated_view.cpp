#include "app/viewer/articulated_view.h"

#include "geometry/cancellation.h"
#include "geometry/render/raycast_scene.h"
#include "gpu/kernels/raycast.h"

#include <algorithm>
#include <cstdio>

namespace vox::app {

struct ArticulatedView::Result {
  ArticulatedSteps steps;
  std::unique_ptr<RaycastMesh> mesh;
  std::unique_ptr<gpu::RaycastKernel> kernel;
};

ArticulatedView::ArticulatedView() = default;

ArticulatedView::~ArticulatedView() {
  cancel();
  wait();
}

void ArticulatedView::cancel() {
  if (running_) cancel_ = true;
}

void ArticulatedView::wait() {
  if (thread_.joinable()) thread_.join();
}

void ArticulatedView::start(const LabelGrid& grid, const OrganTable& organs, const Pose& pose, const std::string& gridSource,
                            const std::string& organsSource) {
  cancel();
  wait();
  cancel_ = false;
  running_ = true;
  stepsDone_ = 0;
  Pose joints;
  joints.frame = pose.frame;
  joints.joints = pose.joints;
  stepCount_ = articulatedStepCount(joints);
  {
    std::lock_guard lock(mutex_);
    solved_.reset();
    solvingJoints_ = pose.joints;
    message_ = "solving on the articulated mesh";
  }
  thread_ = std::thread([this, &grid, &organs, joints = std::move(joints), gridSource, organsSource] {
    ScopedCancellation stop(cancel_);
    std::string message;
    std::unique_ptr<ArticulatedSteps> solved;
    try {
      ArticulatedStepsRequest request{grid, organs};
      request.pose = joints;
      request.gridSource = gridSource;
      request.organsSource = organsSource;
      request.poseSource = "view";
      request.warn = [](const std::string& m) { std::fprintf(stderr, "view: warning: %s\n", m.c_str()); };
      request.onStep = [this](int step) { stepsDone_ = step; };
      solved = std::make_unique<ArticulatedSteps>(poseArticulatedSteps(request));
      char text[200];
      std::snprintf(text, sizeof text, "articulated: %zu steps, %zu tets inverted in the posed mesh, smallest det J on the way %.4f",
                    solved->steps.size(), solved->report.invertedTets, solved->report.minRelativeVolume);
      message = text;
    } catch (const OperationCancelled&) {
      message = "articulated solve cancelled";
    } catch (const std::exception& e) {
      message = std::string("articulated solve failed: ") + e.what();
    }
    std::lock_guard lock(mutex_);
    solved_ = std::move(solved);
    message_ = message;
    running_ = false;
  });
}

bool ArticulatedView::collect(gpu::Context& context, const LabelGrid& grid) {
  if (running_) return false;
  std::unique_ptr<ArticulatedSteps> solved;
  {
    std::lock_guard lock(mutex_);
    if (!solved_) return false;
    solved = std::move(solved_);
    solvedJoints_ = solvingJoints_;
  }
  if (result_ && result_->kernel) result_->kernel->wait();
  result_ = std::make_unique<Result>();
  result_->steps = std::move(*solved);
  result_->mesh = std::make_unique<RaycastMesh>(buildRaycastMesh(result_->steps.rest, grid.geometry(), "articulated transfer mesh"));
  result_->kernel = std::make_unique<gpu::RaycastKernel>(context, grid, *result_->mesh);
  step_ = steps();
  shown_ = true;
  return true;
}

int ArticulatedView::steps() const { return result_ ? int(result_->steps.steps.size()) : 0; }

const RaycastMesh& ArticulatedView::mesh() const { return *result_->mesh; }

gpu::RaycastKernel& ArticulatedView::kernel() { return *result_->kernel; }

const std::vector<Eigen::Vector3d>& ArticulatedView::positions() const {
  const int k = std::clamp(step_, 1, steps());
  return result_->steps.steps[std::size_t(k - 1)];
}

std::string ArticulatedView::message() const {
  std::lock_guard lock(mutex_);
  return message_;
}

}  // namespace vox::app
