#pragma once
// Pose files: which cage vertices are handles and where they go, as data.
//
// JSON schema (docs/POSES.md has the full description and examples):
//   {
//     "name": "right arm raised",                      optional string
//     "frame": "world",                                optional: "world" (default) or "grid"
//     "arap_iterations": 10,                           optional integer >= 0
//     "selections": [                                  required, non-empty
//       { "name": "trunk",                             optional string
//         "box": {"min": [x, y, z], "max": [x, y, z]}, exactly one of box / sphere
//         "fixed": true },                             exactly one of fixed / transform
//       { "name": "picked",
//         "points": [[x, y, z], ...],                  or: the cage vertex nearest each point
//         "fixed": true },
//       { "name": "right arm",
//         "sphere": {"center": [x, y, z], "radius": r},
//         "part": [x, y, z],                               optional: only the cage part nearest this point
//         "group": "right_arm",                            optional: only cage vertices nearest that label group
//         "body_parts": ["right_upper_arm"],               optional: only cage vertices nearest those body parts
//                                                          (skeleton/body_parts.h); alone (no box / sphere /
//                                                          points): every cage vertex nearest them
//         "transform": {
//           "rotation": {"axis": [x, y, z], "angle_deg": a, "center": [x, y, z]},   optional
//           "translation": [x, y, z] } }                                              optional
//     ],
//     "joints": {                                      optional: joint angles (degrees), compiled
//       "right_shoulder": {"abduction": 45,              against the grid's skeleton into selections
//                          "center": [x, y, z]},         and separations (deform/pose/joint_pose.h);
//       "right_elbow": {"flexion": 120} },               "selections" may then be left out
//     "joint_options": {"zone": "parent",              optional: how joints compile (PoseJointOptions)
//                       "margin_mm": 50, "groups": "parts"},
//     "articulated": true,                             optional: pose the joints on the transfer mesh that
//                                                      resolves the skeleton (no selections or separations)
//     "separations": [                                 optional: limb separation (cage and TM)
//       { "groups": ["right_arm", "trunk"],            two label groups (label_groups.h names)
//         "region": {"min": [x, y, z], "max": [x, y, z]},    optional; the whole grid when absent
//         "cut_region": {"min": [x, y, z], "max": [x, y, z]} }   optional TM cut region; default: region
//     ]
//   }
// Coordinates are millimetres in the image's world frame (RAS, as nibabel
// computes it from the NIfTI sform/qform; world_frame.h), or with "frame":
// "grid" in the grid frame (origin + spacing .* ijk is the centre of voxel
// ijk; the two agree for grids stored without rotation or axis flips). Being
// in mm, a pose survives regenerating the cage. The pipeline works in the
// grid frame: poseInGridFrame (pose_frame.h) converts.
// A selection takes the cage vertices inside its box (bounds included) or
// sphere (distance <= radius), or the vertex nearest each of its points. A transform maps x to
//   R(axis, angle) (x - center) + center + translation.
// Selections apply in file order and a vertex selected more than once
// belongs to the LAST selection that selects it (so "fix everything, then
// move the arm" is written as two selections).
// Errors name the file: unreadable file, invalid JSON, unknown or missing
// keys, wrong types, non-finite numbers, an empty box, a radius <= 0, a zero
// rotation axis, and a selection that selects no cage vertex:
//   "<path>: selection 'right arm' selects no cage vertex";
// for joints: an unknown joint or body-part name, an angle the joint lacks
// (an elbow has no abduction) or outside its range:
//   "<path>: joint 'right_elbow' flexion 170 is outside its range [0, 150] degrees".
// Separations are not handles: they tell the pre-processing which label
// groups the inset cage and the transfer mesh keep apart (thesis 4.2.1), so
// that a pose that moves a limb away from the trunk carries the separation
// it needs; an unknown group name is an error naming the file.

#include "geometry/deform/cage/cage_builder.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace vox::skeleton {
enum class JointId : std::uint8_t;
}

namespace vox {

struct PoseTransform {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit length
  double angleDeg = 0.0;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  // The transform applied partially: angle and translation scaled by
  // `fraction` in [0, 1] (0: identity, 1: the full transform).
  Eigen::Vector3d apply(const Eigen::Vector3d& x, double fraction = 1.0) const;
};

// Everywhere: no shape, only the restrictions (body parts) select.
enum class SelectionShape { Box, Sphere, Points, Everywhere };

struct PoseSelection {
  std::string name;
  SelectionShape shape = SelectionShape::Box;
  Eigen::Vector3d boxMin = Eigen::Vector3d::Zero();
  Eigen::Vector3d boxMax = Eigen::Vector3d::Zero();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // sphere
  double radius = 0.0;                               // sphere
  // Points: the cage vertex nearest each point (among those the part and
  // group restrictions leave); the viewer saves picked vertices this way.
  std::vector<Eigen::Vector3d> points;
  bool fixed = false;                                // else `transform` moves it
  PoseTransform transform;
  // Restricts the selection to one connected part of the cage: the part of
  // the cage vertex nearest this point (inset cages split limbs off into
  // parts whose boxes overlap other parts).
  std::optional<Eigen::Vector3d> part;
  // Restricts the selection to the cage vertices whose nearest foreground
  // voxel belongs to this label group (a LabelGroup value, label_groups.h):
  // a box around a hanging arm also holds cage vertices of the hip beside
  // it. Needs the organ table that defines the groups.
  std::optional<Label> group;
  // Restricts the selection to the cage vertices whose nearest foreground
  // voxel belongs to one of these body parts (skeleton::Part values,
  // skeleton/body_parts.h). Needs the body-part grid (a joint pose, or a
  // user's parts grid).
  std::vector<Label> bodyParts;

  bool contains(const Eigen::Vector3d& p) const;
};

// A joint of the skeleton turned by anatomical angles (skeleton/joints.h
// states the axes, signs and ranges), with optional overrides of the joint's
// estimated centre and left-right (flexion) axis, in the pose's frame.
struct PoseJoint {
  std::string name;                      // a joint name of skeleton/joints.h ("right_shoulder")
  std::array<double, 3> degrees{};       // flexion, abduction (lateral_flexion for neck and head), rotation
  std::optional<Eigen::Vector3d> center;  // mm
  std::optional<Eigen::Vector3d> axis;    // any length > 0; oriented to the body's right when used

  bool operator==(const PoseJoint&) const = default;
};

// A limb separation (cage_builder.h) and where it cuts the transfer mesh.
// The TM is cut inside cutRegion, or inside the cage's region when empty; a
// separation whose region covers a joint (so that the cage splits the limb
// off as its own part) keeps the TM whole at the joint with a cutRegion that
// stops short of it.
struct PoseSeparation {
  LimbSeparation cage;  // groups are LabelGroup values (label_groups.h)
  std::optional<Eigen::AlignedBox3d> cutRegion;

  LimbSeparation cut() const { return {cage.groupA, cage.groupB, cutRegion ? cutRegion : cage.region}; }
};

// How a pose's joints are compiled (deform/pose/joint_pose.h states the
// defaults): where the cage vertices near a turned joint go ("parent",
// "free", "child"), how far down the limb that zone and the separations'
// cut-off reach, and whether the separations' label groups come from the
// body parts or the organ names.
struct PoseJointOptions {
  std::optional<std::string> zone;
  std::optional<double> marginMm;
  std::optional<std::string> groups;  // "parts" or "organs"

  bool operator==(const PoseJointOptions&) const = default;
};

enum class PoseFrame { World, Grid };

struct Pose {
  std::string name;
  PoseFrame frame = PoseFrame::World;
  std::vector<PoseSelection> selections;
  int arapIterations = 10;
  std::vector<PoseSeparation> separations;
  // Joint angles, in file order; compiled into selections and separations
  // against the grid's skeleton before the pipeline (deform/pose/joint_pose.h).
  std::vector<PoseJoint> joints;
  PoseJointOptions jointOptions;
  // "articulated": true: a joint pose for the transfer mesh that resolves
  // the skeleton (deform/articulated_pose.h); `deform`, `render` and
  // `prepare` pose it there as with --articulated. Joints only: no
  // selections or separations.
  bool articulated = false;
};

// Reading and writing (pose_json.cpp). Throws InputError(source, ...) on
// any fault listed above.
Pose parsePose(const std::string& jsonText, const std::string& source);
Pose readPose(const std::string& path);
// Serializes with the same schema (readPose(writePose(p)) == p); atomic write.
std::string poseToJson(const Pose& pose);
void writePose(const std::string& path, const Pose& pose);

// The one place a joint angle is checked against its joint (skeleton/joints.h
// states the degrees of freedom and their ranges), for pose files and the
// viewer's edits and scripts alike. jointDof: the index (skeleton::Dof) of
// the degree of freedom `dof` names, else InputError(source, "joint
// 'right_elbow' has no 'abduction' (it has flexion<alsoAllowed>)").
// checkJointAngle: InputError(source, "joint 'right_elbow' flexion 170 is
// outside its range [0, 150] degrees") for an angle outside the range (or
// not finite).
int jointDof(skeleton::JointId joint, const std::string& dof, const std::string& source, const std::string& alsoAllowed = "");
void checkJointAngle(skeleton::JointId joint, int dof, double degrees, const std::string& source);

// The ARAP handle set a pose induces on a cage.
struct PoseHandles {
  std::vector<std::int32_t> vertices;   // cage vertex ids, increasing
  std::vector<std::int32_t> selection;  // per handle: the selection (index into Pose::selections) that owns it
};

// Connected parts of a cage: per vertex, a representative vertex of its part
// (vertices joined through triangles share one).
std::vector<std::int32_t> cageParts(const TriMesh& cage);

// Throws InputError(source, "selection '<name>' selects no cage vertex") for
// a selection whose box or sphere holds no cage vertex (before later
// selections take any of them over). vertexGroups: per cage vertex, the
// label group nearest it (nearestGroups), needed by selections with a
// "group" (InputError(source, ...) without it); vertexParts: per cage
// vertex, the body part nearest it, needed by selections with "body_parts".
PoseHandles selectHandles(const Pose& pose, const TriMesh& cage, const std::string& source,
                          std::span<const Label> vertexGroups = {}, std::span<const Label> vertexParts = {});
// True when a selection restricts itself to a label group.
bool usesLabelGroups(const Pose& pose);
// True when a selection restricts itself to body parts.
bool usesBodyParts(const Pose& pose);

// What a pose (or a command's option) needs the grid's organ table for: limb
// separation and selections by label group find the label groups from the
// organ names, joints and body parts find the bones.
enum class OrganTableNeed { Separation, LabelGroup, Bones };
// The one place the rule is stated: unless `present`, throws
// InputError(source, "<what> needs the grid's organ table (--organs) ...")
// (a UsageError when `usage`: the source is a command-line option).
void requireOrganTable(bool present, OrganTableNeed need, const std::string& source, bool usage = false);

// Targets of the handles (#handles by 3, rows in handles.vertices order) for
// the pose applied by `fraction` in [0, 1]: fixed handles stay at their rest
// position, the others get their selection's transform scaled by fraction.
Eigen::MatrixX3d handleTargets(const Pose& pose, const PoseHandles& handles, const TriMesh& cage, double fraction = 1.0);

}  // namespace vox
