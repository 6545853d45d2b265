#include "geometry/deform/pose/pose_editor.h"

#include "geometry/deform/prepared_state.h"
#include "geometry/skeleton/label_groups.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/error.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace vox {

namespace {

constexpr double kDegrees = 3.14159265358979323846 / 180.0;

bool sameShape(const PoseSelection& a, const PoseSelection& b) {
  return a.shape == b.shape && a.boxMin == b.boxMin && a.boxMax == b.boxMax && a.center == b.center && a.radius == b.radius &&
         a.points == b.points && a.fixed == b.fixed && a.part == b.part && a.group == b.group && a.bodyParts == b.bodyParts;
}

bool hasJoint(const skeleton::Skeleton* s, int joint) {
  return s && std::any_of(s->joints.begin(), s->joints.end(), [&](const skeleton::Joint& j) { return int(j.id) == joint; });
}

}  // namespace

bool EditState::operator==(const EditState& o) const {
  if (cuts != o.cuts || hidden != o.hidden || active != o.active || joint != o.joint || pose.arapIterations != o.pose.arapIterations ||
      pose.articulated != o.pose.articulated ||
      pose.joints != o.pose.joints || !(pose.jointOptions == o.pose.jointOptions) || !sameHandleSets(pose, o.pose))
    return false;
  for (std::size_t k = 0; k < pose.selections.size(); ++k) {
    const PoseTransform &a = pose.selections[k].transform, &b = o.pose.selections[k].transform;
    if (a.axis != b.axis || a.angleDeg != b.angleDeg || a.center != b.center || a.translation != b.translation) return false;
  }
  return true;
}

bool sameHandleSets(const Pose& a, const Pose& b) {
  if (a.selections.size() != b.selections.size()) return false;
  for (std::size_t k = 0; k < a.selections.size(); ++k)
    if (!sameShape(a.selections[k], b.selections[k])) return false;
  return true;
}

PoseEditor::PoseEditor(const LabelGrid& grid, std::optional<OrganTable> organs, const Pose& setup, const std::string& setupSource,
                       const std::vector<LimbSeparation>& extraSeparations, std::shared_ptr<PreparedState> prepared)
    : grid_(grid), organs_(std::move(organs)), setupSource_(setupSource), separations_(setup.separations) {
  for (const LimbSeparation& s : extraSeparations) separations_.push_back({s, std::nullopt});
  Pose shaping = setup;
  shaping.separations = separations_;
  PipelineOptions options;
  if (!setup.joints.empty() || usesBodyParts(setup)) {
    requireOrganTable(organs_.has_value(), OrganTableNeed::Bones, setupSource);
    skeleton_ = prepared && prepared->skeleton
                    ? std::make_unique<skeleton::Skeleton>(*prepared->skeleton)
                    : std::make_unique<skeleton::Skeleton>(skeleton::buildSkeleton(grid_, *organs_, {"grid", "organ table", "body parts"}));
    options = skeleton::skeletalPoseOptions(shaping, setupSource, *skeleton_, organs_);
    separations_ = options.pose->separations;
    bones_ = std::make_unique<skeleton::BoneOverlapIndex>(skeleton_->parts);
  } else {
    options = poseOptions(shaping, setupSource, organs_);
  }
  // The selections are embedded by update(); a pose without any has none.
  const Pose compiledSetup = *options.pose;
  options.pose.reset();
  options.prepared = std::move(prepared);
  pipeline_ = std::make_unique<DeformationPipeline>(grid_, options);
  tetVoxels_ = tetLabelVoxels(grid_, pipeline_->transferMesh());
  // The edited pose keeps its joints and its own separations (the compiled
  // ones follow from the joints); the session works in the grid frame, and
  // saves its poses so.
  state_.pose = shaping;
  state_.pose.frame = PoseFrame::Grid;
  setCompiled(compiledSetup);
  if (!compiled_.selections.empty())
    selectHandles(compiled_, pipeline_->builtCage(), setupSource_, pipeline_->cageGroups(), pipeline_->cageBodyParts());
  refreshFigures();
}

PoseEditor::~PoseEditor() = default;

void PoseEditor::pick(const std::vector<std::int32_t>& vertices, bool add) {
  if (!add) picked_.clear();
  for (std::int32_t v : vertices)
    if (v >= 0 && std::size_t(v) < pipeline_->builtCage().vertexCount()) picked_.push_back(v);
  std::sort(picked_.begin(), picked_.end());
  picked_.erase(std::unique(picked_.begin(), picked_.end()), picked_.end());
}

std::vector<std::int32_t> PoseEditor::groupVertices(const std::string& group) const {
  requireOrganTable(!pipeline_->cageGroups().empty(), OrganTableNeed::LabelGroup, "label group '" + group + "'");
  const Label g = Label(labelGroupFromName(group));
  std::vector<std::int32_t> out;
  for (std::size_t v = 0; v < pipeline_->cageGroups().size(); ++v)
    if (pipeline_->cageGroups()[v] == g) out.push_back(std::int32_t(v));
  return out;
}

void PoseEditor::push() {
  undo_.push_back(state_);
  redo_.clear();
}

int PoseEditor::addPickedSelection(const std::string& name, bool fixed) {
  if (picked_.empty()) throw InputError("selection '" + name + "'", "no cage vertex is picked");
  PoseSelection s;
  s.name = name;
  s.shape = SelectionShape::Points;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (std::int32_t v : picked_) {
    s.points.push_back(pipeline_->builtCage().positions[std::size_t(v)]);
    centre += s.points.back();
  }
  s.fixed = fixed;
  if (!fixed) s.transform.center = centre / double(picked_.size());
  push();
  state_.pose.articulated = false;  // selections are the cage pipeline's
  state_.pose.selections.push_back(std::move(s));
  const int index = int(state_.pose.selections.size()) - 1;
  if (!fixed) {
    state_.active = index;
    state_.joint = -1;
  }
  return index;
}

int PoseEditor::addGroupSelection(const std::string& group, bool fixed) {
  const std::vector<std::int32_t> vertices = groupVertices(group);
  if (vertices.empty()) throw InputError("label group '" + group + "'", "no cage vertex lies nearest this group");
  PoseSelection s;
  s.name = group;
  s.shape = SelectionShape::Box;
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : pipeline_->builtCage().positions) box.extend(p);
  s.boxMin = box.min() - Eigen::Vector3d::Constant(1.0);
  s.boxMax = box.max() + Eigen::Vector3d::Constant(1.0);
  s.group = Label(labelGroupFromName(group));
  s.fixed = fixed;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (std::int32_t v : vertices) centre += pipeline_->builtCage().positions[std::size_t(v)];
  if (!fixed) s.transform.center = centre / double(vertices.size());
  push();
  state_.pose.articulated = false;  // selections are the cage pipeline's
  state_.pose.selections.push_back(std::move(s));
  const int index = int(state_.pose.selections.size()) - 1;
  if (!fixed) {
    state_.active = index;
    state_.joint = -1;
  }
  return index;
}

void PoseEditor::removeSelection(int index) {
  if (index < 0 || std::size_t(index) >= state_.pose.selections.size()) return;
  push();
  state_.pose.selections.erase(state_.pose.selections.begin() + index);
  if (state_.active == index) state_.active = -1;
  else if (state_.active > index) --state_.active;
}

void PoseEditor::setActive(int index) {
  if (index >= int(state_.pose.selections.size())) index = -1;
  if (index >= 0 && state_.pose.selections[std::size_t(index)].fixed) index = -1;
  if (index == state_.active && (index < 0 || state_.joint < 0)) return;
  push();
  state_.active = index;
  if (index >= 0) state_.joint = -1;
}

void PoseEditor::beginDrag() { push(); }

void PoseEditor::rotateActive(const Eigen::Vector3d& axis, double degrees, bool continuing) {
  if (state_.active < 0 || axis.norm() == 0.0) return;
  if (!continuing) push();
  PoseTransform& t = state_.pose.selections[std::size_t(state_.active)].transform;
  // x -> R (x - c) + c + d, then a turn Q about the centre moved by d:
  // Q R (x - c) + c + d, so only the rotation changes. A turn about the
  // current axis adds to the angle, so angles read as the user typed them.
  const Eigen::Vector3d u = axis.normalized();
  if (t.angleDeg == 0.0) {
    t.axis = u;
    t.angleDeg = degrees;
    return;
  }
  const Eigen::Vector3d a = t.axis.normalized();
  if (a.cross(u).norm() < 1e-12) {
    t.angleDeg += a.dot(u) > 0.0 ? degrees : -degrees;
    return;
  }
  const Eigen::AngleAxisd composed(Eigen::Quaterniond(Eigen::AngleAxisd(degrees * kDegrees, u)) *
                                   Eigen::Quaterniond(Eigen::AngleAxisd(t.angleDeg * kDegrees, a)));
  t.axis = composed.axis();
  t.angleDeg = composed.angle() / kDegrees;
}

void PoseEditor::translateActive(const Eigen::Vector3d& delta, bool continuing) {
  if (state_.active < 0) return;
  if (!continuing) push();
  state_.pose.selections[std::size_t(state_.active)].transform.translation += delta;
}

void PoseEditor::setActiveCenter(const Eigen::Vector3d& centre) {
  if (state_.active < 0) return;
  push();
  state_.pose.selections[std::size_t(state_.active)].transform.center = centre;
}

void PoseEditor::setArapIterations(int iterations) {
  if (iterations == state_.pose.arapIterations) return;
  push();
  state_.pose.arapIterations = std::max(0, iterations);
}

void PoseEditor::setCuts(std::vector<std::string> cuts) {
  if (cuts == state_.cuts) return;
  push();
  state_.cuts = std::move(cuts);
}

void PoseEditor::setHidden(std::vector<Label> hidden) {
  std::sort(hidden.begin(), hidden.end());
  if (hidden == state_.hidden) return;
  push();
  state_.hidden = std::move(hidden);
}

void PoseEditor::loadPose(const Pose& given, const std::string& source) {
  if (!skeleton_ && (!given.joints.empty() || usesBodyParts(given)))
    throw InputError(source, "a pose with joints opens with view --pose (this session was not built from the skeleton)");
  Pose compiled = compile(given, source);
  if (compiled.separations.size() != separations_.size())
    throw InputError(source, "its limb separations differ from the ones this session was built with; open it with view --pose");
  selectHandles(compiled, pipeline_->builtCage(), source, pipeline_->cageGroups(), pipeline_->cageBodyParts());
  push();
  state_.pose = given;
  state_.pose.frame = PoseFrame::Grid;
  // A compiled pose keeps its own separations (saved as given); the others
  // take the session's.
  if (!compiles(given)) state_.pose.separations = separations_;
  state_.active = -1;
  state_.joint = -1;
  for (std::size_t k = 0; k < given.selections.size(); ++k)
    if (!given.selections[k].fixed) state_.active = int(k);
  setCompiled(std::move(compiled));
}

std::vector<skeleton::Joint> PoseEditor::joints() const {
  if (!skeleton_) return {};
  return skeleton::posedJoints(*skeleton_, state_.pose.joints, setupSource_);
}

double PoseEditor::jointAngle(int joint, int dof) const {
  for (const PoseJoint& j : state_.pose.joints)
    if (skeleton::jointFromName(j.name) == skeleton::JointId(joint)) return j.degrees[std::size_t(dof)];
  return 0.0;
}

JointFrame PoseEditor::jointFrame(int joint) const {
  JointFrame f;
  const std::vector<skeleton::Joint> all = joints();
  for (const skeleton::Joint& j : all) {
    if (int(j.id) != joint) continue;
    const Eigen::Isometry3d parent = skeleton::partMotions(all, state_.pose.joints)[std::size_t(j.kind().parent)];
    f.centre = parent * j.centre;
    for (int d = 0; d < skeleton::kDofCount; ++d)
      if (j.kind().dofNames[std::size_t(d)]) f.axes[std::size_t(d)] = parent.linear() * j.axis(skeleton::Dof(d));
  }
  return f;
}

void PoseEditor::setJointAngle(int joint, int dof, double degrees, bool continuing) {
  const skeleton::JointKind& kind = skeleton::jointKind(skeleton::JointId(joint));
  const std::string what = std::string("joint '") + kind.name + "'";
  if (!skeleton_) throw InputError(what, "this session was not built from the skeleton (open a joint pose with view --pose)");
  if (dof < 0 || dof >= skeleton::kDofCount || !kind.dofNames[std::size_t(dof)])
    throw InputError(what, "no such degree of freedom");
  if (!hasJoint(skeleton_.get(), joint))
    throw InputError(what, "the grid's skeleton lacks it (its bones are missing)");
  checkJointAngle(kind.id, dof, degrees, "view");
  if (jointAngle(joint, dof) == degrees) return;
  if (!continuing) push();
  for (PoseJoint& j : state_.pose.joints)
    if (j.name == kind.name) {
      j.degrees[std::size_t(dof)] = degrees;
      return;
    }
  PoseJoint added;
  added.name = kind.name;
  added.degrees[std::size_t(dof)] = degrees;
  state_.pose.joints.push_back(added);
}

void PoseEditor::selectJoint(int joint) {
  if (joint >= 0 && !hasJoint(skeleton_.get(), joint)) joint = -1;
  if (joint == state_.joint && (joint < 0 || state_.active < 0)) return;
  push();
  state_.joint = joint;
  if (joint >= 0) state_.active = -1;
}

bool PoseEditor::compiles(const Pose& pose) const { return skeleton_ && (!pose.joints.empty() || usesBodyParts(pose)); }

Pose PoseEditor::compile(const Pose& pose, const std::string& source) const {
  if (!compiles(pose)) return pose;
  return skeleton::compileJointPose(pose, *skeleton_, source, skeleton::jointPoseOptions(pose.jointOptions));
}

namespace {

// What the compiled selections' shapes depend on: which joints are turned
// (not by how much), their overrides, the options and the own selections'
// shapes.
bool sameCompiledShapes(const Pose& a, const Pose& b) {
  const auto turned = [](const PoseJoint& j) { return std::any_of(j.degrees.begin(), j.degrees.end(), [](double d) { return d != 0.0; }); };
  if (a.joints.size() != b.joints.size() || !(a.jointOptions == b.jointOptions) || !sameHandleSets(a, b)) return false;
  for (std::size_t k = 0; k < a.joints.size(); ++k)
    if (a.joints[k].name != b.joints[k].name || turned(a.joints[k]) != turned(b.joints[k]) || a.joints[k].center != b.joints[k].center ||
        a.joints[k].axis != b.joints[k].axis)
      return false;
  return true;
}

bool sameTransform(const PoseTransform& a, const PoseTransform& b) {
  return a.axis == b.axis && a.angleDeg == b.angleDeg && a.center == b.center && a.translation == b.translation;
}

}  // namespace

void PoseEditor::recompile() {
  const Pose& pose = state_.pose;
  if (!compiles(pose) || !retargetable_ || !sameCompiledShapes(pose, compiledFrom_)) {
    setCompiled(compile(pose, setupSource_));
    return;
  }
  // The same turned joints at other angles: only the transforms change.
  const std::vector<skeleton::Joint> joints = skeleton::posedJoints(*skeleton_, pose.joints, setupSource_);
  const skeleton::PartMotions motions = skeleton::partMotions(joints, pose.joints);
  for (std::size_t k = 0; k < compiledMotions_.size(); ++k)
    if (const auto [part, joint] = compiledMotions_[k]; part >= 0)
      compiled_.selections[k].transform = skeleton::screwTransform(motions[std::size_t(part)], joints[std::size_t(joint)].centre);
  std::copy(pose.selections.begin(), pose.selections.end(), compiled_.selections.begin() + std::ptrdiff_t(compiledMotions_.size()));
  compiled_.arapIterations = pose.arapIterations;
  compiledFrom_ = pose;
}

void PoseEditor::setCompiled(Pose compiled) {
  compiled_ = std::move(compiled);
  compiled_.separations = separations_;
  compiled_.arapIterations = state_.pose.arapIterations;
  compiledFrom_ = state_.pose;
  if (compiles(state_.pose)) findCompiledMotions();
  else retargetable_ = false;
}

void PoseEditor::findCompiledMotions() {
  // Each compiled joint selection's transform is the screw of one part's
  // forward-kinematics motion about one joint's centre: found once, redone
  // for new angles. Any selection not found so makes every change compile.
  const Pose& pose = state_.pose;
  const std::size_t count = compiled_.selections.size() - pose.selections.size();
  const std::vector<skeleton::Joint> joints = skeleton::posedJoints(*skeleton_, pose.joints, setupSource_);
  const skeleton::PartMotions motions = skeleton::partMotions(joints, pose.joints);
  compiledMotions_.assign(count, {-1, -1});
  retargetable_ = true;
  for (std::size_t k = 0; k < count; ++k) {
    const PoseSelection& s = compiled_.selections[k];
    if (s.fixed) continue;
    for (std::size_t p = 0; p < motions.size() && compiledMotions_[k][0] < 0; ++p)
      for (std::size_t j = 0; j < joints.size(); ++j)
        if (sameTransform(skeleton::screwTransform(motions[p], joints[j].centre), s.transform)) {
          compiledMotions_[k] = {int(p), int(j)};
          break;
        }
    retargetable_ = retargetable_ && compiledMotions_[k][0] >= 0;
  }
}

bool PoseEditor::undo() {
  if (undo_.empty()) return false;
  redo_.push_back(state_);
  state_ = undo_.back();
  undo_.pop_back();
  return true;
}

bool PoseEditor::redo() {
  if (redo_.empty()) return false;
  undo_.push_back(state_);
  state_ = redo_.back();
  redo_.pop_back();
  return true;
}

bool PoseEditor::update() {
  const auto t0 = std::chrono::steady_clock::now();
  if (!(EditState{state_.pose, {}, {}, -1, -1} == EditState{compiledFrom_, {}, {}, -1, -1})) recompile();
  const Pose& pose = compiled_;
  bool changed = false;
  if (pose.selections.empty()) {
    changed = embedded_;
    embedded_ = false;
    embeddedPose_ = pose;
  } else {
    if (!embedded_ || !sameHandleSets(pose, embeddedPose_)) {
      pipeline_->setPose(pose, setupSource_);
      embedded_ = true;
      deformed_ = false;
    }
    const bool transformsChanged = !deformed_ || !(EditState{pose, {}, {}, -1, -1} == EditState{embeddedPose_, {}, {}, -1, -1});
    if (transformsChanged) {
      pipeline_->deformTo(handleTargets(pose, pipeline_->handles(), pipeline_->cage()), pose.arapIterations);
      deformed_ = true;
      changed = true;
    }
    embeddedPose_ = pose;
  }
  if (changed) refreshFigures();
  if (changed && bones_)
    figures_.bonesThroughEachOther =
        skeleton::bonesThroughEachOther(*bones_, skeleton::posedJoints(*skeleton_, state_.pose.joints, setupSource_), state_.pose.joints,
                                        skeleton::kMaxBoneOverlapPercent);
  figures_.deformMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return changed;
}

const std::vector<Eigen::Vector3d>& PoseEditor::transferMeshPositions() const {
  return embedded_ ? pipeline_->deformedTransferMesh() : pipeline_->transferMesh().positions;
}

std::vector<Eigen::Vector3d> PoseEditor::builtCagePositions() const {
  std::vector<Eigen::Vector3d> out = pipeline_->builtCage().positions;
  if (!embedded_) return out;
  const std::vector<Eigen::Vector3d>& deformed = pipeline_->deformedCage();
  const std::vector<std::int32_t>& source = pipeline_->cageSource();
  for (std::size_t v = 0; v < source.size() && v < deformed.size(); ++v) out[std::size_t(source[v])] = deformed[v];
  return out;
}

std::vector<std::int32_t> PoseEditor::handleOwners() const {
  std::vector<std::int32_t> owners(pipeline_->builtCage().vertexCount(), -1);
  if (compiled_.selections.empty()) return owners;
  try {
    const PoseHandles h = selectHandles(compiled_, pipeline_->builtCage(), setupSource_, pipeline_->cageGroups(), pipeline_->cageBodyParts());
    for (std::size_t k = 0; k < h.vertices.size(); ++k) owners[std::size_t(h.vertices[k])] = h.selection[k];
  } catch (const InputError&) {
    // A selection that selects nothing shows no handles; update() reports it.
  }
  return owners;
}

void PoseEditor::refreshFigures() {
  const TetMesh& rest = pipeline_->transferMesh();
  const std::vector<Eigen::Vector3d>& now = transferMeshPositions();
  figures_.restVoxels = deformedLabelVolumes(tetVoxels_, rest, rest.positions);
  figures_.deformedVoxels = deformedLabelVolumes(tetVoxels_, rest, now);
  figures_.tmOutsideCage = 0;
  if (embedded_)
    for (std::uint8_t inside : pipeline_->transferMeshInside()) figures_.tmOutsideCage += inside ? 0 : 1;
  figures_.tmInverted = 0;
  for (const Tet& t : rest.tets)
    if (signedVolume(now, t) <= 0.0) ++figures_.tmInverted;
}

}  // namespace vox
