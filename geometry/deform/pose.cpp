#include "geometry/deform/pose.h"

#include "geometry/error.h"
#include "geometry/io/atomic_file.h"

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <sstream>

namespace vox {

namespace {

using nlohmann::json;

class PoseParser {
public:
  explicit PoseParser(std::string source) : source_(std::move(source)) {}

  Pose parse(const std::string& document) {
    json root;
    try {
      root = json::parse(document);
    } catch (const json::exception& e) {
      fail(std::string("invalid JSON: ") + e.what());
    }
    requireObject(root, "the pose");
    allowKeys(root, "the pose", {"name", "arap_iterations", "selections"});
    Pose pose;
    if (root.contains("name")) pose.name = text(root["name"], "'name'");
    if (root.contains("arap_iterations")) {
      const json& it = root["arap_iterations"];
      if (!it.is_number_integer() || it.get<long long>() < 0 || it.get<long long>() > 100000)
        fail("'arap_iterations' must be an integer between 0 and 100000");
      pose.arapIterations = it.get<int>();
    }
    if (!root.contains("selections")) fail("missing 'selections'");
    const json& selections = root["selections"];
    if (!selections.is_array() || selections.empty()) fail("'selections' must be a non-empty array");
    for (std::size_t k = 0; k < selections.size(); ++k) pose.selections.push_back(selection(selections[k], k));
    return pose;
  }

private:
  [[noreturn]] void fail(const std::string& fault) const { throw InputError(source_, fault); }

  void requireObject(const json& j, const std::string& what) const {
    if (!j.is_object()) fail(what + " must be a JSON object");
  }
  void allowKeys(const json& j, const std::string& what, std::initializer_list<const char*> keys) const {
    for (const auto& [key, value] : j.items()) {
      bool known = false;
      for (const char* k : keys) known = known || key == k;
      if (!known) fail(what + " has an unknown key '" + key + "'");
    }
  }
  std::string text(const json& j, const std::string& what) const {
    if (!j.is_string()) fail(what + " must be a string");
    return j.get<std::string>();
  }
  double number(const json& j, const std::string& what) const {
    if (!j.is_number()) fail(what + " must be a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) fail(what + " is not finite");
    return v;
  }
  Eigen::Vector3d vector3(const json& j, const std::string& what) const {
    if (!j.is_array() || j.size() != 3) fail(what + " must be an array of 3 numbers");
    return {number(j[0], what), number(j[1], what), number(j[2], what)};
  }
  const json& member(const json& j, const char* key, const std::string& what) const {
    if (!j.contains(key)) fail(what + " is missing '" + key + "'");
    return j[key];
  }

  PoseSelection selection(const json& j, std::size_t index) {
    const std::string fallback = "selection " + std::to_string(index + 1);
    requireObject(j, fallback);
    PoseSelection s;
    s.name = j.contains("name") ? text(j["name"], fallback + " 'name'") : fallback;
    const std::string what = "selection '" + s.name + "'";
    allowKeys(j, what, {"name", "box", "sphere", "fixed", "transform"});
    if (j.contains("box") == j.contains("sphere")) fail(what + " needs exactly one of 'box' and 'sphere'");
    if (j.contains("box")) {
      const json& box = j["box"];
      requireObject(box, what + " 'box'");
      allowKeys(box, what + " 'box'", {"min", "max"});
      s.shape = SelectionShape::Box;
      s.boxMin = vector3(member(box, "min", what + " 'box'"), what + " box 'min'");
      s.boxMax = vector3(member(box, "max", what + " 'box'"), what + " box 'max'");
      if ((s.boxMin.array() > s.boxMax.array()).any()) fail(what + " has a box with min > max");
    } else {
      const json& sphere = j["sphere"];
      requireObject(sphere, what + " 'sphere'");
      allowKeys(sphere, what + " 'sphere'", {"center", "radius"});
      s.shape = SelectionShape::Sphere;
      s.center = vector3(member(sphere, "center", what + " 'sphere'"), what + " sphere 'center'");
      s.radius = number(member(sphere, "radius", what + " 'sphere'"), what + " sphere 'radius'");
      if (!(s.radius > 0)) fail(what + " has a sphere radius <= 0");
    }
    const bool fixedKey = j.contains("fixed");
    if (fixedKey == j.contains("transform")) fail(what + " needs exactly one of 'fixed' and 'transform'");
    if (fixedKey) {
      if (!j["fixed"].is_boolean() || !j["fixed"].get<bool>()) fail(what + " 'fixed' must be true (give a 'transform' to move it)");
      s.fixed = true;
      return s;
    }
    const json& t = j["transform"];
    requireObject(t, what + " 'transform'");
    allowKeys(t, what + " 'transform'", {"rotation", "translation"});
    if (t.contains("translation")) s.transform.translation = vector3(t["translation"], what + " 'translation'");
    if (t.contains("rotation")) {
      const json& r = t["rotation"];
      requireObject(r, what + " 'rotation'");
      allowKeys(r, what + " 'rotation'", {"axis", "angle_deg", "center"});
      const Eigen::Vector3d axis = vector3(member(r, "axis", what + " 'rotation'"), what + " rotation 'axis'");
      if (!(axis.norm() > 0)) fail(what + " has a zero rotation axis");
      s.transform.axis = axis.normalized();
      s.transform.angleDeg = number(member(r, "angle_deg", what + " 'rotation'"), what + " rotation 'angle_deg'");
      s.transform.center = vector3(member(r, "center", what + " 'rotation'"), what + " rotation 'center'");
    }
    return s;
  }

  std::string source_;
};

json toJson(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

}  // namespace

Eigen::Vector3d PoseTransform::apply(const Eigen::Vector3d& x, double fraction) const {
  const double angle = fraction * angleDeg * std::numbers::pi / 180.0;
  return Eigen::AngleAxisd(angle, axis) * (x - center) + center + fraction * translation;
}

bool PoseSelection::contains(const Eigen::Vector3d& p) const {
  if (shape == SelectionShape::Box) return (p.array() >= boxMin.array()).all() && (p.array() <= boxMax.array()).all();
  return (p - center).squaredNorm() <= radius * radius;
}

Pose parsePose(const std::string& jsonText, const std::string& source) { return PoseParser(source).parse(jsonText); }

Pose readPose(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the pose file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, "cannot read the pose file");
  return parsePose(text.str(), path);
}

std::string poseToJson(const Pose& pose) {
  json root;
  if (!pose.name.empty()) root["name"] = pose.name;
  root["arap_iterations"] = pose.arapIterations;
  json selections = json::array();
  for (const PoseSelection& s : pose.selections) {
    json j;
    j["name"] = s.name;
    if (s.shape == SelectionShape::Box)
      j["box"] = {{"min", toJson(s.boxMin)}, {"max", toJson(s.boxMax)}};
    else
      j["sphere"] = {{"center", toJson(s.center)}, {"radius", s.radius}};
    if (s.fixed) {
      j["fixed"] = true;
    } else {
      j["transform"] = {{"rotation", {{"axis", toJson(s.transform.axis)}, {"angle_deg", s.transform.angleDeg},
                                      {"center", toJson(s.transform.center)}}},
                        {"translation", toJson(s.transform.translation)}};
    }
    selections.push_back(std::move(j));
  }
  root["selections"] = std::move(selections);
  return root.dump(2) + "\n";
}

void writePose(const std::string& path, const Pose& pose) { writeFileAtomic(path, poseToJson(pose)); }

PoseHandles selectHandles(const Pose& pose, const TriMesh& cage, const std::string& source) {
  std::vector<std::int32_t> owner(cage.vertexCount(), -1);
  for (std::size_t k = 0; k < pose.selections.size(); ++k) {
    const PoseSelection& s = pose.selections[k];
    bool any = false;
    for (std::size_t v = 0; v < cage.vertexCount(); ++v)
      if (s.contains(cage.positions[v])) {
        owner[v] = std::int32_t(k);
        any = true;
      }
    if (!any) throw InputError(source, "selection '" + s.name + "' selects no cage vertex");
  }
  PoseHandles handles;
  for (std::size_t v = 0; v < owner.size(); ++v)
    if (owner[v] >= 0) {
      handles.vertices.push_back(std::int32_t(v));
      handles.selection.push_back(owner[v]);
    }
  return handles;
}

Eigen::MatrixX3d handleTargets(const Pose& pose, const PoseHandles& handles, const TriMesh& cage, double fraction) {
  if (!(fraction >= 0.0 && fraction <= 1.0)) throw InputError("pose", "fraction " + std::to_string(fraction) + " is outside [0, 1]");
  Eigen::MatrixX3d targets(Eigen::Index(handles.vertices.size()), 3);
  for (std::size_t k = 0; k < handles.vertices.size(); ++k) {
    const Eigen::Vector3d& rest = cage.positions[std::size_t(handles.vertices[k])];
    const PoseSelection& s = pose.selections[std::size_t(handles.selection[k])];
    targets.row(Eigen::Index(k)) = (s.fixed ? rest : s.transform.apply(rest, fraction)).transpose();
  }
  return targets;
}

}  // namespace vox
