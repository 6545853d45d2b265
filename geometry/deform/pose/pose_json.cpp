#include "geometry/deform/pose/pose.h"

#include "geometry/atomic_file.h"
#include "geometry/error.h"
#include "geometry/skeleton/body_parts.h"
#include "geometry/skeleton/joints.h"
#include "geometry/skeleton/label_groups.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>

// The pose file format (docs/POSES.md): parsing with the schema's checks,
// and writing what the parser reads back.

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
    allowKeys(root, "the pose", {"name", "frame", "arap_iterations", "selections", "separations", "joints", "joint_options", "articulated"});
    Pose pose;
    if (root.contains("name")) pose.name = text(root["name"], "'name'");
    if (root.contains("frame")) {
      const std::string frame = text(root["frame"], "'frame'");
      if (frame != "world" && frame != "grid") fail("'frame' must be \"world\" or \"grid\", not '" + frame + "'");
      pose.frame = frame == "grid" ? PoseFrame::Grid : PoseFrame::World;
    }
    if (root.contains("arap_iterations")) {
      const json& it = root["arap_iterations"];
      if (!it.is_number_integer() || it.get<long long>() < 0 || it.get<long long>() > 100000)
        fail("'arap_iterations' must be an integer between 0 and 100000");
      pose.arapIterations = it.get<int>();
    }
    if (root.contains("joints")) pose.joints = joints(root["joints"]);
    if (root.contains("joint_options")) pose.jointOptions = jointOptions(root["joint_options"]);
    if (!root.contains("selections") && pose.joints.empty()) fail("missing 'selections' (or 'joints')");
    if (root.contains("selections")) {
      const json& selections = root["selections"];
      if (!selections.is_array() || (selections.empty() && pose.joints.empty())) fail("'selections' must be a non-empty array");
      for (std::size_t k = 0; k < selections.size(); ++k) pose.selections.push_back(selection(selections[k], k));
    }
    if (root.contains("separations")) {
      const json& separations = root["separations"];
      if (!separations.is_array()) fail("'separations' must be an array");
      for (std::size_t k = 0; k < separations.size(); ++k) pose.separations.push_back(separation(separations[k], k));
    }
    if (root.contains("articulated")) {
      if (!root["articulated"].is_boolean()) fail("'articulated' must be true or false");
      pose.articulated = root["articulated"].get<bool>();
      if (pose.articulated && pose.joints.empty()) fail("'articulated' poses joints: the pose has no 'joints'");
      if (pose.articulated && (!pose.selections.empty() || !pose.separations.empty()))
        fail("'articulated' poses joints only: the pose's selections and separations have no place there");
    }
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
    allowKeys(j, what, {"name", "box", "sphere", "points", "part", "group", "body_parts", "fixed", "transform"});
    if (j.contains("body_parts")) {
      const json& parts = j["body_parts"];
      if (!parts.is_array() || parts.empty()) fail(what + " 'body_parts' must be a non-empty array of body part names");
      for (const json& p : parts) {
        const std::string name = text(p, what + " 'body_parts'");
        const auto part = skeleton::partFromName(name);
        if (!part) fail(what + " names an unknown body part '" + name + "' (expected one of " + skeleton::partNames() + ")");
        s.bodyParts.push_back(Label(*part));
      }
    }
    const int shapes = int(j.contains("box")) + int(j.contains("sphere")) + int(j.contains("points"));
    if (shapes > 1 || (shapes == 0 && s.bodyParts.empty()))
      fail(what + " needs exactly one of 'box', 'sphere' and 'points' (or 'body_parts' alone)");
    if (shapes == 0) {
      s.shape = SelectionShape::Everywhere;
    } else if (j.contains("points")) {
      const json& points = j["points"];
      if (!points.is_array() || points.empty()) fail(what + " 'points' must be a non-empty array of [x, y, z]");
      s.shape = SelectionShape::Points;
      for (const json& q : points) s.points.push_back(vector3(q, what + " 'points'"));
    } else if (j.contains("box")) {
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
    if (j.contains("part")) s.part = vector3(j["part"], what + " 'part'");
    if (j.contains("group")) s.group = Label(labelGroupFromName(text(j["group"], what + " 'group'"), source_));
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

  PoseJointOptions jointOptions(const json& j) const {
    requireObject(j, "'joint_options'");
    allowKeys(j, "'joint_options'", {"zone", "margin_mm", "groups"});
    PoseJointOptions o;
    if (j.contains("zone")) {
      o.zone = text(j["zone"], "'joint_options' 'zone'");
      if (*o.zone != "parent" && *o.zone != "free" && *o.zone != "child")
        fail("'joint_options' 'zone' must be \"parent\", \"free\" or \"child\", not '" + *o.zone + "'");
    }
    if (j.contains("margin_mm")) {
      o.marginMm = number(j["margin_mm"], "'joint_options' 'margin_mm'");
      if (*o.marginMm < 0 || *o.marginMm > 1000) fail("'joint_options' 'margin_mm' must be between 0 and 1000");
    }
    if (j.contains("groups")) {
      o.groups = text(j["groups"], "'joint_options' 'groups'");
      if (*o.groups != "parts" && *o.groups != "organs") fail("'joint_options' 'groups' must be \"parts\" or \"organs\", not '" + *o.groups + "'");
    }
    return o;
  }

  std::vector<PoseJoint> joints(const json& j) const {
    if (!j.is_object()) fail("'joints' must be an object of joint names");
    std::vector<PoseJoint> out;
    std::set<skeleton::JointId> seen;
    for (const auto& [key, value] : j.items()) {
      const auto id = skeleton::jointFromName(key);
      if (!id) fail("unknown joint '" + key + "' (expected one of " + skeleton::jointNames() + ")");
      if (!seen.insert(*id).second) fail("joint '" + key + "' is given twice");
      const skeleton::JointKind& kind = skeleton::jointKind(*id);
      const std::string what = std::string("joint '") + kind.name + "'";
      if (!value.is_object()) fail(what + " must be an object of angles in degrees");
      PoseJoint joint;
      joint.name = kind.name;
      for (const auto& [dofKey, dofValue] : value.items()) {
        if (dofKey == "center") {
          joint.center = vector3(dofValue, what + " 'center'");
          continue;
        }
        if (dofKey == "axis") {
          const Eigen::Vector3d axis = vector3(dofValue, what + " 'axis'");
          if (!(axis.norm() > 0)) fail(what + " has a zero 'axis'");
          joint.axis = axis;
          continue;
        }
        const int dof = jointDof(*id, dofKey, source_, ", and 'center' and 'axis'");
        const double degrees = number(dofValue, what + " " + dofKey);
        checkJointAngle(*id, dof, degrees, source_);
        joint.degrees[std::size_t(dof)] = degrees;
      }
      out.push_back(std::move(joint));
    }
    return out;
  }

  std::optional<Eigen::AlignedBox3d> region(const json& j, const char* key, const std::string& what) const {
    if (!j.contains(key)) return std::nullopt;
    const json& region = j[key];
    const std::string name = what + " '" + key + "'";
    requireObject(region, name);
    allowKeys(region, name, {"min", "max"});
    const Eigen::Vector3d lo = vector3(member(region, "min", name), name + " 'min'");
    const Eigen::Vector3d hi = vector3(member(region, "max", name), name + " 'max'");
    if ((lo.array() > hi.array()).any()) fail(what + " has a " + key + " with min > max");
    return Eigen::AlignedBox3d(lo, hi);
  }

  PoseSeparation separation(const json& j, std::size_t index) {
    const std::string what = "separation " + std::to_string(index + 1);
    requireObject(j, what);
    allowKeys(j, what, {"groups", "region", "cut_region"});
    const json& groups = member(j, "groups", what);
    if (!groups.is_array() || groups.size() != 2) fail(what + " 'groups' must be an array of two label group names");
    PoseSeparation s;
    s.cage.groupA = Label(labelGroupFromName(text(groups[0], what + " group"), source_));
    s.cage.groupB = Label(labelGroupFromName(text(groups[1], what + " group"), source_));
    if (s.cage.groupA == s.cage.groupB) fail(what + " separates a group from itself");
    s.cage.region = region(j, "region", what);
    s.cutRegion = region(j, "cut_region", what);
    return s;
  }

  std::string source_;
};

json toJson(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

}  // namespace

int jointDof(skeleton::JointId joint, const std::string& dof, const std::string& source, const std::string& alsoAllowed) {
  const skeleton::JointKind& kind = skeleton::jointKind(joint);
  std::string has;
  for (int d = 0; d < skeleton::kDofCount; ++d)
    if (const char* n = kind.dofNames[std::size_t(d)]) {
      if (dof == n) return d;
      has += std::string(has.empty() ? "" : ", ") + n;
    }
  throw InputError(source, std::string("joint '") + kind.name + "' has no '" + dof + "' (it has " + has + alsoAllowed + ")");
}

void checkJointAngle(skeleton::JointId joint, int dof, double degrees, const std::string& source) {
  const skeleton::JointKind& kind = skeleton::jointKind(joint);
  const auto& range = kind.range[std::size_t(dof)];
  if (degrees >= range[0] && degrees <= range[1]) return;
  std::ostringstream m;
  m << "joint '" << kind.name << "' " << kind.dofNames[std::size_t(dof)] << " " << degrees << " is outside its range [" << range[0] << ", "
    << range[1] << "] degrees";
  throw InputError(source, m.str());
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
  if (pose.frame == PoseFrame::Grid) root["frame"] = "grid";
  root["arap_iterations"] = pose.arapIterations;
  if (pose.articulated) root["articulated"] = true;
  json selections = json::array();
  for (const PoseSelection& s : pose.selections) {
    json j;
    j["name"] = s.name;
    if (s.shape == SelectionShape::Points) {
      json points = json::array();
      for (const Eigen::Vector3d& q : s.points) points.push_back(toJson(q));
      j["points"] = points;
    } else if (s.shape == SelectionShape::Box) {
      j["box"] = {{"min", toJson(s.boxMin)}, {"max", toJson(s.boxMax)}};
    } else if (s.shape == SelectionShape::Sphere) {
      j["sphere"] = {{"center", toJson(s.center)}, {"radius", s.radius}};
    }
    if (!s.bodyParts.empty()) {
      json parts = json::array();
      for (const Label p : s.bodyParts) parts.push_back(skeleton::partName(skeleton::Part(p)));
      j["body_parts"] = parts;
    }
    if (s.fixed) {
      j["fixed"] = true;
    } else {
      j["transform"] = {{"rotation", {{"axis", toJson(s.transform.axis)}, {"angle_deg", s.transform.angleDeg},
                                      {"center", toJson(s.transform.center)}}},
                        {"translation", toJson(s.transform.translation)}};
    }
    if (s.part) j["part"] = toJson(*s.part);
    if (s.group) j["group"] = labelGroupName(LabelGroup(*s.group));
    selections.push_back(std::move(j));
  }
  root["selections"] = std::move(selections);
  if (!pose.joints.empty()) {
    json joints = json::object();
    for (const PoseJoint& pj : pose.joints) {
      json j = json::object();
      const auto id = skeleton::jointFromName(pj.name);
      for (int d = 0; d < skeleton::kDofCount; ++d)
        if (const char* n = id ? skeleton::jointKind(*id).dofNames[std::size_t(d)] : nullptr; n && pj.degrees[std::size_t(d)] != 0.0)
          j[n] = pj.degrees[std::size_t(d)];
      if (pj.center) j["center"] = toJson(*pj.center);
      if (pj.axis) j["axis"] = toJson(*pj.axis);
      joints[pj.name] = std::move(j);
    }
    root["joints"] = std::move(joints);
  }
  const PoseJointOptions& jo = pose.jointOptions;
  if (jo.zone || jo.marginMm || jo.groups) {
    json j = json::object();
    if (jo.zone) j["zone"] = *jo.zone;
    if (jo.marginMm) j["margin_mm"] = *jo.marginMm;
    if (jo.groups) j["groups"] = *jo.groups;
    root["joint_options"] = std::move(j);
  }
  if (!pose.separations.empty()) {
    json separations = json::array();
    for (const PoseSeparation& s : pose.separations) {
      json j;
      j["groups"] = {labelGroupName(LabelGroup(s.cage.groupA)), labelGroupName(LabelGroup(s.cage.groupB))};
      if (s.cage.region) j["region"] = {{"min", toJson(s.cage.region->min())}, {"max", toJson(s.cage.region->max())}};
      if (s.cutRegion) j["cut_region"] = {{"min", toJson(s.cutRegion->min())}, {"max", toJson(s.cutRegion->max())}};
      separations.push_back(std::move(j));
    }
    root["separations"] = std::move(separations);
  }
  return root.dump(2) + "\n";
}

void writePose(const std::string& path, const Pose& pose) { writeFileAtomic(path, poseToJson(pose)); }

}  // namespace vox
