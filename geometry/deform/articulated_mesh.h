#pragma once
// The articulated transfer mesh: a transfer mesh (transfer_mesh.h) that
// resolves the skeleton, so that bones move rigidly by construction and the
// large joints slide.
//
//  - Tags. Each tet carries what it holds: soft tissue, the bone of one body
//    part (kBoneTag + part), or the articular body of one joint
//    (kBodyTag + joint). Bones are resolved where they move against each
//    other: every bone of a part that a joint turns, and the trunk's and
//    pelvis' bones within reach of a joint (the scapula and clavicle at the
//    shoulder, the hip bones at the hip); the trunk's other bones (ribs,
//    spine) stay with the soft tissue there, which no joint moves. The head,
//    the hands and the feet are rigid whole, tissue too, but near the joint
//    that turns them. Tets are fine at the interfaces between tags and at
//    the bodies' surfaces, coarse away from them.
//  - Articular bodies. At each ball joint (shoulders, hips) the sphere about
//    the joint centre that reaches up to, but not into, the socket's bone;
//    at each hinge (elbows, knees) the cylinder about the flexion axis
//    through the joint centre that reaches up to, not into, the child's bone
//    (the humeral trochlea and the femoral condyles turn inside the ulna and
//    on the tibia). The body belongs to its convex side, the owner: the
//    child at a ball joint (the humeral and femoral heads), the parent at a
//    hinge. The mesher resolves the analytic surface (buildTransferMesh's
//    relabel), so its vertices lie on the sphere or cylinder, not on a voxel
//    staircase.
//  - Sliding cut. Each body's tets are cut from every other tet (cutTransferMesh
//    with CutSides) across the body's surface except where the owner's shaft
//    leaves it (the attachment: a cone about the owner's bone axis at a ball,
//    an angular sector about the axis at a hinge). The joint's rotation maps
//    the body's surface onto itself (a rotation about the sphere's centre,
//    about the cylinder's axis), so the tissue on the other side of the cut
//    slides along it without a gap or an overlap.
//  - Limb cuts. Where a limb's tissue touches another label group's (an arm
//    hanging against the trunk, the thighs against each other) beyond
//    limbCutMarginRadii head radii down the limb from the joint that carries it (the
//    shoulder, the hip), the mesh is cut between them (cutTransferMesh), so
//    a turn parts them instead of tearing tets; at the joint the tissue stays
//    joined. A leg is cut from the trunk in front of its hip (the groin) and
//    only a little behind it (legTrunkCut): under the buttock the phantom's
//    tissue is one, which a flexed hip stretches. A tet's group is that of
//    its part (the skeleton's part at its centroid for tissue, its bone's or
//    body's part otherwise).
//  - Vertex roles. A vertex of a bone or body tet of exactly one part is
//    Rigid: its part's rigid motion places it (a hard constraint: a posed
//    voxel that maps back into a bone copies that bone). A vertex on the
//    outer side of a cut that is not Rigid is Sliding: it stays on the body's
//    surface. A vertex where bones of two parts meet without a cut (wrist,
//    ankle, neck) is Free and counted. An edge between vertices of two parts
//    is split at its midpoint (a Free vertex), so no tet is held whole by
//    two parts that move against each other. Free vertices are the soft
//    tissue, placed by the injective solve.

#include "geometry/deform/transfer_mesh.h"
#include "geometry/label_grid.h"
#include "geometry/organ_table.h"
#include "geometry/skeleton/skeleton.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

inline constexpr std::int32_t kSoftTissueTag = 1;
inline constexpr std::int32_t kBoneTag = 1;   // + skeleton::Part: 2..17
inline constexpr std::int32_t kBodyTag = 32;  // + skeleton::JointId: 32..45

// Rigid segments: the body parts (skeleton::Part, 1..kPartCount), the
// scapulae, which the body-part grid counts with the trunk but the
// articulated mesh moves with their shoulders, and the patellae, which it
// counts with the lower legs but the mesh slides down the femur as the knee
// bends (segmentMotions). Motions and per-part arrays of the articulated
// mesh are indexed by segment.
inline constexpr int kRightScapula = skeleton::kPartCount + 1;
inline constexpr int kLeftScapula = skeleton::kPartCount + 2;
inline constexpr int kRightPatella = skeleton::kPartCount + 3;
inline constexpr int kLeftPatella = skeleton::kPartCount + 4;
inline constexpr int kSegmentCount = skeleton::kPartCount + 4;
// partName for a body part, "right_scapula" ... "left_patella" beyond.
const char* segmentName(int segment);
// The body part a segment belongs to: itself for a part, the trunk for a
// scapula, the lower leg for a patella.
skeleton::Part segmentPart(int segment);

enum class ArticularShape : std::uint8_t { Sphere, Cylinder };

struct ArticularBody {
  skeleton::JointId joint = skeleton::JointId::RightShoulder;
  ArticularShape shape = ArticularShape::Sphere;
  skeleton::Part owner = skeleton::Part::None;  // carries the body (convex side)
  skeleton::Part other = skeleton::Part::None;  // slides on it
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // grid frame, mm (on the axis for a cylinder)
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();   // cylinder axis (unit)
  double radius = 0.0, halfLength = 0.0;             // mm; halfLength: cylinder only
  Eigen::Vector3d attachment = -Eigen::Vector3d::UnitZ();  // unit: from the centre towards the owner's shaft
  double attachmentHalfAngleDeg = 50.0;

  std::int32_t tag() const { return kBodyTag + std::int32_t(joint); }
  bool contains(const Eigen::Vector3d& p) const;
  // The point of the body's surface nearest p.
  Eigen::Vector3d project(const Eigen::Vector3d& p) const;
  // Outside the attachment: where the body's surface is cut.
  bool cutAt(const Eigen::Vector3d& p) const;
  // How far p lies outside the body (0 inside).
  double distanceOutside(const Eigen::Vector3d& p) const;
  // The point nearest p on the surface that the joint's rotation maps onto
  // itself through `rest` (a point of the body's rest frame): the sphere
  // about the centre through it, or the cylinder about the axis through it
  // (its end plane where `rest` lies on an end disc). A sliding vertex
  // whose rest place is on the body's own surface slides on that surface;
  // one off it (on the owner's bone beside the body) slides at its own
  // distance.
  Eigen::Vector3d slide(const Eigen::Vector3d& p, const Eigen::Vector3d& rest) const;
};

struct ArticulatedMeshOptions {
  double fineSizeVoxels = 3.0;   // tet size near resolved bones and bodies, in the grid's finest spacing
  double coarseSizeMm = 40.0;    // tet size far from them
  double gradingMm = 60.0;       // the size grows from fine to coarse over this distance
  double trunkBoneReachMm = 90.0;   // trunk bones this near a joint centre are resolved
  double pelvisBoneReachMm = 90.0;  // pelvis bones (hip bones, sacrum) this near a joint centre are resolved
  // Parts held rigid whole, bone and tissue (no pose bends them), except
  // within jointClearanceMm of the joint that moves them, whose tissue the
  // joint's turn bends.
  std::vector<skeleton::Part> rigidWholeParts = {skeleton::Part::Head, skeleton::Part::RightHand, skeleton::Part::LeftHand,
                                                 skeleton::Part::RightFoot, skeleton::Part::LeftFoot};
  double jointClearanceMm = 30.0;
  // ... and within this distance of another part's bone (the forearm's
  // radius and ulna beside the hand's tissue across a wrist 60 mm wide,
  // which the joint's sphere does not reach): a bone that turns against a
  // rigid whole part needs soft tissue between them to bend.
  double wholePartBoneClearanceMm = 20.0;
  // The whole part's own bones this near another part's bone soft too (at
  // most wholePartBoneClearanceMm; 0: none, the bones stay rigid). The
  // carpals' face on the radius soft unbends the wrist's last folds but
  // bends the hand's bones (docs/BENCHMARKS.md, "Untangling").
  double wholePartOwnBoneClearanceMm = 0.0;
  double bodyMarginVoxels = 0.5;   // a body stops this far (finest spacing) short of the other part's bone
  double minBodyRadiusVoxels = 2.0;  // a smaller body is not built (the joint is not cut)
  double attachmentHalfAngleDeg = 50.0;
  // The same at an elbow (an angular sector about the flexion axis about
  // the humerus' shaft); < 0: attachmentHalfAngleDeg. Narrow, so that the
  // cut follows the humerus' end up to where its shaft leaves: the AF's
  // olecranon lies in the humerus' fossa about 30 degrees behind the shaft,
  // under 2 mm from it, and at 50 degrees the tets between them (edges
  // split between the two bones) kept ulna and humerus joined there, so
  // that the phone call's elbow could not turn (docs/BENCHMARKS.md, "The
  // elbow's sliding cut up to the humerus' shaft"). The knees keep
  // attachmentHalfAngleDeg.
  double elbowAttachmentHalfAngleDeg = 20.0;
  // A sphere body at each wrist too, about its centre in the carpus up to
  // the forearm bones, owned by the hand (docs/BENCHMARKS.md, "The wrist in
  // the carpus": not better on the phone call).
  bool wristBodies = false;
  // The owner's bone within this many voxels (the grid's coarsest
  // spacing) outside its body, away from the attachment, joins the body:
  // the sliding cut follows the bone's staircase there instead of cutting
  // through it, so that the owner's bone end turns past the other side's
  // (the 8 mm slices' staircases of a femoral head and its acetabulum
  // cross as the hip turns) without tissue between them. Both stay rigid;
  // where the staircases cross they overlap by less than a voxel. Two
  // voxels take the femoral neck's base in as well: at one, the neck's
  // staircase 9 to 16 mm outside the hip's sphere lay a tet or two from the
  // acetabular rim, and the hips' turn crushed the tissue between
  // (docs/BENCHMARKS.md, "The femoral neck in the hip's body"). 0: the body
  // is the sphere or cylinder alone.
  double ownerShellVoxels = 2.0;
  // At a hinge, the owner's bone up to hingeOwnerReachMm outside the
  // cylinder, away from the attachment, joins the body as well: the
  // sliding cut follows the owner's bone end all round, where the cylinder
  // alone does not reach (the femoral trochlea 60 mm in front of the knee's
  // axis, under the patella that turns with the lower leg; the humerus'
  // epicondyles). The tissue between the other part's bone and the owner's
  // then moves with the other part instead of being sheared across a gap
  // of a few millimetres. 0: the ball joints' shell alone.
  double hingeOwnerReachMm = 60.0;
  // At these ball joints the bone of the two parts within
  // yieldingShellVoxels (the grid's coarsest spacing) outside the body's
  // sphere is soft tissue, not rigid: the staircases of the head's and the
  // socket's surfaces cross as the joint turns, and a rigid shell there has
  // nowhere to go. Off by default (0): those bone voxels are then no longer
  // moved rigidly, and the humerus' shape measures below the bones' bar
  // (docs/POSES.md, "A yielding shell at the shoulders").
  std::vector<skeleton::JointId> yieldingShellJoints = {skeleton::JointId::RightShoulder, skeleton::JointId::LeftShoulder};
  double yieldingShellVoxels = 0.0;
  // Limb cuts start this many joint radii (the humeral or femoral head's)
  // down the limb from its shoulder or hip (<= 0: no limb cuts).
  double limbCutMarginRadii = 1.5;
  // Where a leg is cut from the trunk: nowhere; in front of the plane
  // legTrunkCutBehindMm behind its hip's centre (normal to the hip's
  // anterior axis: the groin, which a flexed hip closes); or all round.
  // Under the buttock the phantom's thigh and buttock are one tissue, which
  // a flexed hip stretches: cut there, the seated pose opened a notch under
  // the AF's buttock; cut nowhere, the flexed thighs pressed the groin into
  // the lower abdomen (the bladder and sigmoid colon 3.6 % under their
  // volume) (docs/BENCHMARKS.md, "The bones left to the tissue held; the
  // buttock joined to the thigh").
  enum class LegTrunkCut : std::uint8_t { None, Front, All };
  LegTrunkCut legTrunkCut = LegTrunkCut::Front;
  double legTrunkCutBehindMm = 40.0;
  // Each scapula its own rigid segment, turned by its shoulder's rhythm
  // (segmentMotions); false: the trunk's (docs/POSES.md: not yet the
  // default, the tissue between the scapula and the ribs has no sliding
  // plane).
  bool movingScapulae = false;
  // Each patella its own rigid segment (markPatellae), which slides down
  // the femur's trochlea as its knee bends (segmentMotions); false: the
  // lower leg's.
  bool movingPatellae = true;
  // Bone-gap cuts: at these joints, where the resolved bones of the joint's
  // two parts lie within boneGapMm of each other and within boneGapReachMm
  // of the joint's centre, the tissue between them is cut along the surface
  // midway between the two bones (each tet goes with the nearer bone), so
  // that each side moves with its own bone and the two slide over each
  // other as the joint turns. At the wrist, turned about the carpus, the
  // carpals pass within a millimetre of the radius' end, across tissue a
  // tet or two thick that no placement of its vertices keeps positive
  // (docs/BENCHMARKS.md, "Where the AF phone call's wrist folds"; the cut's
  // figures: "The bone-gap cut at the wrists, by default"). At the elbows
  // the olecranon's tissue in the humerus' fossa, at the hips the femoral
  // neck's beside the acetabulum's rim (docs/BENCHMARKS.md, "The bone-gap
  // cut at the elbows and the hips", "Cut-off tissue with its nearest
  // bone"). 0: none (deform --bone-gap 0).
  std::vector<skeleton::JointId> boneGapJoints = {skeleton::JointId::RightWrist, skeleton::JointId::LeftWrist, skeleton::JointId::RightElbow,
                                                  skeleton::JointId::LeftElbow,  skeleton::JointId::RightHip,  skeleton::JointId::LeftHip};
  double boneGapMm = 10.0;
  double boneGapReachMm = 40.0;
  // The tets that touch the mesh's surface (the skin, and without
  // boneGapBesideCuts the faces of the cuts before it) are left out of the
  // bone-gap cut: a slit inside the tissue, the skin closed over it. false:
  // the cut may reach the skin.
  bool boneGapKeepsSkin = true;
  // With boneGapKeepsSkin: the skin alone is kept, not the faces of the
  // cuts before, so a tet beside a sliding or limb cut may be cut (the
  // olecranon's tissue from the humerus' in its fossa); where that would
  // close a piece of tissue off from every bone, body and sliding surface,
  // cutOffTissueRigid places it; without, that piece's tets and the cut's
  // beside it stay uncut.
  bool boneGapBesideCuts = true;
  // With boneGapBesideCuts: the cut may close pieces of tissue off from
  // every bone, body and sliding surface, and each such piece moves rigidly
  // with the part of the bone nearest to it at rest (the olecranon's fat
  // pad with the humerus whose fossa holds it) instead of keeping its tets
  // out of the cut.
  bool cutOffTissueRigid = true;
  // The mesher's options; the articulated mesh rebuilds the mesh for every
  // uncovered centre (no caps): the hard postures' solves were measured on
  // that mesh, and a mesh with caps instead changes them (the seated pose
  // then inverts several times as many tets: docs/BENCHMARKS.md, "Caps
  // instead of meshing again").
  TransferMeshOptions transferMesh = {.coverageCaps = false};
};

enum class VertexRole : std::uint8_t { Free, Rigid, Sliding };

struct ArticulatedMesh {
  TetMesh mesh;  // rest, grid frame mm, labels: the tags above; cut at every body
  std::vector<ArticularBody> bodies;
  std::vector<CutReport> cuts;  // per body
  CutReport limbCut;            // between the limbs and the groups they touch
  CutReport boneGapCut;         // between two parts' bones across a narrow gap (boneGapJoints)
  std::vector<VertexRole> role;                 // per vertex
  std::vector<skeleton::Part> vertexPart;       // per vertex: the part of a Rigid vertex, else None
  std::vector<std::int8_t> vertexBody;          // per vertex: the body (index) a Sliding vertex stays on, else -1
  std::size_t conflictVertices = 0;             // in bones of two parts without a cut: Free
  std::array<std::size_t, kSegmentCount + 1> rigidVertices{};  // per segment
  std::size_t resolvedBoneVoxels = 0;           // bone voxels whose part's bone is resolved
  // Positions on the cuts (every copy of a vertex together) put onto their
  // body's surface, and those left where that would degenerate a tet.
  std::size_t snappedVertices = 0, unsnappedVertices = 0;
  // Edges between vertices of two parts (tissue spanning the gap between
  // two bones in one tet) split at their midpoints, free vertices.
  std::size_t splitEdges = 0;
  // Vertices of pieces of tissue closed off by the cuts, made rigid with
  // the nearest bone's part (cutOffTissueRigid).
  std::size_t cutOffTissueVertices = 0;
  // Per body: the triangles of its side of the sliding cut (rest frame).
  // At a hinge, whose body takes the owner's bone end beyond the cylinder
  // (hingeOwnerReachMm), they are the surface its sliding vertices stay on
  // (slideOnBody).
  std::vector<std::vector<std::array<Eigen::Vector3d, 3>>> bodySurfaces;
  double seconds = 0.0;
};

// Where sliding vertex p (in the rest frame of body `body`'s owner) goes,
// its rest place `rest`: at a ball joint ArticularBody::slide (the sphere
// through its rest place); at a hinge the nearest point of the body's cut
// surface (bodySurfaces): the tissue stays on the owner's bone end as the
// other side turns, where that end is no cylinder (the femoral trochlea
// under the patella), instead of leaving a gap or pressing into it.
Eigen::Vector3d slideOnBody(const ArticulatedMesh& mesh, std::size_t body, const Eigen::Vector3d& p, const Eigen::Vector3d& rest);

// Per vertex of mesh.mesh: the label group (skeleton/label_groups.h) of the
// part its tets belong to, -1 where they belong to several or to none: the
// sides of the limb cuts, for the contact (ContactOptions::side).
std::vector<std::int32_t> limbGroupSides(const ArticulatedMesh& mesh, const skeleton::Skeleton& skeleton);

// Whether every vertex of `t` is rigid with one and the same segment: the
// tet moves rigidly with it (the poser leaves it out of the solve).
bool rigidWithOneSegment(const ArticulatedMesh& mesh, const Tet& t);

// The bodies the skeleton's joints allow (a joint whose body would be
// smaller than options.minBodyRadiusVoxels gets none).
std::vector<ArticularBody> articularBodies(const LabelGrid& grid, const LabelGrid& boneParts,
                                           const skeleton::Skeleton& skeleton, const ArticulatedMeshOptions& options = {});

// The articulated transfer mesh of `grid` (the working grid) from its organ
// table's bones and its skeleton (built on the same grid). Throws
// InputError("grid", ...) for a grid without foreground.
ArticulatedMesh buildArticulatedMesh(const LabelGrid& grid, const OrganTable& organs, const skeleton::Skeleton& skeleton,
                                     const ArticulatedMeshOptions& options = {});

// Per vertex of mesh.mesh: Part::Pelvis where a tet around it (one not
// rigid with one segment) holds at rest a voxel of the pelvis' bones that
// the mesh leaves to the soft tissue (the sacrum and the iliac wings beyond
// options.pelvisBoneReachMm of every joint), None elsewhere. The poser
// holds such a vertex at rest while the pose leaves the pelvis where it is
// (ArticulatedPoseOptions::tissueBoneParts), so the flexed thighs do not
// drag those bones through the buttock. The trunk's bones left to the
// tissue (ribs, spine) are not held: the ribs lie in the tissue that a
// turning shoulder moves (held too, the AF phone call's arm cartilage lost
// more of its volume: docs/BENCHMARKS.md, "The bones left to the tissue
// held; the buttock joined to the thigh").
std::vector<skeleton::Part> tissueBoneParts(const ArticulatedMesh& mesh, const LabelGrid& grid, const OrganTable& organs,
                                            const skeleton::Skeleton& skeleton, const ArticulatedMeshOptions& options = {});

// Per voxel of `grid`: the body part of a bone voxel (organ table names,
// bones.h, and the skeleton's part grid), 0 elsewhere.
LabelGrid bonePartGrid(const LabelGrid& grid, const OrganTable& organs, const skeleton::Skeleton& skeleton);

// The patellae in `boneParts` (bonePartGrid): of each lower leg's bone,
// the 26-connected pieces but the largest whose centre lies above the
// knee's centre (towards the thigh), relabelled kRightPatella or
// kLeftPatella. A side without its knee keeps its labels.
void markPatellae(LabelGrid& boneParts, const skeleton::Skeleton& skeleton);

// The scapulohumeral rhythm: past thresholdDeg of the humerus' elevation
// (the angle between its rest and posed long axes), the scapula turns
// upward by `ratio` of the further elevation, in the same plane, about the
// acromion (its bone's most superior point, next to the clavicle, which
// stays with the trunk); the arm below keeps the orientation its joints give
// and rides on the turned glenoid.
struct ScapularRhythm {
  double ratio = 0.4;
  double thresholdDeg = 30.0;
};

// The motions of every segment (index = segment, kSegmentCount + 1 entries)
// from the forward kinematics' part motions (index = Part): each scapula
// resolved in `mesh` turned by its shoulder's rhythm, the parts below that
// shoulder carried with it; each patella resolved in `mesh` slid along the
// femur: relative to the thigh it turns about the knee's axis by the angle
// that keeps its ligament at its rest length, from its apex (its lowest
// rigid vertex) to the tibial tuberosity (the lower leg's most anterior
// rigid vertex 20 to 70 mm below the knee's centre, across the patella's
// width), at its rest height above the femur's profile (the thigh's rigid
// vertices farthest from the axis in each direction about it, across the
// patella's width).
std::vector<Eigen::Isometry3d> segmentMotions(std::span<const Eigen::Isometry3d> partMotions, const skeleton::Skeleton& skeleton,
                                              const ArticulatedMesh& mesh, const ScapularRhythm& rhythm = {});

// Part `part`'s motion (index = Part; identity where absent) at `fraction`
// of it (screwInterpolate, solve/injective_solve.h).
Eigen::Isometry3d partMotionAt(std::span<const Eigen::Isometry3d> motions, skeleton::Part part, double fraction);

// The rigid vertices of `mesh` placed by their parts' motions (index =
// Part; identity where a part has none), at `fraction` of each motion
// (screwInterpolate, solve/injective_solve.h); other vertices keep their
// entries of `positions`.
void placeRigidVertices(const ArticulatedMesh& mesh, std::span<const Eigen::Isometry3d> motions, double fraction,
                        std::span<Eigen::Vector3d> positions);

// The sliding vertices put on their bodies' surfaces, the bodies moved by
// their owners' motions at `fraction`.
void projectSlidingVertices(const ArticulatedMesh& mesh, std::span<const Eigen::Isometry3d> motions, double fraction,
                            std::span<Eigen::Vector3d> positions);

}  // namespace vox
