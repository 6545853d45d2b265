#include "app/viewer/script_runner.h"

#include "app/viewer/export_job.h"
#include "app/viewer/viewer_app.h"
#include "geometry/deform/pose/pose_editor.h"
#include "geometry/error.h"
#include "geometry/skeleton/joints.h"

#include <algorithm>
#include <filesystem>

namespace vox::app {

ScriptRunner::ScriptRunner(ViewerScript script, std::string screenshotDir)
    : script_(std::move(script)), screenshotDir_(std::move(screenshotDir)) {
  wait_ = script_.steps.empty() ? 0 : script_.steps[0].frames;
  // Every file the session writes, before the pre-processing: a missing or
  // read-only directory is refused at the start, not at its step.
  if (!screenshotDir_.empty() && !std::filesystem::is_directory(screenshotDir_))
    throw InputError(screenshotDir_, "the screenshot directory does not exist");
  for (const ScriptStep& s : script_.steps) {
    if (s.step == "screenshot") checkWritablePath(screenshotPath(s));
    if (s.step == "save_pose") checkWritablePath(s.path);
    if (s.step == "export")
      for (const std::string* path : {&s.path, &s.report, &s.png})
        if (!path->empty()) checkWritablePath(*path);
  }
}

std::string ScriptRunner::screenshotPath(const ScriptStep& s) const {
  const bool relative = !screenshotDir_.empty() && !std::filesystem::path(s.path).is_absolute();
  return relative ? (std::filesystem::path(screenshotDir_) / s.path).string() : s.path;
}

bool ScriptRunner::beginFrame(Viewer& viewer) {
  const bool playing = dragging();
  InputState& input = viewer.input();
  if (playing) {
    if (index_ < path_.points.size()) {
      input.x = path_.points[index_].first;
      input.y = path_.points[index_].second;
      input.down[0] = true;
    } else {
      input.down[0] = false;
    }
  } else if (next_ >= script_.steps.size()) {
    viewer.quit();
  } else if (wait_ <= 0) {
    runStep(script_.steps[next_], viewer);
    ++next_;
    wait_ = next_ < script_.steps.size() ? script_.steps[next_].frames : 0;
  } else {
    --wait_;
  }
  return playing;
}

bool ScriptRunner::advance(DragKind grabbed) {
  if (index_ == 0 && grabbed != path_.expected) return false;
  if (index_ >= path_.points.size()) path_.points.clear();
  else ++index_;
  return true;
}

void ScriptRunner::drag(PointerPath path) {
  path_ = std::move(path);
  index_ = 0;
}

void ScriptRunner::runStep(const ScriptStep& s, Viewer& viewer) {
  const std::string& k = s.step;
  PoseEditor& editor = viewer.editor();
  InputState& input = viewer.input();
  if (k == "mouse_move") {
    input.x = s.numbers[0];
    input.y = s.numbers[1];
  } else if (k == "mouse_down" || k == "mouse_up") {
    if (s.numbers.size() == 2) {
      input.x = s.numbers[0];
      input.y = s.numbers[1];
    }
    input.down[std::clamp(s.button, 0, 2)] = k == "mouse_down";
  } else if (k == "scroll") {
    input.scroll += s.value;
  } else if (k == "key") {
    if (s.text == "Z" && s.flag) editor.undo();
    else if (s.text == "Y" && s.flag) editor.redo();
    else if (s.text == "F") viewer.fitCamera();
    else if (s.text == "R") viewer.resetCamera();
    else throw InputError("script", "key '" + s.text + "' has no binding");
    viewer.applyView();
  } else if (k == "select_group") {
    editor.pick(editor.groupVertices(s.text), s.flag);
  } else if (k == "pick_rect") {
    editor.pick(cageVerticesInRect(viewer.viewRays(), editor.builtCagePositions(), s.numbers[0], s.numbers[1], s.numbers[2], s.numbers[3]),
                s.flag);
  } else if (k == "pick_clear") {
    editor.clearPicked();
  } else if (k == "fix" || k == "move") {
    editor.addPickedSelection(s.text.empty() ? (k == "fix" ? "fixed" : "moving") : s.text, k == "fix");
    if (k == "move" && s.numbers.size() == 3) editor.setActiveCenter({s.numbers[0], s.numbers[1], s.numbers[2]});
    editor.clearPicked();
  } else if (k == "gizmo_rotate") {
    // x, y, z: the active selection's rings; a degree of freedom: the selected joint's.
    const int joint = editor.state().joint;
    const bool gridAxis = s.text.size() == 1;
    if (gridAxis == (joint >= 0))
      throw InputError("script", gridAxis ? "gizmo_rotate: a joint is selected; turn it about one of its degrees of freedom (\"flexion\"...)"
                                          : "gizmo_rotate: '" + s.text + "' turns a joint; select one first (select_joint)");
    const int ring = gridAxis ? s.text[0] - 'x' : jointDof(skeleton::JointId(joint), s.text, "script");
    drag(viewer.gizmo().rotatePath(viewer.viewRays(), ring, s.value, s.substeps));
  } else if (k == "select_joint") {
    editor.selectJoint(int(*skeleton::jointFromName(s.joint)));
    if (editor.state().joint < 0) throw InputError("script", "select_joint: the session has no joint '" + s.joint + "' (open a joint pose with view --pose)");
  } else if (k == "set_joint") {
    const skeleton::JointId joint = *skeleton::jointFromName(s.joint);
    editor.setJointAngle(int(joint), jointDof(joint, s.text, "script"), s.value);
  } else if (k == "gizmo_translate") {
    drag(viewer.gizmo().translatePath(viewer.viewRays(), s.text[0] - 'x', s.value, s.substeps));
  } else if (k == "cut_drag") {
    drag(viewer.gizmo().cutPath(viewer.viewRays(), s.text[0] - 'x', s.value, s.substeps));
  } else if (k == "toggle") {
    Overlays& overlays = viewer.overlays();
    if (s.text == "cage") overlays.cage = s.flag;
    else if (s.text == "envelope") overlays.envelope = s.flag;
    else if (s.text == "tm") overlays.tm = s.flag;
    else throw InputError("script", "toggle: unknown overlay '" + s.text + "' (cage, envelope, tm)");
  } else if (k == "arap") {
    editor.setArapIterations(s.flag ? int(s.value > 0 ? s.value : 10) : 0);
    viewer.applyView();
  } else if (k == "cut") {
    for (const std::string& c : s.list) CuttingPlanes().add(c);
    editor.setCuts(s.list);
    viewer.applyView();
  } else if (k == "hide") {
    std::vector<Label> hidden;
    Palette probe = viewer.palette();
    for (std::size_t l = 1; l < probe.size(); ++l) probe.setVisible(Label(l), true);
    std::string list;
    for (const std::string& o : s.list) list += (list.empty() ? "" : ",") + o;
    if (!list.empty()) probe.hide(list, editor.organs() ? &*editor.organs() : nullptr);
    for (std::size_t l = 1; l < probe.size(); ++l)
      if (!probe.visible(Label(l))) hidden.push_back(Label(l));
    editor.setHidden(hidden);
    viewer.applyView();
  } else if (k == "undo" || k == "redo") {
    for (int i = 0; i < s.count; ++i)
      if (!(k == "undo" ? editor.undo() : editor.redo())) throw InputError("script", "nothing to " + k);
    viewer.applyView();
  } else if (k == "save_pose") {
    viewer.savePose(s.path);
  } else if (k == "load_pose") {
    viewer.loadPose(s.path);
  } else if (k == "export") {
    viewer.startExport(s.path, s.report, s.png, s.flag);
    if (!s.background) {
      ExportJob& job = viewer.exportJob();
      job.wait();
      viewer.status(job.message());
      if (job.message().rfind("exported", 0) != 0) throw RuntimeFailure("view: " + job.message());
    }
  } else if (k == "articulated") {
    // The solve, waited for: its steps are shown from the next frame.
    viewer.startArticulated();
    ArticulatedView& a = viewer.articulated();
    a.wait();
    if (!a.collect(viewer.gpuContext(), viewer.grid())) throw RuntimeFailure("view: " + a.message());
    viewer.status(a.message());
    viewer.redraw();
  } else if (k == "articulated_step") {
    ArticulatedView& a = viewer.articulated();
    if (!a.held()) throw InputError("script", "articulated_step: no articulated solve to show (an 'articulated' step first)");
    if (s.count > a.steps()) throw InputError("script", "articulated_step: index " + std::to_string(s.count) + " is beyond the solve's " + std::to_string(a.steps()) + " steps");
    a.step() = s.count;
    a.shown() = true;
    viewer.redraw();
  } else if (k == "cancel_export") {
    viewer.exportJob().cancel();
    viewer.exportJob().wait();
    viewer.status(viewer.exportJob().message());
  } else if (k == "screenshot") {
    viewer.screenshot(screenshotPath(s), s.flag);
  } else if (k == "camera") {
    OrbitCamera& orbit = viewer.orbit();
    if (s.value != 0.0 || !s.numbers.empty()) orbit.azimuth = s.value;
    if (!s.numbers.empty()) orbit.elevation = s.numbers[0];
    viewer.redraw();
  } else if (k == "wait") {
  } else if (k == "quit") {
    viewer.quit();
  }
}

}  // namespace vox::app
