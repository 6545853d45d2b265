#pragma once
// The cutting planes as the viewer edits and draws them: the panel's numbers
// (three axis planes and one free plane, slid inside the scene box), and the
// CuttingPlanes the ray caster gets. The edit state (PoseEditor's
// EditState::cuts) keeps the planes as `render --cut` strings, for pose
// files and undo; the CuttingPlanes are parsed from those strings once
// after each change, never per frame.

#include "geometry/render/cutting_planes.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace vox {
class PoseEditor;
}

namespace vox::app {

class CutControls {
public:
  // Panel values.
  bool on[3] = {false, false, false};
  bool above[3] = {true, true, true};
  float at[3] = {0, 0, 0};
  bool freeOn = false;
  float freeNormal[3] = {1, 0, 0};
  float freeOffset = 0;

  // The box the planes slide in; the axis planes start at its middle.
  void setBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
  const Eigen::Vector3d& lo() const { return lo_; }
  const Eigen::Vector3d& hi() const { return hi_; }
  // The handle of axis plane a: the centre of the plane's section of the box.
  Eigen::Vector3d handle(int a) const;
  // Slides axis plane a by mm, kept inside the box.
  void slide(int a, double mm);

  // The panel values as `render --cut` strings.
  std::vector<std::string> strings() const;
  // The panel values from the edit state's strings (after undo, redo, a
  // loaded pose or a script step); the planes are parsed again.
  void read(const std::vector<std::string>& cuts);
  // Sets the edit state's cuts from the panel values.
  void commit(PoseEditor& editor);
  // What the ray caster gets: the edit state's strings as parsed after their
  // last change (throws what CuttingPlanes::add throws).
  const CuttingPlanes& planes(const std::vector<std::string>& cuts);

private:
  Eigen::Vector3d lo_{0, 0, 0}, hi_{0, 0, 0};
  CuttingPlanes planes_;
  bool stale_ = true;
};

}  // namespace vox::app
