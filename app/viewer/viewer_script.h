#pragma once
// Scripted sessions of the viewer (`voxmorph view --script session.json`), so
// that the application runs headless under Xvfb in tests. A script is a list
// of steps run one after the other, each after `frames` frames (default 1)
// of the previous one:
//
//   {"size": [960, 540],
//    "steps": [
//      {"step": "camera", "azimuth": 20, "elevation": 10},
//      {"step": "screenshot", "path": "rest.png"},
//      {"step": "select_group", "group": "right_arm"},
//      {"step": "move", "name": "right arm", "center": [97, 145, 1450]},
//      {"step": "gizmo_rotate", "axis": "y", "degrees": 45, "steps": 15},
//      {"step": "cut", "cuts": ["y>150mm"]},
//      {"step": "undo", "count": 3},
//      {"step": "save_pose", "path": "pose.json"},
//      {"step": "export", "path": "posed.nii.gz", "report": "posed.json"},
//      {"step": "quit"}]}
//
// Low-level steps drive the mouse and keyboard at window pixels
// (mouse_move, mouse_down, mouse_up with "button": 0 left, 1 right, 2 middle;
// scroll with "dy"; key with "key": a GLFW key name such as "Z" and
// "ctrl"/"shift"); high-level steps call what the panels call (select_group,
// pick_rect, pick_clear, fix, move, gizmo_rotate and gizmo_translate through
// the gizmo's drag code, cut_drag through a cutting plane's handle, toggle,
// cut, hide, arap, undo, redo, save_pose,
// load_pose, export, cancel_export, screenshot, camera, wait, quit). Joints
// (a session opened with a joint pose; skeleton/joints.h names them):
//   {"step": "select_joint", "joint": "right_shoulder"}     the Joints panel's click: the gizmo's target
//   {"step": "set_joint", "joint": "right_shoulder", "dof": "abduction", "degrees": 60}   its slider
//   {"step": "gizmo_rotate", "axis": "abduction", "degrees": 15}   the selected joint's ring
//   {"step": "articulated"}                 the Joints panel's "Solve on the articulated mesh", waited for
//   {"step": "articulated_step", "index": 3}   its step slider (1 to the solve's steps; the last: the posed mesh)
// A joint or degree of freedom that does not exist, or an angle outside the
// joint's range, is an error naming the joint when the script is read. An
// export waits for its end unless "background": true; cancel_export cancels
// the running export and waits until it has stopped. Paths are relative to
// the working directory; screenshot paths to --screenshot-dir when given.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace vox::app {

struct ScriptStep {
  std::string step;
  int frames = 1;  // frames to wait before this step runs
  std::string text, path, report, png;  // group / name / key / axis / dof / toggle name; paths
  std::string joint;                    // select_joint, set_joint
  std::vector<std::string> list;        // cuts, hidden organs
  std::vector<double> numbers;          // pixels, rect, centre...
  double value = 0.0;                   // degrees, mm, dy, count...
  int count = 1, button = 0, substeps = 10;
  bool flag = false;                    // add / ctrl / window / preserve_volumes
  bool shift = false;
  bool background = false;  // export: return at once (cancel_export then ends it)
};

struct ViewerScript {
  int width = 0, height = 0;  // window size (0: the command's)
  std::vector<ScriptStep> steps;
};

// Throws InputError(path, ...) for unreadable files, bad JSON, unknown steps
// or keys, and wrong types.
ViewerScript readViewerScript(const std::string& path);

}  // namespace vox::app
