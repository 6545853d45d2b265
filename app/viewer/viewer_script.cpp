#include "app/viewer/viewer_script.h"

#include "geometry/deform/pose/pose.h"
#include "geometry/error.h"
#include "geometry/skeleton/joints.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <set>
#include <sstream>

namespace vox::app {

namespace {

using nlohmann::json;

const std::set<std::string> kSteps = {"mouse_move", "mouse_down", "mouse_up", "scroll",      "key",       "select_group", "pick_rect",
                                      "pick_clear", "fix",        "move",     "gizmo_rotate", "gizmo_translate", "toggle", "cut", "cut_drag",
                                      "hide",       "arap",       "undo",     "redo",        "save_pose", "load_pose",    "export",       "cancel_export",
                                      "screenshot", "camera",     "wait",     "quit",        "select_joint", "set_joint",
                                      "articulated", "articulated_step"};
const std::set<std::string> kGizmoAxes = {"x", "y", "z", "flexion", "abduction", "lateral_flexion", "rotation"};

struct Reader {
  std::string source;
  [[noreturn]] void fail(const std::string& what) const { throw InputError(source, what); }

  double number(const json& j, const std::string& what) const {
    if (!j.is_number()) fail(what + " must be a number");
    return j.get<double>();
  }
  std::string text(const json& j, const std::string& what) const {
    if (!j.is_string()) fail(what + " must be a string");
    return j.get<std::string>();
  }
  std::vector<double> numbers(const json& j, const std::string& what) const {
    if (!j.is_array()) fail(what + " must be an array of numbers");
    std::vector<double> out;
    for (const json& v : j) out.push_back(number(v, what));
    return out;
  }

  ScriptStep step(const json& j, std::size_t index) const {
    const std::string what = "step " + std::to_string(index + 1);
    if (!j.is_object() || !j.contains("step")) fail(what + " must be an object with a 'step'");
    ScriptStep s;
    s.step = text(j["step"], what + " 'step'");
    if (!kSteps.count(s.step)) fail(what + ": unknown step '" + s.step + "'");
    for (const auto& [key, v] : j.items()) {
      const std::string k = what + " '" + key + "'";
      if (key == "step") continue;
      if (key == "frames") s.frames = int(number(v, k));
      else if (key == "group" || key == "name" || key == "key" || key == "axis" || key == "what" || key == "dof") s.text = text(v, k);
      else if (key == "joint") s.joint = text(v, k);
      else if (key == "path") s.path = text(v, k);
      else if (key == "report") s.report = text(v, k);
      else if (key == "png") s.png = text(v, k);
      else if (key == "cuts" || key == "organs") {
        if (!v.is_array()) fail(k + " must be an array of strings");
        for (const json& e : v) s.list.push_back(text(e, k));
      } else if (key == "x" || key == "y") {
        s.numbers.resize(2, 0.0);
        s.numbers[key == "x" ? 0 : 1] = number(v, k);
      } else if (key == "rect" || key == "center") s.numbers = numbers(v, k);
      else if (key == "degrees" || key == "mm" || key == "dy" || key == "azimuth" || key == "iterations") s.value = number(v, k);
      else if (key == "elevation") s.numbers = {number(v, k)};
      else if (key == "count" || key == "index") s.count = int(number(v, k));
      else if (key == "button") s.button = int(number(v, k));
      else if (key == "steps") s.substeps = int(number(v, k));
      else if (key == "add" || key == "ctrl" || key == "window" || key == "preserve_volumes" || key == "on") {
        if (!v.is_boolean()) fail(k + " must be true or false");
        s.flag = v.get<bool>();
      } else if (key == "background") {
        if (!v.is_boolean()) fail(k + " must be true or false");
        s.background = v.get<bool>();
      } else if (key == "shift") {
        if (!v.is_boolean()) fail(k + " must be true or false");
        s.shift = v.get<bool>();
      } else fail(what + ": unknown key '" + key + "'");
    }
    if (s.frames < 0 || s.frames > 100000) fail(what + " 'frames' must be in 0..100000");
    if (s.count < 0 || s.substeps < 1 || s.substeps > 10000) fail(what + ": 'count' or 'steps' out of range");
    if ((s.step == "mouse_move" || s.step == "mouse_down" || s.step == "mouse_up") && s.numbers.size() != 2 && s.step == "mouse_move")
      fail(what + " needs 'x' and 'y'");
    if (s.step == "articulated_step" && (!j.contains("index") || s.count < 1)) fail(what + ": articulated_step needs 'index', the step shown (1 or more)");
    if (s.step == "pick_rect" && s.numbers.size() != 4) fail(what + " needs 'rect': [x0, y0, x1, y1]");
    if ((s.step == "screenshot" || s.step == "save_pose" || s.step == "load_pose" || s.step == "export") && s.path.empty())
      fail(what + " needs a 'path'");
    if ((s.step == "gizmo_translate" || s.step == "cut_drag") && s.text != "x" && s.text != "y" && s.text != "z")
      fail(what + " needs 'axis': \"x\", \"y\" or \"z\"");
    if (s.step == "gizmo_rotate" && !kGizmoAxes.count(s.text))
      fail(what + " needs 'axis': \"x\", \"y\" or \"z\" (a selection), or a joint's degree of freedom (\"flexion\"...)");
    if (s.step == "select_joint" || s.step == "set_joint") {
      const auto joint = skeleton::jointFromName(s.joint);
      if (!joint) fail(what + ": unknown joint '" + s.joint + "' (expected one of " + skeleton::jointNames() + ")");
      if (s.step == "set_joint") {
        if (!j.contains("degrees")) fail(what + " needs 'degrees'");
        // The pose reader's checks: the degree of freedom, the range.
        checkJointAngle(*joint, jointDof(*joint, s.text, source + ": " + what), s.value, source + ": " + what);
      }
    }
    return s;
  }
};

}  // namespace

ViewerScript readViewerScript(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the script");
  std::ostringstream text;
  text << in.rdbuf();
  const Reader r{path};
  json root;
  try {
    root = json::parse(text.str());
  } catch (const json::exception& e) {
    r.fail(std::string("invalid JSON: ") + e.what());
  }
  if (!root.is_object() || !root.contains("steps") || !root["steps"].is_array()) r.fail("needs an object with a 'steps' array");
  ViewerScript script;
  for (const auto& [key, v] : root.items()) {
    if (key == "steps") continue;
    if (key != "size") r.fail("unknown key '" + key + "'");
    const std::vector<double> size = r.numbers(v, "'size'");
    if (size.size() != 2 || size[0] < 720 || size[1] < 240 || size[0] > 8192 || size[1] > 8192)
      r.fail("'size' must be [width, height] with width 720..8192 and height 240..8192");
    script.width = int(size[0]);
    script.height = int(size[1]);
  }
  for (std::size_t i = 0; i < root["steps"].size(); ++i) script.steps.push_back(r.step(root["steps"][i], i));
  return script;
}

}  // namespace vox::app
