#pragma once
// The Joints panel: the session skeleton's joints (skeleton/joints.h), each
// with its angles and a slider per degree of freedom within the joint's
// stated range; clicking a joint's name makes it the gizmo's target (its
// rings turn it about its axes). A slider's gesture is one undo step. A
// session not built from the skeleton (not opened with a joint pose) has
// no joints to turn, and the panel says so. Below the list, in red while it
// lasts: the bones the pose presses through each other, which an export is
// refused for (PoseFigures::bonesThroughEachOther).

namespace vox::app {

class Viewer;

class JointsPanel {
public:
  void draw(Viewer& viewer);

private:
  int sliding_ = -1;  // the slider being dragged: joint * 3 + degree of freedom
  int scrolledTo_ = -1;  // the selected joint the list last scrolled to
};

}  // namespace vox::app
