#pragma once
// Plays a scripted session (viewer_script.h) in the viewer's frame loop: one
// step after its frames have passed, through what the panels and the mouse
// call; a scripted drag feeds its pointer path one position a frame to the
// gizmo's mouse handling.

#include "app/viewer/gizmo.h"
#include "app/viewer/viewer_script.h"

#include <cstddef>
#include <string>

namespace vox::app {

class Viewer;

class ScriptRunner {
public:
  // Screenshot paths are taken relative to screenshotDir when it is given.
  // Throws InputError for a file the script writes (screenshot, saved pose,
  // export) whose directory is missing or not writable.
  ScriptRunner(ViewerScript script, std::string screenshotDir);
  const ViewerScript& script() const { return script_; }

  // At a frame's start: the next pointer position of a drag being played
  // (into the viewer's input), or else the next step once its frames have
  // passed (the viewer quits after the last). Returns whether a drag was
  // being played.
  bool beginFrame(Viewer& viewer);
  // Whether a drag is set (being played, or set by this frame's step).
  bool dragging() const { return !path_.points.empty(); }
  // After the mouse handling of a frame that played a drag: false when its
  // first position did not grab the expected handle (`grabbed`); else the
  // next position (the drag ends one frame after its last).
  bool advance(DragKind grabbed);

private:
  void runStep(const ScriptStep& step, Viewer& viewer);
  std::string screenshotPath(const ScriptStep& step) const;
  void drag(PointerPath path);

  ViewerScript script_;
  std::string screenshotDir_;
  std::size_t next_ = 0;
  int wait_ = 0;
  PointerPath path_;
  std::size_t index_ = 0;
};

}  // namespace vox::app
