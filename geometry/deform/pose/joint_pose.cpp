#include "geometry/deform/pose/joint_pose.h"

#include "geometry/ascii_text.h"
#include "geometry/distance_transform.h"
#include "geometry/error.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>

namespace vox::skeleton {

namespace {

// Parts in an order where each comes after its parent.
constexpr std::array<Part, kPartCount> kTreeOrder = {
    Part::Trunk,        Part::Pelvis,        Part::Neck,       Part::Head,       Part::RightUpperArm, Part::RightForearm,
    Part::RightHand,    Part::LeftUpperArm,  Part::LeftForearm, Part::LeftHand,  Part::RightThigh,    Part::RightLowerLeg,
    Part::RightFoot,    Part::LeftThigh,     Part::LeftLowerLeg, Part::LeftFoot};

// The limbs' joints from the body out.
constexpr std::array<std::array<JointId, 3>, 4> kLimbs = {{
    {JointId::RightShoulder, JointId::RightElbow, JointId::RightWrist},
    {JointId::LeftShoulder, JointId::LeftElbow, JointId::LeftWrist},
    {JointId::RightHip, JointId::RightKnee, JointId::RightAnkle},
    {JointId::LeftHip, JointId::LeftKnee, JointId::LeftAnkle},
}};

const PoseJoint* anglesOf(const std::vector<PoseJoint>& angles, JointId id) {
  for (const PoseJoint& a : angles)
    if (jointFromName(a.name) == id) return &a;
  return nullptr;
}

bool turned(const PoseJoint* a) { return a && std::any_of(a->degrees.begin(), a->degrees.end(), [](double d) { return d != 0.0; }); }

// Whether `part` hangs below `ancestor` (or is it).
bool below(Part part, Part ancestor) {
  for (Part p = part; p != Part::None; p = parentPart(p))
    if (p == ancestor) return true;
  return false;
}

std::string partList(const std::vector<Label>& parts) {
  std::string s;
  for (const Label p : parts) s += std::string(s.empty() ? "" : ", ") + partName(Part(p));
  return s;
}

// The region of the parts below a turned joint (moving[part]): the box of
// their voxels, padded, with the joint's end cut off `margin` down the limb
// along the axis the limb runs along most. Empty when nothing is left.
Eigen::AlignedBox3d belowJoint(const LabelGrid& parts, const Joint& joint, const std::array<bool, kPartCount + 1>& moving,
                               const JointPoseOptions& options) {
  const GridGeometry& g = parts.geometry();
  Eigen::AlignedBox3d box;
  double reach = 0.0;  // how far the parts extend down the limb from the joint
  for (std::int64_t v = 0; v < g.voxelCount(); ++v)
    if (const Label l = parts.labels()[std::size_t(v)]; l != 0 && l <= kPartCount && moving[l]) {
      const Index3 c = g.ijk(v);
      const Eigen::Vector3d p = g.voxelCenter(c[0], c[1], c[2]);
      box.extend(p - 0.5 * g.spacing);
      box.extend(p + 0.5 * g.spacing);
      reach = std::max(reach, (p - joint.centre).dot(joint.longAxis));
    }
  if (box.isEmpty()) return box;
  box.min().array() -= options.regionPaddingMm;
  box.max().array() += options.regionPaddingMm;
  Eigen::Index axis = 0;
  joint.longAxis.cwiseAbs().maxCoeff(&axis);
  const double margin = std::min(options.jointMarginMm, options.jointMarginFraction * reach);
  const double cut = joint.centre(axis) + margin * joint.longAxis(axis);
  if (joint.longAxis(axis) < 0) box.max()(axis) = std::min(box.max()(axis), cut);
  else box.min()(axis) = std::max(box.min()(axis), cut);
  if ((box.min().array() > box.max().array()).any()) return Eigen::AlignedBox3d();
  return box;
}

std::array<bool, kPartCount + 1> partsBelow(Part child) {
  std::array<bool, kPartCount + 1> moving{};
  for (int p = 1; p <= kPartCount; ++p) moving[std::size_t(p)] = below(Part(p), child);
  return moving;
}

// Separations of one limb below its highest turned joint: its label group
// from every other group near its moving parts inside the region.
void limbSeparations(std::vector<PoseSeparation>& out, const Skeleton& skeleton, const std::vector<Joint>& joints,
                     const std::vector<PoseJoint>& angles, const std::array<JointId, 3>& limb, const JointPoseOptions& options) {
  const Joint* top = nullptr;
  for (const JointId id : limb)
    if (turned(anglesOf(angles, id))) {
      top = findJoint(joints, id);
      break;
    }
  if (!top) return;
  const Part child = top->kind().child;
  const LabelGroup group = labelGroupOf(child);
  const LabelGrid& parts = skeleton.parts.parts;
  const GridGeometry& g = parts.geometry();
  const std::array<bool, kPartCount + 1> moving = partsBelow(child);
  const Eigen::AlignedBox3d box = belowJoint(parts, *top, moving, options);
  if (box.isEmpty()) return;
  // The groups within reach of the moving parts inside the region: the
  // cage would wrap them together (it lies a dilation away from both).
  std::vector<std::uint8_t> mask(std::size_t(g.voxelCount()), 0);
  for (std::int64_t v = 0; v < g.voxelCount(); ++v)
    if (const Label l = parts.labels()[std::size_t(v)]; l != 0 && l <= kPartCount && moving[l]) mask[std::size_t(v)] = 1;
  const ScalarGrid distance = euclideanDistanceTransform(g, mask).distance;
  std::array<std::int64_t, kLabelGroupCount + 1> touching{};
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
    const Label l = parts.labels()[std::size_t(v)];
    if (l == 0 || l > kPartCount || moving[l] || labelGroupOf(Part(l)) == group) continue;
    if (distance.values[std::size_t(v)] > options.nearMm) continue;
    const Index3 c = g.ijk(v);
    if (box.contains(g.voxelCenter(c[0], c[1], c[2]))) ++touching[std::size_t(labelGroupOf(Part(l)))];
  }
  for (int other = 1; other <= kLabelGroupCount; ++other)
    if (touching[std::size_t(other)] > 0) {
      PoseSeparation s;
      s.cage = {Label(group), Label(other), box};
      out.push_back(s);
    }
}

PoseSelection partSelection(std::string name, std::vector<Label> parts, const Eigen::Isometry3d& motion, const Eigen::Vector3d& near) {
  PoseSelection s;
  s.name = std::move(name);
  s.shape = SelectionShape::Everywhere;
  s.bodyParts = std::move(parts);
  if (motion.matrix() == Eigen::Matrix4d::Identity()) s.fixed = true;
  else s.transform = screwTransform(motion, near);
  return s;
}

}  // namespace

std::vector<Joint> posedJoints(const Skeleton& skeleton, const std::vector<PoseJoint>& angles, const std::string& source) {
  std::vector<Joint> joints = skeleton.joints;
  for (const PoseJoint& a : angles) {
    const auto id = jointFromName(a.name);
    if (!id) throw InputError(source, "unknown joint '" + a.name + "' (expected one of " + jointNames() + ")");
    Joint* j = nullptr;
    for (Joint& candidate : joints)
      if (candidate.id == *id) j = &candidate;
    if (!j) {
      const JointKind& k = jointKind(*id);
      throw InputError(source, std::string("the grid's skeleton has no joint '") + k.name + "': it needs bones in both " + partName(k.parent) +
                                   " and " + partName(k.child) + " (voxmorph parts lists the bones found)");
    }
    if (a.center) {
      j->centre = *a.center;
      j->radius = 0.0;
      j->method = "given";
    }
    if (a.axis) {
      const Eigen::Vector3d u = *a.axis - a.axis->dot(j->longAxis) * j->longAxis;
      if (u.norm() < 0.1 * a.axis->norm())
        throw InputError(source, std::string("joint '") + j->kind().name + "': the given axis runs along the bone; give the left-right axis");
      j->leftRight = u.normalized().dot(skeleton.parts.frame.right) < 0.0 ? Eigen::Vector3d(-u.normalized()) : Eigen::Vector3d(u.normalized());
      j->axisMethod = "given";
    }
  }
  return joints;
}

PartMotions partMotions(const std::vector<Joint>& joints, const std::vector<PoseJoint>& angles) {
  PartMotions m;
  m.fill(Eigen::Isometry3d::Identity());
  for (const Part p : kTreeOrder) {
    const auto id = jointMoving(p);
    if (!id) continue;  // trunk and pelvis
    Eigen::Isometry3d motion = m[std::size_t(jointKind(*id).parent)];
    const Joint* j = findJoint(joints, *id);
    const PoseJoint* a = anglesOf(angles, *id);
    if (j && turned(a)) {
      // x -> R (x - c) + c
      Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
      turn.linear() = j->rotation(a->degrees);
      turn.translation() = j->centre - turn.linear() * j->centre;
      motion = motion * turn;
    }
    m[std::size_t(p)] = motion;
  }
  return m;
}

std::optional<std::string> bonesThroughEachOther(const Skeleton& skeleton, const std::vector<Joint>& joints, const std::vector<PoseJoint>& angles,
                                                 double maxPercent) {
  if (std::none_of(angles.begin(), angles.end(), [](const PoseJoint& a) { return turned(&a); })) return std::nullopt;
  return bonesThroughEachOther(BoneOverlapIndex(skeleton.parts), joints, angles, maxPercent);
}

std::optional<std::string> bonesThroughEachOther(const BoneOverlapIndex& bones, const std::vector<Joint>& joints,
                                                 const std::vector<PoseJoint>& angles, double maxPercent) {
  if (std::none_of(angles.begin(), angles.end(), [](const PoseJoint& a) { return turned(&a); })) return std::nullopt;
  const PartMotions motions = partMotions(joints, angles);
  const std::vector<BoneOverlap> overlaps = bones.under(joints, motions);
  if (overlaps.empty() || !(100.0 * overlaps.front().fractionOfSmaller > maxPercent)) return std::nullopt;
  const BoneOverlap& o = overlaps.front();
  // The turned joints on the way between the two parts, up from each to
  // the part both hang from.
  std::vector<Part> above;
  for (Part p = o.first; p != Part::None; p = parentPart(p)) above.push_back(p);
  std::vector<std::string> names;
  const auto name = [&](Part p) {
    const auto id = jointMoving(p);
    if (id && turned(anglesOf(angles, *id))) names.insert(names.begin(), jointKind(*id).name);
  };
  Part common = o.second;
  for (; common != Part::None && std::find(above.begin(), above.end(), common) == above.end(); common = parentPart(common)) name(common);
  for (Part p = o.first; p != common && p != Part::None; p = parentPart(p)) name(p);
  const std::string joinedNames = joinedWords(names);
  char figures[160];
  std::snprintf(figures, sizeof figures, "%zu voxels, %.1f cm3: %.1f %% of the %s's bones, more than %g %%", o.voxels, o.volumeMm3 / 1000.0,
                100.0 * o.fractionOfSmaller, partName(o.smaller), maxPercent);
  return std::string("the bones of the ") + partName(o.first) + " and the " + partName(o.second) + " pass through each other (" + figures + ")" +
         (joinedNames.empty() ? std::string() : " with " + joinedNames + " as posed");
}

PoseTransform screwTransform(const Eigen::Isometry3d& motion, const Eigen::Vector3d& near) {
  PoseTransform t;
  const Eigen::AngleAxisd aa(motion.linear());
  if (!(aa.angle() > 1e-12)) {
    t.translation = motion.translation();
    return t;
  }
  const Eigen::Vector3d a = aa.axis().normalized();
  const Eigen::Vector3d along = a.dot(motion.translation()) * a;
  // (I - R) c = the translation across the axis; the minimum-norm solution
  // lies across the axis too, then slides along it to the point nearest `near`.
  const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - motion.linear();
  Eigen::Vector3d c = across.completeOrthogonalDecomposition().solve(motion.translation() - along);
  c += a.dot(near - c) * a;
  t.axis = a;
  t.angleDeg = aa.angle() * 180.0 / std::numbers::pi;
  t.center = c;
  t.translation = along;
  return t;
}

std::vector<PoseTransform> partTransforms(const Pose& pose, const Skeleton& skeleton, const std::string& source) {
  const std::vector<Joint> joints = posedJoints(skeleton, pose.joints, source);
  const PartMotions motions = partMotions(joints, pose.joints);
  std::vector<PoseTransform> out(motions.size());
  for (std::size_t p = 0; p < motions.size(); ++p) {
    const auto id = p == 0 ? std::nullopt : jointMoving(Part(p));
    const Joint* joint = id ? findJoint(joints, *id) : nullptr;
    out[p] = screwTransform(motions[p], joint ? joint->centre : Eigen::Vector3d::Zero());
  }
  return out;
}

Pose compileJointPose(const Pose& pose, const Skeleton& skeleton, const std::string& source, const JointPoseOptions& options) {
  const std::vector<Joint> joints = posedJoints(skeleton, pose.joints, source);
  const PartMotions motions = partMotions(joints, pose.joints);
  const auto present = [&](Part p) { return skeleton.parts.voxels[std::size_t(p)] > 0; };

  Pose out = pose;
  out.joints.clear();
  out.selections.clear();
  out.separations.clear();
  std::vector<Label> still;
  for (const Part p : kTreeOrder)
    if (present(p) && motions[std::size_t(p)].matrix() == Eigen::Matrix4d::Identity()) still.push_back(Label(p));
  if (!still.empty()) out.selections.push_back(partSelection("body parts at rest", still, Eigen::Isometry3d::Identity(), Eigen::Vector3d::Zero()));
  // Per turned joint, down the tree: the parts that move with it and no
  // deeper turned joint. Their cage vertices beyond the joint's margin take
  // the joint's motion; those near the joint its parent's (or none).
  for (const Part child : kTreeOrder) {
    const auto id = jointMoving(child);
    if (!id || !turned(anglesOf(pose.joints, *id))) continue;
    const Joint* joint = findJoint(joints, *id);
    if (!joint) continue;
    std::vector<Label> group;
    std::array<bool, kPartCount + 1> moving{};
    for (const Part p : kTreeOrder) {
      if (!present(p) || !below(p, child)) continue;
      bool deeper = false;
      for (Part q = p; q != child; q = parentPart(q))
        deeper = deeper || turned(anglesOf(pose.joints, *jointMoving(q)));
      if (deeper) continue;
      group.push_back(Label(p));
      moving[std::size_t(p)] = true;
    }
    if (group.empty()) continue;
    const std::string name = std::string(joint->kind().name) + ": " + partList(group);
    const Eigen::Isometry3d& parentMotion = motions[std::size_t(joint->kind().parent)];
    if (options.jointZone == JointZone::Parent)
      out.selections.push_back(partSelection(name + " (near the joint)", group, parentMotion, joint->centre));
    PoseSelection s = partSelection(name, group, motions[std::size_t(child)], joint->centre);
    if (options.jointZone != JointZone::Child) {
      const Eigen::AlignedBox3d box = belowJoint(skeleton.parts.parts, *joint, moving, options);
      if (!box.isEmpty()) {
        s.shape = SelectionShape::Box;
        s.boxMin = box.min();
        s.boxMax = box.max();
      }
    }
    out.selections.push_back(s);
  }
  out.selections.insert(out.selections.end(), pose.selections.begin(), pose.selections.end());
  for (const auto& limb : kLimbs) limbSeparations(out.separations, skeleton, joints, pose.joints, limb, options);
  out.separations.insert(out.separations.end(), pose.separations.begin(), pose.separations.end());
  return out;
}

JointPoseOptions jointPoseOptions(const PoseJointOptions& given, JointPoseOptions base) {
  if (given.zone) base.jointZone = *given.zone == "free" ? JointZone::Free : *given.zone == "child" ? JointZone::Child : JointZone::Parent;
  if (given.marginMm) base.jointMarginMm = *given.marginMm;
  return base;
}

}  // namespace vox::skeleton
