#pragma once
// Joints of the skeleton: which body parts each joins, its degrees of
// freedom with their anatomical ranges, and its centre and axes estimated
// from the bones (grid frame, mm).
//
// Estimation (bones from body_parts.h; a bone's long axis is the principal
// axis of its voxel centres, its ends the 0.5 % and 99.5 % quantiles along
// it):
//  - shoulder, hip: a sphere fitted (least squares, then trimmed of points
//    off it by more than half a voxel diagonal, three times) to the surface
//    voxels of the humeral / femoral head: those within 12 % (humerus) or
//    10 % (femur) of the bone's length of its voxel nearest the trunk's
//    (pelvis') bones among those of its proximal quarter (the end away from
//    the forearm / lower-leg bones), which is on the head, facing the
//    glenoid (acetabulum). A fit whose radius is outside 2-20 % of the bone's length,
//    or whose sphere misses that nearest voxel by more than a voxel diagonal,
//    falls back to the centroid of those voxels.
//  - elbow, knee: the centroid of the humerus' (femur's) distal end, the
//    voxels within 8 % of its length of the end away from the shoulder
//    (hip): epicondyles and condyles. The hinge axis is that end's widest
//    direction across the bone (the epicondylar axis) when it is at least
//    1.5 times wider than deep, else the body's left-right axis.
//  - wrist, ankle: the centroid of the forearm (lower-leg) bones' distal
//    6 %; the ankle's axis is the malleoli's widest direction as above, the
//    wrist's the body's left-right axis.
//  - neck, head: the centroids of the cervical spine's lower and upper 15 %.
// Every joint but the shoulders and hips is then moved across its flexion
// axis, within an eighth of the parent bone's length, to the nearest place
// where the child's bone end (the forearm bones, tibiae, hand and foot
// bones, the cervical spine against the thoracic, the cranium against the
// cervical spine) turns clear of the parent's bone over the joint's range,
// every 10 degrees of each degree of freedom ("..., cleared over flexion").
// Each joint's long axis points from its centre to the next joint down the
// chain (or the child bone's centroid). The flexion axis is the hinge found
// on the bone end (made perpendicular to the bone, pointing to the body's
// right), else the body's left-right axis; abduction turns about the body's
// front-back axis, rotation about the long axis. Clinical angles are
// measured against the body's planes, not the bone's rest tilt: a shoulder
// abduction turns the arm in the frontal plane even though the ICRP arms
// hang slightly backwards.
//
// Angle conventions (degrees; docs/POSES.md):
//   flexion: about the left-right axis; positive moves the limb forward
//     (shoulder, elbow, wrist, hip), the lower leg backward (knee), the toes
//     up (ankle: dorsiflexion), the face down (neck, head);
//   abduction (lateral_flexion for neck and head): in the frontal plane;
//     positive moves a limb away from the midline, the head towards the
//     right shoulder;
//   rotation: about the long axis; positive turns a limb's front towards
//     the midline (internal rotation), the face towards the right.
// A joint's rotation is R = R_flexion R_abduction R_rotation, all about axes
// fixed in the parent part (rotation about the long axis first).

#include "geometry/skeleton/body_parts.h"

#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace vox::skeleton {

enum class JointId : std::uint8_t {
  Neck,
  Head,
  RightShoulder,
  RightElbow,
  RightWrist,
  LeftShoulder,
  LeftElbow,
  LeftWrist,
  RightHip,
  RightKnee,
  RightAnkle,
  LeftHip,
  LeftKnee,
  LeftAnkle,
};
inline constexpr int kJointCount = 14;

enum class Dof : std::uint8_t { Flexion = 0, Abduction = 1, Rotation = 2 };
inline constexpr int kDofCount = 3;

// The fixed description of a joint.
struct JointKind {
  JointId id;
  const char* name;          // "right_shoulder"
  Part parent, child;        // child moves with the joint
  Side side;                 // Axial for neck and head
  double flexionSign;        // flexion axis = flexionSign * the left-right axis
  std::array<const char*, kDofCount> dofNames;  // nullptr: the joint lacks it
  std::array<std::array<double, 2>, kDofCount> range;  // degrees, [min, max]
};

const JointKind& jointKind(JointId id);
inline bool isWrist(JointId id) { return id == JointId::RightWrist || id == JointId::LeftWrist; }
inline bool isElbow(JointId id) { return id == JointId::RightElbow || id == JointId::LeftElbow; }
std::optional<JointId> jointFromName(const std::string& name);
std::string jointNames();  // "neck, head, right_shoulder, ..." for messages
// The joint whose child is `part` (nullopt for the trunk and pelvis).
std::optional<JointId> jointMoving(Part part);
// The part `part` hangs from (trunk for the pelvis; None for the trunk).
Part parentPart(Part part);
// The joint between parts a and b when one hangs from the other by it.
std::optional<JointId> jointBetween(Part a, Part b);

struct Joint {
  JointId id = JointId::Neck;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();        // grid frame, mm
  Eigen::Vector3d longAxis = Eigen::Vector3d::UnitZ();     // unit, towards the child's far end
  Eigen::Vector3d leftRight = Eigen::Vector3d::UnitX();    // unit flexion axis (up to the joint's sign), towards the body's right
  Eigen::Vector3d anterior = -Eigen::Vector3d::UnitY();    // the body's front-back axis (abduction)
  Eigen::Vector3d superior = Eigen::Vector3d::UnitZ();     // the body's up
  double radius = 0.0;       // articular sphere, mm: fitted (shoulder, hip), up to the forearm bones (wrist); 0 otherwise
  std::string method;        // how the centre was found ("sphere fit", "distal end", ...)
  std::string axisMethod;    // how leftRight was found ("bone end width", "body axis", "given")

  const JointKind& kind() const { return jointKind(id); }
  // Unit axis of a degree of freedom, oriented so that a positive angle
  // follows the conventions above.
  Eigen::Vector3d axis(Dof dof) const;
  // R_flexion R_abduction R_rotation (angles in degrees).
  Eigen::Matrix3d rotation(const std::array<double, kDofCount>& degrees) const;
};

// The joint `id` among `joints` (nullptr when absent).
const Joint* findJoint(std::span<const Joint> joints, JointId id);

struct SphereFit {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0.0;
  double rms = 0.0;  // of the distances to the sphere over the points used
  std::size_t points = 0;
};
// Least-squares sphere through `points` (algebraic fit, then Gauss-Newton on
// the geometric distances); nullopt for fewer than 4 points or a degenerate set.
std::optional<SphereFit> fitSphere(std::span<const Eigen::Vector3d> points);

// The joints the bones allow (a joint needs the bones of both its parts),
// in JointId order.
std::vector<Joint> estimateJoints(const GridGeometry& grid, const BodyParts& bones);

}  // namespace vox::skeleton
