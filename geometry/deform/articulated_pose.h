#pragma once
// Posing the articulated transfer mesh (articulated_mesh.h): the bones by
// their parts' rigid motions (hard constraints), the tissue on the other
// side of each sliding cut pulled onto its articular body's surface (soft
// targets, so it can slide along it), and the soft tissue by the injective
// solve (solve/injective_solve.h), the pose applied in steps from rest so
// that no tet inverts on the way:
//  - each step starts from a prediction (every vertex moved by its nearest
//    parts' step motions; a bone's vertex by its own part's), taken vertex
//    by vertex as far as no tet is squeezed, so a tight spot at one joint
//    does not hold back the rest of the body;
//  - the steps hold the bones by stiff soft targets (one squeezed tet then
//    slows only the bones near it), stiffened at the full pose;
//  - a sliding vertex's target is taken in its body's frame: where the
//    owner's bones are now (their best rigid fit), put on the surface there,
//    and carried to the step's pose, so it may slide along the surface
//    whether the bones lead or lag;
//  - a last step puts the bones on their motions exactly: every vertex is
//    moved by its parts' remaining corrections, and where that inverts a
//    tet the bones are chased as hard constraints from where they are;
//  - where tets are still inverted with every bone on its motion, the
//    tissue around them is untangled (solve/untangle.h) with the bones,
//    the still tissue and everything farther away held (in each of the
//    regions untangleRadiiMm gives, while any is left).
//
// Only the tets that can change are solved: a tet whose four vertices move
// with one part is moved rigidly and left out of the solve.

#include "geometry/deform/articulated_mesh.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/deform/solve/contact.h"
#include "geometry/deform/solve/injective_solve.h"
#include "geometry/deform/solve/untangle.h"

#include <Eigen/Geometry>
#include <array>
#include <functional>
#include <span>
#include <vector>

namespace vox {

struct ArticulatedPoseOptions {
  // Pose steps from rest to the full motions: at least `steps`, and for a
  // joint pose stepsPerQuarterTurn per 90 degrees of its largest joint angle
  // (articulatedPoseSteps): the tissue in a crease follows a turn of a few
  // degrees a step, while a larger step leaves the bones behind and the
  // last step's jump folds the tets around them.
  int steps = 8;
  int stepsPerQuarterTurn = 16;
  // The prediction blends a vertex's nearest part's step motion (nearest
  // along the mesh's edges) with the second nearest part's where that is
  // within blendMm of it too.
  double blendMm = 40.0;
  double slidingWeight = 20.0;  // soft pull of a sliding vertex onto its body (w_k of the solve)
  // The steps hold the bones by stiff soft targets of this weight (w_k); a
  // last step puts them on their motions exactly (hard constraints).
  double boneWeight = 1e4;
  // Then, at the full pose, rounds with the bones' weight times 10, 100, ...
  // before they are put on their motions exactly.
  int stiffeningRounds = 3;
  // Still tissue: a tissue vertex farther than this (mm, along the mesh's
  // edges) from every bone of a segment the pose moves stays at rest (a
  // hard constraint in every step), and a tet of such vertices and of
  // unmoved parts' bones only is left out of the solve. The solve is then
  // the tissue around the moved limbs, and tissue far from them (with the
  // trunk's bones the mesh leaves to it) is not dragged by them. <= 0:
  // every tet but the rigid ones is solved.
  double stillBeyondMm = 150.0;
  // The bones of unmoved parts in the steps: true, held at rest; false,
  // soft targets as the moved bones are, so that a pelvis gives way to
  // the thighs on the way (the last step puts them back). Held, the seated
  // pose's thighs fall behind their motions and far more tets invert
  // (docs/BENCHMARKS.md, "Still tissue").
  bool holdUnmovedBones = false;
  // Per mesh vertex (empty: none): the part whose bones, left to the soft
  // tissue, its tets carry (tissueBoneParts, articulated_mesh.h: the
  // pelvis'). A free vertex of a part the pose does not move is still (held
  // at rest in every step) wherever it lies, so the sacrum and the iliac
  // wings beside the turning thighs keep their shape.
  std::vector<skeleton::Part> tissueBoneParts;
  InjectiveSolveOptions solve;
  // Untangling after the last step: the free and sliding tissue within
  // each radius (mm along the mesh's edges) of the inverted tets, in turn,
  // until none is left (the sliding vertices held near their bodies by
  // slidingWeight). Empty: none.
  std::vector<double> untangleRadiiMm = {30.0};
  UntangleOptions untangle;
  // Contact after the untangling: the free tissue's boundary vertices that
  // the pose put into tissue they lay apart from at rest (contact.h: a
  // crease's skin through the skin across it) are drawn to the boundary
  // they crossed, halfway where that boundary's tissue may move too (the
  // two sides meet on a contact surface), and contactMarginMm beyond, by
  // anchors of weight contactWeight, the free and sliding tissue within
  // contactRadiusMm of them solved by the untangling's energy (no tet
  // inverts that was not); a vertex once drawn out stays held where it got.
  // Tissue within contactRadiusMm of a tet the untangling left inverted is
  // left as it is. Up to contactRounds rounds, while any is left; 0: none.
  int contactRounds = 4;
  double contactRadiusMm = 20.0;
  double contactWeight = 1000.0;
  double contactMarginMm = 1.0;
  // The boundary faces' centroids are probed too (ContactOptions::
  // faceCentroids; a face found moves its three vertices): where the two
  // sides' surfaces cross between their vertices (the seated groin).
  ContactOptions contact = [] {
    ContactOptions c;
    c.faceCentroids = true;
    return c;
  }();
  // Called after each step of the approach (1-based) and after the last,
  // hard step (steps + 1) with every vertex of the mesh where that step left
  // it: what a viewer shows of the way, or a benchmark inspects.
  std::function<void(int step, std::span<const Eigen::Vector3d> positions)> onStep;
};

struct ArticulatedPoseReport {
  int steps = 0, iterations = 0;
  std::size_t solvedVertices = 0, solvedTets = 0, constrainedVertices = 0, slidingVertices = 0;
  // Solved vertices held at rest as still tissue (stillBeyondMm), and the
  // tets left out of the solve because every vertex of theirs is still.
  std::size_t stillVertices = 0, stillTets = 0;
  // Tets whose four vertices are prescribed by two or more parts: the solve
  // cannot change them (reported: they deform with their bones).
  std::size_t bridgingTets = 0;
  double minRelativeVolume = 1.0;         // smallest det J over every step's iterates
  std::vector<double> stepMinRelativeVolume;  // per step
  // Per step of the approach: the largest distance (mm) of a bone vertex
  // from where its part's motion puts it at that step (the bones' lag).
  std::vector<double> stepBoneLagMm;
  // Per segment (index = skeleton::Part, then the scapulae): the largest
  // distance (mm) of its bone vertices from their places at the full pose
  // after the stiffened approach, before the last step puts them there.
  std::vector<double> segmentLagMm;
  std::size_t invertedTets = 0;           // in the final positions (all tets)
  // The untangling after the last step: the inverted tets it found, the
  // last radius it took (0: none ran), the vertices it moved, its seconds;
  // the smallest det J of the final positions (every tet but those rigid
  // with one segment).
  std::size_t invertedBeforeUntangling = 0, untangledVertices = 0;
  double untangleRadiusMm = 0.0, untangleSeconds = 0.0;
  double finalMinRelativeVolume = 1.0;
  // Contact: the boundary vertices through the tissue across a crease
  // before the first round and after the last, and the deepest of them
  // (mm from the boundary they crossed), the rounds, the vertices moved
  // (the last round's), the seconds.
  std::size_t penetratingBeforeContact = 0, penetratingAfterContact = 0, contactVertices = 0;
  double deepestPenetrationBeforeMm = 0.0, deepestPenetrationAfterMm = 0.0;
  int contactRounds = 0;
  double contactSeconds = 0.0;
  bool reachedTargets = false;            // the bones reached their motions
  double maxSlidingGapMm = 0.0;           // largest distance of a sliding vertex from its body's surface
  double seconds = 0.0;
};

class ArticulatedPoser {
public:
  explicit ArticulatedPoser(const ArticulatedMesh& mesh, const ArticulatedPoseOptions& options = {});

  // Per segment (index = skeleton::Part, then the scapulae; identity where
  // absent) the rigid motion of the pose at `fraction` of the way from rest
  // (0) to it (1).
  using MotionPath = std::function<std::vector<Eigen::Isometry3d>(double fraction)>;

  // The pose from rest in options.steps steps along `path`: the step's
  // bones where the path puts them at its fraction. A joint pose's path is
  // the forward kinematics of the joint angles scaled by the fraction
  // (jointMotionPath), so every step is a pose of the skeleton: the forearm
  // turns with the upper arm and about the elbow at every step.
  ArticulatedPoseReport pose(const MotionPath& path);
  // The same along each motion's own screw (screwInterpolate): right for a
  // single turned joint, not for a chain (a forearm turned 235 degrees by
  // shoulder and elbow together takes the short way round, 125 degrees the
  // other way).
  ArticulatedPoseReport pose(std::span<const Eigen::Isometry3d> motions);

  // Every vertex of the mesh, posed.
  const std::vector<Eigen::Vector3d>& positions() const { return positions_; }

private:
  // The solve for a pose whose segments at the full pose are `motions`:
  // the still vertices and tets (stillBeyondMm), the solved tets and their
  // vertices' roles, both solvers' precomputation.
  void prepare(std::span<const Eigen::Isometry3d> motions);
  // The bones' and sliding vertices' targets with the segments at `motions`.
  void targets(const InjectiveSolver& solver, std::span<const Eigen::Isometry3d> motions);
  // Moves the solve's positions towards the blended step motion that takes
  // the segments from `from` to `to`, as far as no tet inverts.
  void predict(InjectiveSolver& solver, std::span<const Eigen::Isometry3d> from, std::span<const Eigen::Isometry3d> to);
  using PartTransforms = std::array<Eigen::Isometry3d, kSegmentCount + 1>;
  // Solve vertex i's point p moved by its nearest parts' transforms,
  // blended by nearWeight_.
  Eigen::Vector3d blended(std::size_t i, const PartTransforms& transforms, const Eigen::Vector3d& p) const;
  // `current` (solve positions) moved so that every part's bones land on
  // its motion: each vertex by its nearest parts' corrections, blended as
  // the prediction is.
  std::vector<Eigen::Vector3d> corrected(const std::vector<Eigen::Vector3d>& current, std::span<const Eigen::Isometry3d> motions) const;
  void nearestParts();
  void gather(const InjectiveSolver& solver);
  // Per segment: the rigid motion that best takes its bone vertices from
  // rest to where they are in `solver` (identity for fewer than three).
  PartTransforms partFits(const InjectiveSolver& solver) const;
  // The rigid vertices outside the solve (in tets of one part's bones only)
  // placed by their part's best rigid fit of its bones in `solver`: the
  // mesh as the step left it.
  void placeUnsolved(const InjectiveSolver& solver);
  // Untangles positions_ about its inverted tets (untangleRadiiMm),
  // filling the report's untangling fields but the final count.
  void untangle(std::span<const Eigen::Isometry3d> motions, ArticulatedPoseReport& report);
  // The contact rounds (contactRounds) on positions_.
  void resolveContacts(std::span<const Eigen::Isometry3d> motions, ArticulatedPoseReport& report);
  // Per mesh vertex: solved, not rigid, not still (what the untangling and
  // the contact may move).
  std::vector<std::uint8_t> movableVertices() const;
  // Per mesh vertex: its distance along the mesh's edges to the nearest
  // tet inverted in positions_ (infinite with none); `inverted` their count.
  std::vector<double> distanceToInverted(std::size_t& inverted) const;
  // The movable vertices within `radius` of `dist`'s seeds set free, the
  // sliding ones among them anchored to `onBodies` (slidingWeight); how many.
  std::size_t freeWithin(std::span<const double> dist, double radius, std::span<const std::uint8_t> movable,
                         std::span<const Eigen::Vector3d> onBodies, std::vector<std::uint8_t>& free,
                         std::vector<UntangleAnchor>& anchors) const;
  // Per segment: the largest distance of its bone vertices in `solver`'s
  // positions from constrainedTargets_.
  std::vector<double> boneLag(const InjectiveSolver& solver) const;

  const ArticulatedMesh& mesh_;
  ArticulatedPoseOptions options_;
  std::vector<std::int32_t> solved_;      // solve index -> mesh vertex
  std::vector<Tet> solveTets_;            // the solved tets (solve indices)
  std::vector<std::int32_t> constrained_, sliding_;  // solve indices
  // Solve indices: the still free and sliding vertices (hard at rest in
  // both solvers), the approach's hard vertices (those, and with
  // holdUnmovedBones the bones of unmoved segments) and its soft ones
  // (sliding, then the other bones).
  std::vector<std::int32_t> still_, approachHard_;
  std::vector<std::size_t> approachSoftBones_;  // indices into constrained_
  // Per solve index: still (still tissue, or a bone of an unmoved segment);
  // the prediction leaves it where it is.
  std::vector<std::uint8_t> stillSolve_;
  std::vector<std::vector<std::pair<std::int32_t, double>>> edges_;  // per mesh vertex: neighbours and lengths
  std::vector<std::array<std::pair<double, skeleton::Part>, 2>> nearest_;  // per mesh vertex: two nearest parts
  std::array<std::vector<std::int32_t>, kSegmentCount + 1> partConstrained_;  // per part: its constrained solve indices
  std::vector<Eigen::Vector3d> constrainedTargets_, slidingTargets_;
  std::vector<Eigen::Vector3d> positions_;
  InjectiveSolver solver_;    // bones hard (the last step)
  InjectiveSolver approach_;  // bones soft (the steps)
  std::size_t bridgingTets_ = 0, solvedTets_ = 0, stillTets_ = 0;
  // Per solved vertex: its two nearest parts and their weights.
  std::vector<std::array<skeleton::Part, 2>> nearPart_;
  std::vector<double> nearWeight_;  // weight of the nearest; 1 - it of the second
};

// The steps for a joint pose: options.steps, or more, stepsPerQuarterTurn
// per 90 degrees of the largest angle of any joint's degree of freedom.
int articulatedPoseSteps(std::span<const PoseJoint> angles, const ArticulatedPoseOptions& options);

// A joint pose's path: at each fraction the forward kinematics of every
// joint's angles times the fraction (skeleton::partMotions of `joints`, the
// skeleton's joints as posed), the segments of `mesh` by segmentMotions.
ArticulatedPoser::MotionPath jointMotionPath(const skeleton::Skeleton& skeleton, const std::vector<skeleton::Joint>& joints,
                                             const std::vector<PoseJoint>& angles, const ArticulatedMesh& mesh);

}  // namespace vox
