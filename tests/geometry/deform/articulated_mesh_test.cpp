#include "geometry/deform/articulated_mesh.h"

#include "geometry/cancellation.h"
#include "geometry/deform/articulated_pose.h"
#include "geometry/deform/solve/contact.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/deform/prepared_state.h"
#include "geometry/synth.h"
#include "geometry/tri_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <span>

namespace vox {
namespace {

using skeleton::JointId;
using skeleton::Part;

constexpr int kFigureSize = 96;

struct Figure {
  LabelGrid grid;
  OrganTable organs;
  skeleton::Skeleton skeleton;
  ArticulatedMesh mesh;
};

const Figure& figure() {
  static const Figure f = [] {
    Figure out{synthesize(SynthKind::SkeletonFigure, kFigureSize), synthOrganTable(SynthKind::SkeletonFigure), {}, {}};
    out.skeleton = skeleton::buildSkeleton(out.grid, out.organs, {"figure", "figure organs", "figure parts"});
    out.mesh = buildArticulatedMesh(out.grid, out.organs, out.skeleton);
    return out;
  }();
  return f;
}

const ArticularBody* bodyOf(const ArticulatedMesh& m, JointId id) {
  for (const ArticularBody& b : m.bodies)
    if (b.joint == id) return &b;
  return nullptr;
}

// A leg is cut from the trunk in front of its hip (the groin, which a
// flexed hip closes), not far behind it, where the thigh's tissue and the
// buttock's are one tissue that the flexed hip stretches.
TEST(ArticulatedMesh, ALegIsCutFromTheTrunkInFrontOfItsHip) {
  const Figure& f = figure();
  ASSERT_EQ(ArticulatedMeshOptions{}.legTrunkCut, ArticulatedMeshOptions::LegTrunkCut::Front);
  // The figure's thighs touch its trunk only about the hips: the cuts from
  // the hips' centres down.
  std::array<std::size_t, 3> faces{};
  for (const auto cut : {ArticulatedMeshOptions::LegTrunkCut::None, ArticulatedMeshOptions::LegTrunkCut::Front,
                         ArticulatedMeshOptions::LegTrunkCut::All}) {
    ArticulatedMeshOptions options;
    options.limbCutMarginRadii = 0.01;
    options.legTrunkCut = cut;
    options.legTrunkCutBehindMm = 0.0;
    faces[std::size_t(cut)] = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options).limbCut.cutFaces;
  }
  EXPECT_LT(faces[0], faces[1]);
  EXPECT_LT(faces[1], faces[2]);
}

// `prepare --articulated` stores the mesh whole: what reads back is what
// was built, found by its options' key and by no other.
TEST(ArticulatedMesh, APreparedStateHoldsItWhole) {
  const Figure& f = figure();
  PreparedState state;
  state.articulatedMeshes.push_back({articulatedMeshOptionsKey({}), f.mesh});
  const PreparedState back = PreparedState::fromBytes(state.bytes(), "figure.vxprep");
  ASSERT_EQ(back.articulatedMeshes.size(), 1u);
  const PreparedArticulatedMesh* found = back.findArticulatedMesh(articulatedMeshOptionsKey({}));
  ASSERT_NE(found, nullptr);
  const ArticulatedMesh& m = found->mesh;
  const ArticulatedMesh& built = f.mesh;
  EXPECT_EQ(m.mesh.positions, built.mesh.positions);
  EXPECT_EQ(m.mesh.tets, built.mesh.tets);
  EXPECT_EQ(m.mesh.labels, built.mesh.labels);
  EXPECT_EQ(m.mesh.labelNames, built.mesh.labelNames);
  ASSERT_EQ(m.bodies.size(), built.bodies.size());
  ASSERT_FALSE(built.bodies.empty());
  for (std::size_t b = 0; b < m.bodies.size(); ++b) {
    const ArticularBody &x = m.bodies[b], &y = built.bodies[b];
    EXPECT_TRUE(x.joint == y.joint && x.shape == y.shape && x.owner == y.owner && x.other == y.other) << b;
    EXPECT_TRUE(x.centre == y.centre && x.axis == y.axis && x.attachment == y.attachment) << b;
    EXPECT_TRUE(x.radius == y.radius && x.halfLength == y.halfLength && x.attachmentHalfAngleDeg == y.attachmentHalfAngleDeg) << b;
  }
  ASSERT_EQ(m.cuts.size(), built.cuts.size());
  for (std::size_t c = 0; c < m.cuts.size(); ++c) {
    EXPECT_EQ(m.cuts[c].splitVertices, built.cuts[c].splitVertices);
    EXPECT_EQ(m.cuts[c].cutFaces, built.cuts[c].cutFaces);
  }
  EXPECT_EQ(m.limbCut.splitVertices, built.limbCut.splitVertices);
  EXPECT_EQ(m.role, built.role);
  EXPECT_EQ(m.vertexPart, built.vertexPart);
  EXPECT_EQ(m.vertexBody, built.vertexBody);
  EXPECT_EQ(m.rigidVertices, built.rigidVertices);
  EXPECT_EQ(m.splitEdges, built.splitEdges);
  EXPECT_EQ(m.snappedVertices, built.snappedVertices);
  ASSERT_EQ(m.bodySurfaces.size(), built.bodySurfaces.size());
  for (std::size_t b = 0; b < m.bodySurfaces.size(); ++b) EXPECT_TRUE(m.bodySurfaces[b] == built.bodySurfaces[b]) << b;
  ArticulatedMeshOptions other;
  other.elbowAttachmentHalfAngleDeg += 1.0;
  EXPECT_EQ(back.findArticulatedMesh(articulatedMeshOptionsKey(other)), nullptr);
  EXPECT_NE(back.summary().find("articulated transfer mesh"), std::string::npos);
}

TEST(ArticulatedMesh, BallJointsAndHingesGetTheirBodies) {
  const Figure& f = figure();
  const ArticularBody* shoulder = bodyOf(f.mesh, JointId::RightShoulder);
  const ArticularBody* elbow = bodyOf(f.mesh, JointId::RightElbow);
  const ArticularBody* hip = bodyOf(f.mesh, JointId::RightHip);
  ASSERT_NE(shoulder, nullptr);
  ASSERT_NE(elbow, nullptr);
  ASSERT_NE(hip, nullptr);
  EXPECT_EQ(shoulder->shape, ArticularShape::Sphere);
  EXPECT_EQ(shoulder->owner, Part::RightUpperArm);
  EXPECT_EQ(elbow->shape, ArticularShape::Cylinder);
  EXPECT_EQ(elbow->owner, Part::RightUpperArm);
  EXPECT_EQ(elbow->other, Part::RightForearm);
  // The sphere holds no bone of another part than the head's.
  const LabelGrid bones = bonePartGrid(f.grid, f.organs, f.skeleton);
  const GridGeometry& g = f.grid.geometry();
  for (const ArticularBody& b : f.mesh.bodies)
    for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
      const Label part = bones.labels()[std::size_t(v)];
      if (part == 0 || Part(part) == b.owner) continue;
      const Index3 c = g.ijk(v);
      EXPECT_FALSE(b.contains(g.voxelCenter(c[0], c[1], c[2]))) << "joint " << int(b.joint) << " holds a bone of part " << int(part);
    }
  EXPECT_NO_THROW(f.mesh.mesh.validate("articulated mesh"));
}

TEST(ArticulatedMesh, BonesAndBodiesAreResolvedAndTheirVerticesRigid) {
  const ArticulatedMesh& m = figure().mesh;
  std::set<std::int32_t> tags(m.mesh.labels.begin(), m.mesh.labels.end());
  // Soft tissue, the limbs' bones and one body per joint.
  EXPECT_TRUE(tags.count(kSoftTissueTag));
  EXPECT_TRUE(tags.count(kBoneTag + std::int32_t(Part::RightUpperArm)));
  EXPECT_TRUE(tags.count(kBoneTag + std::int32_t(Part::RightForearm)));
  for (const ArticularBody& b : m.bodies) EXPECT_TRUE(tags.count(b.tag())) << "joint " << int(b.joint);
  // Every vertex of a bone or body tet is rigid with that tet's part, or a
  // counted conflict.
  std::set<std::int32_t> free;
  for (std::size_t t = 0; t < m.mesh.tetCount(); ++t) {
    if (m.mesh.labels[t] == kSoftTissueTag) continue;
    for (const std::int32_t v : m.mesh.tets[t])
      if (m.role[std::size_t(v)] != VertexRole::Rigid) free.insert(v);
  }
  EXPECT_EQ(free.size(), m.conflictVertices);
  EXPECT_GT(m.rigidVertices[std::size_t(Part::RightForearm)], 4u);
  // Bone and body tets come first: the rasterization's lowest-index tet
  // gives an overlap across a cut to the bone.
  const auto tissue = std::find(m.mesh.labels.begin(), m.mesh.labels.end(), kSoftTissueTag);
  EXPECT_TRUE(std::all_of(tissue, m.mesh.labels.end(), [](std::int32_t l) { return l == kSoftTissueTag; }));
}

// The hands', feet's and head's tissue within wholePartBoneClearanceMm of
// another part's bone stays soft, so that a turn of the wrist, ankle or
// neck has tissue between the two rigid bones to bend; without it the
// hand's rigid tissue lies beside the forearm's bone.
TEST(ArticulatedMesh, AWholePartStaysSoftBesideAnotherPartsBone) {
  const Figure& f = figure();
  const double spacing = f.grid.geometry().spacing.maxCoeff();
  const auto nearestToOtherBone = [](const ArticulatedMesh& m, const std::vector<Part>& whole) {
    std::vector<Eigen::Vector3d> wholeRigid, otherRigid;
    for (std::size_t v = 0; v < m.role.size(); ++v) {
      if (m.role[v] != VertexRole::Rigid) continue;
      const auto part = Part(m.vertexPart[v]);
      const bool isWhole = std::find(whole.begin(), whole.end(), part) != whole.end();
      const bool isLimb = part != Part::Trunk && part != Part::Pelvis && part != Part::None;
      if (isWhole) wholeRigid.push_back(m.mesh.positions[v]);
      else if (isLimb) otherRigid.push_back(m.mesh.positions[v]);
    }
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& a : wholeRigid)
      for (const Eigen::Vector3d& b : otherRigid) nearest = std::min(nearest, (a - b).norm());
    return nearest;
  };
  // The figure's hands and feet are small: 20 mm (the default) leaves
  // them no rigid vertex; five voxels do.
  const std::vector<Part> hands = {Part::RightHand, Part::LeftHand, Part::RightFoot, Part::LeftFoot};
  // Their own bones there too (wholePartOwnBoneClearanceMm), so that no
  // rigid vertex of theirs is left within the distance.
  ArticulatedMeshOptions options;
  options.wholePartBoneClearanceMm = 5.0 * spacing;
  options.wholePartOwnBoneClearanceMm = 5.0 * spacing;
  const ArticulatedMesh cleared = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  const double clear = nearestToOtherBone(cleared, hands);
  EXPECT_LT(clear, 1e9);  // rigid vertices are left
  EXPECT_GE(clear, options.wholePartBoneClearanceMm - spacing);
  // The own bones rigid (the default): the tissue alone gives way, and
  // rigid vertices of the hands' and feet's bones stay nearer.
  options.wholePartOwnBoneClearanceMm = 0.0;
  const ArticulatedMesh bonesRigid = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  EXPECT_LT(nearestToOtherBone(bonesRigid, hands), clear);
  options.wholePartBoneClearanceMm = 0.0;
  const ArticulatedMesh beside = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  EXPECT_LT(nearestToOtherBone(beside, hands), clear - 2.0 * spacing);
}

// Each scapula is its own segment; past 30 degrees of elevation it turns
// upward by 0.4 of the further elevation, in the arm's plane, about its
// acromion, and the arm keeps the orientation its joints give.
// The bone of both parts in a shell just outside each shoulder's sphere is
// soft tissue with the yielding shell (opt-in): bone tets leave it.
TEST(ArticulatedMesh, TheShouldersYieldingShellHoldsNoBoneTet) {
  const Figure& f = figure();
  ArticulatedMeshOptions options;
  options.yieldingShellVoxels = 1.0;
  const ArticulatedMesh yielding = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  const double shell = f.grid.geometry().spacing.maxCoeff();
  const auto boneTetsInShell = [&](const ArticulatedMesh& mesh) {
    std::size_t n = 0;
    for (const ArticularBody& b : mesh.bodies) {
      if (b.joint != JointId::RightShoulder && b.joint != JointId::LeftShoulder) continue;
      for (std::size_t t = 0; t < mesh.mesh.tetCount(); ++t) {
        const std::int32_t tag = mesh.mesh.labels[t];
        if (tag != kBoneTag + std::int32_t(b.owner) && tag != kBoneTag + std::int32_t(b.other)) continue;
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        for (const std::int32_t v : mesh.mesh.tets[t]) c += 0.25 * mesh.mesh.positions[std::size_t(v)];
        const double d = (c - b.centre).norm();
        n += d > b.radius + 0.25 * shell && d < b.radius + 0.75 * shell;
      }
    }
    return n;
  };
  // The mesh resolves the shell to about a tet (the shell is one voxel
  // thick, the tets three): a few bone tets of its boundary reach into it.
  const std::size_t without = boneTetsInShell(f.mesh), with = boneTetsInShell(yielding);
  EXPECT_GT(without, 10u);
  EXPECT_LT(10 * with, without);
  EXPECT_NO_THROW(yielding.mesh.validate("articulated mesh"));
}

TEST(ArticulatedMesh, TheScapulaFollowsItsShouldersRhythm) {
  const Figure& f = figure();
  EXPECT_EQ(f.mesh.rigidVertices[std::size_t(kRightScapula)], 0u);  // not by default
  ArticulatedMeshOptions options;
  options.movingScapulae = true;
  const ArticulatedMesh m = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  EXPECT_GT(m.rigidVertices[std::size_t(kRightScapula)], 10u);
  EXPECT_GT(m.rigidVertices[std::size_t(kLeftScapula)], 10u);
  EXPECT_STREQ(segmentName(kRightScapula), "right_scapula");
  EXPECT_STREQ(segmentName(int(Part::RightForearm)), "right_forearm");
  const skeleton::Joint* joint = f.skeleton.joint(JointId::RightShoulder);
  ASSERT_NE(joint, nullptr);
  const auto motionsFor = [&](double abduction) {
    PoseJoint pj;
    pj.name = "right_shoulder";
    pj.degrees = {0.0, abduction, 0.0};
    const std::vector<PoseJoint> angles{pj};
    const skeleton::PartMotions parts = skeleton::partMotions(skeleton::posedJoints(f.skeleton, angles, "pose"), angles);
    return std::pair{parts, segmentMotions(parts, f.skeleton, m)};
  };
  const auto angleOf = [](const Eigen::Isometry3d& t) { return Eigen::AngleAxisd(t.linear()).angle() * 180.0 / std::numbers::pi; };
  {
    const auto [parts, segments] = motionsFor(20.0);
    ASSERT_EQ(segments.size(), std::size_t(kSegmentCount + 1));
    EXPECT_NEAR(angleOf(segments[std::size_t(kRightScapula)]), 0.0, 1e-9);
    EXPECT_TRUE(segments[std::size_t(Part::RightUpperArm)].isApprox(parts[std::size_t(Part::RightUpperArm)]));
  }
  const auto [parts, segments] = motionsFor(80.0);
  const Eigen::Isometry3d& scapula = segments[std::size_t(kRightScapula)];
  const Eigen::Vector3d d = joint->longAxis.normalized(), posed = parts[std::size_t(Part::RightUpperArm)].linear() * d;
  const double elevation = std::acos(d.dot(posed)) * 180.0 / std::numbers::pi;  // about the 80 degrees asked
  EXPECT_NEAR(elevation, 80.0, 2.0);
  EXPECT_NEAR(angleOf(scapula), 0.4 * (elevation - 30.0), 1e-6);
  EXPECT_NEAR(angleOf(segments[std::size_t(kLeftScapula)]), 0.0, 1e-9);
  // Turned in the arm's plane of elevation.
  EXPECT_GT(Eigen::AngleAxisd(scapula.linear()).axis().dot(d.cross(posed).normalized()), 1.0 - 1e-9);
  // The arm's orientation is kept; it rides on the turned glenoid.
  for (const Part p : {Part::RightUpperArm, Part::RightForearm, Part::RightHand}) {
    EXPECT_TRUE(segments[std::size_t(p)].linear().isApprox(parts[std::size_t(p)].linear(), 1e-9)) << int(p);
    EXPECT_LT((segments[std::size_t(p)] * joint->centre - scapula * joint->centre).norm(), 1e-9) << int(p);
  }
  // The acromion, the pivot, stays; the glenoid (the joint centre) moves.
  EXPECT_GT((scapula * joint->centre - joint->centre).norm(), 1.0);
}

TEST(ArticulatedMesh, TheBodiesSurfaceIsCutOutsideTheAttachmentAndItsVerticesLieOnIt) {
  const ArticulatedMesh& m = figure().mesh;
  ASSERT_EQ(m.cuts.size(), m.bodies.size());
  std::size_t offSurface = 0;
  for (std::size_t b = 0; b < m.bodies.size(); ++b) {
    const ArticularBody& body = m.bodies[b];
    EXPECT_GT(m.cuts[b].cutFaces, 10u) << "joint " << int(body.joint);
    // Sliding vertices sit on the body's surface (snapped there, all but a
    // few the mesher put on a bone's surface close by), or on the owner's
    // bone beside it (the cut follows the bone there).
    const double shell = ArticulatedMeshOptions{}.ownerShellVoxels * figure().grid.geometry().spacing.maxCoeff();
    std::size_t sliding = 0, beside = 0;
    for (std::size_t v = 0; v < m.role.size(); ++v) {
      if (m.role[v] != VertexRole::Sliding || std::size_t(m.vertexBody[v]) != b) continue;
      ++sliding;
      const Eigen::Vector3d& p = m.mesh.positions[v];
      if ((body.project(p) - p).norm() <= 1e-9) continue;
      // A tet joins the body by its centroid: its vertices lie up to a tet's
      // size farther.
      EXPECT_LE(body.distanceOutside(p), 2.0 * shell) << "joint " << int(body.joint);
      ++beside;
    }
    EXPECT_GT(sliding, 0u) << "joint " << int(body.joint);
    offSurface += beside;
    EXPECT_LT(beside, sliding) << "joint " << int(body.joint);
  }
  EXPECT_LT(double(m.unsnappedVertices), 0.1 * double(m.snappedVertices));
  EXPECT_GT(offSurface, 0u);
}

// The owner's bone beside a body joins it: no tet of the owner's bone
// within the shell outside the attachment, and without the shell some.
TEST(ArticulatedMesh, TheOwnersBoneBesideItsBodyJoinsTheBody) {
  const Figure& f = figure();
  const auto besideBodies = [&](const ArticulatedMesh& m) {
    const double shell = f.grid.geometry().spacing.maxCoeff();
    std::size_t n = 0;
    for (std::size_t t = 0; t < m.mesh.tetCount(); ++t) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const std::int32_t v : m.mesh.tets[t]) c += 0.25 * m.mesh.positions[std::size_t(v)];
      for (const ArticularBody& b : m.bodies)
        n += m.mesh.labels[t] == kBoneTag + std::int32_t(b.owner) && b.cutAt(c) && b.distanceOutside(c) < 0.9 * shell;
    }
    return n;
  };
  EXPECT_EQ(besideBodies(f.mesh), 0u);
  ArticulatedMeshOptions without;
  without.ownerShellVoxels = 0.0;
  EXPECT_GT(besideBodies(buildArticulatedMesh(f.grid, f.organs, f.skeleton, without)), 0u);
}

// At a hinge the owner's bone end joins the body up to hingeOwnerReachMm
// outside the cylinder, away from the attachment: the elbows' and knees'
// cuts follow the humerus' and femur's ends (the knee's trochlea, in front
// of the cylinder, under the patella).
TEST(ArticulatedMesh, TheOwnersBoneEndJoinsAHingesBody) {
  const Figure& f = figure();
  // The balls' one-voxel shell off, so that the hinges' reach is what joins.
  ArticulatedMeshOptions with;
  with.ownerShellVoxels = 0.0;
  ArticulatedMeshOptions without = with;
  without.hingeOwnerReachMm = 0.0;
  const auto besideHinges = [&](const ArticulatedMesh& m) {
    std::size_t beside = 0, joined = 0;
    for (std::size_t t = 0; t < m.mesh.tetCount(); ++t) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const std::int32_t v : m.mesh.tets[t]) c += 0.25 * m.mesh.positions[std::size_t(v)];
      for (const ArticularBody& b : m.bodies) {
        if (b.shape != ArticularShape::Cylinder || !b.cutAt(c) || b.contains(c) || b.distanceOutside(c) >= 0.9 * with.hingeOwnerReachMm)
          continue;
        beside += m.mesh.labels[t] == kBoneTag + std::int32_t(b.owner);
        joined += m.mesh.labels[t] == b.tag();
      }
    }
    return std::pair{beside, joined};
  };
  const auto [beside, joined] = besideHinges(buildArticulatedMesh(f.grid, f.organs, f.skeleton, with));
  EXPECT_EQ(beside, 0u);
  EXPECT_GT(joined, 0u);
  const auto [besideWithout, joinedWithout] = besideHinges(buildArticulatedMesh(f.grid, f.organs, f.skeleton, without));
  EXPECT_GT(besideWithout, 0u);
  EXPECT_LT(joinedWithout, joined);
}

// At an elbow the cut leaves out only a narrow sector about the humerus'
// shaft (elbowAttachmentHalfAngleDeg), so the humerus' end between that
// sector and the balls' wider one joins the elbow's body (the olecranon
// fossa, behind the shaft, which the ulna's tip touches); the knees keep
// the wider sector.
TEST(ArticulatedMesh, TheElbowsCutReachesUpToTheHumerusShaft) {
  const Figure& f = figure();
  const ArticulatedMeshOptions defaults;
  ASSERT_LT(defaults.elbowAttachmentHalfAngleDeg, defaults.attachmentHalfAngleDeg);
  const auto betweenSectors = [&](const ArticulatedMesh& m) {
    std::size_t joined = 0;
    for (std::size_t t = 0; t < m.mesh.tetCount(); ++t) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const std::int32_t v : m.mesh.tets[t]) c += 0.25 * m.mesh.positions[std::size_t(v)];
      for (const ArticularBody& b : m.bodies) {
        if (!skeleton::isElbow(b.joint)) continue;
        Eigen::Vector3d d = c - b.centre;
        d -= d.dot(b.axis) * b.axis;
        if (d.norm() < 1e-9 || b.contains(c)) continue;
        const double angle = std::acos(std::clamp(d.normalized().dot(b.attachment), -1.0, 1.0)) * 180.0 / std::numbers::pi;
        joined += angle > defaults.elbowAttachmentHalfAngleDeg && angle < defaults.attachmentHalfAngleDeg &&
                  m.mesh.labels[t] == b.tag();
      }
    }
    return joined;
  };
  EXPECT_GT(betweenSectors(f.mesh), 0u);
  for (const ArticularBody& b : f.mesh.bodies) {
    EXPECT_EQ(b.attachmentHalfAngleDeg, skeleton::isElbow(b.joint) ? defaults.elbowAttachmentHalfAngleDeg : defaults.attachmentHalfAngleDeg)
        << "joint " << int(b.joint);
  }
  ArticulatedMeshOptions wide;
  wide.elbowAttachmentHalfAngleDeg = wide.attachmentHalfAngleDeg;
  EXPECT_EQ(betweenSectors(buildArticulatedMesh(f.grid, f.organs, f.skeleton, wide)), 0u);
}

// The sliver exudation after the mesher's refinement has no time limit
// (the mesh must not depend on the machine's speed), and CGAL's exuder can
// cycle without end: with the figure's elbows turned about these axes (a
// wrist placement tried on the way) it pumped 435,000 vertices of the
// articulated mesh's 5,000 with the same 225 cells queued. It now stops
// after as many pumps as the triangulation has vertices.
TEST(ArticulatedMesh, TheExudationEndsWhereItWouldCycle) {
  const Figure& f = figure();
  skeleton::Skeleton s = f.skeleton;
  struct Placed {
    JointId id;
    Eigen::Vector3d centre, longAxis, leftRight;
  };
  const Placed placed[] = {
      {JointId::RightElbow, {27.0, 28.0, 120.66666666666667}, {0.0, -0.027262590177555817, -0.9996283065103801},
       {-0.9999999005110546, 0.00044590356687812955, -1.2161006369404435e-05}},
      {JointId::LeftElbow, {86.25, 27.75, 120.75}, {0.020399668712070152, -0.020399668712070152, -0.9995837668914375},
       {-0.9997215790197486, -0.012274447128331279, -0.02015198228349831}},
      {JointId::RightWrist, {27.0, 27.0, 84.0}, {0.0, 0.0, -1.0}, {-1.0, 0.0, 0.0}},
      {JointId::LeftWrist, {87.0, 27.0, 84.0}, {0.0, 0.0, -1.0}, {-1.0, 0.0, 0.0}},
  };
  for (const Placed& p : placed)
    for (skeleton::Joint& j : s.joints)
      if (j.id == p.id) {
        j.centre = p.centre;
        j.longAxis = p.longAxis.normalized();
        j.leftRight = p.leftRight.normalized();
      }
  const ArticulatedMesh m = buildArticulatedMesh(f.grid, f.organs, s);
  EXPECT_GT(m.mesh.tetCount(), 1000u);
  for (const Tet& t : m.mesh.tets) EXPECT_GT(signedVolume(m.mesh.positions, t), 0.0);
}

// The joint turned with the body's owner moved rigidly, the other side
// still: the body's tets keep their volume (rigid), and no face is shared
// across the cut (the two sides can slide).
TEST(ArticulatedMesh, TurningTheOwnerMovesTheBodyRigidlyAndApartFromTheOtherSide) {
  const Figure& f = figure();
  const ArticulatedMesh& m = f.mesh;
  const ArticularBody* shoulder = bodyOf(m, JointId::RightShoulder);
  ASSERT_NE(shoulder, nullptr);
  const skeleton::Joint* joint = f.skeleton.joint(JointId::RightShoulder);
  ASSERT_NE(joint, nullptr);
  std::array<Eigen::Isometry3d, skeleton::kPartCount + 1> motions;
  motions.fill(Eigen::Isometry3d::Identity());
  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
  turn.rotate(Eigen::AngleAxisd(std::numbers::pi / 2, joint->axis(skeleton::Dof::Abduction)));
  turn.pretranslate(joint->centre - turn.linear() * joint->centre);
  for (const Part p : {Part::RightUpperArm, Part::RightForearm, Part::RightHand}) motions[std::size_t(p)] = turn;
  std::vector<Eigen::Vector3d> posed = m.mesh.positions;
  placeRigidVertices(m, motions, 1.0, posed);
  projectSlidingVertices(m, motions, 1.0, posed);
  for (std::size_t t = 0; t < m.mesh.tetCount(); ++t) {
    if (m.mesh.labels[t] != shoulder->tag()) continue;
    const double rest = signedVolume(m.mesh.positions, m.mesh.tets[t]);
    EXPECT_NEAR(signedVolume(posed, m.mesh.tets[t]), rest, 1e-9 * std::max(1.0, rest));
  }
  // Halfway, the screw interpolation the posing uses is the half turn about
  // the same centre.
  const Eigen::Isometry3d half = screwInterpolate(turn, 0.5);
  EXPECT_LT((half * joint->centre - joint->centre).norm(), 1e-9);
  EXPECT_NEAR(Eigen::AngleAxisd(Eigen::Matrix3d(half.linear())).angle(), std::numbers::pi / 4, 1e-12);
  // Sliding vertices stay on the spheres the turn maps onto themselves:
  // the body's, or beside the owner's bone the one through their rest place.
  for (std::size_t v = 0; v < m.role.size(); ++v)
    if (m.role[v] == VertexRole::Sliding && m.bodies[std::size_t(m.vertexBody[v])].joint == JointId::RightShoulder) {
      EXPECT_NEAR((posed[v] - shoulder->centre).norm(), (m.mesh.positions[v] - shoulder->centre).norm(), 1e-9);
    }
}

}  // namespace
}  // namespace vox

namespace vox {
namespace {

skeleton::PartMotions figureMotions(const skeleton::Skeleton& s, const std::vector<PoseJoint>& angles) {
  return skeleton::partMotions(skeleton::posedJoints(s, angles, "pose"), angles);
}

PoseJoint jointAngles(JointId id, double flexion, double abduction = 0.0) {
  PoseJoint j;
  j.name = skeleton::jointKind(id).name;
  j.degrees = {flexion, abduction, 0.0};
  return j;
}

// The steps of a joint pose follow the joints: at every fraction the
// forearm hangs from the elbow where the upper arm put it. Each part's own
// screw from rest to the pose does not: the forearm, turned 220 degrees by
// shoulder and elbow together, takes the short way round.
TEST(ArticulatedPose, AJointPathKeepsTheChainTogetherAtEveryStep) {
  const Figure& f = figure();
  const std::vector<PoseJoint> angles = {jointAngles(JointId::RightShoulder, 100.0), jointAngles(JointId::RightElbow, 120.0)};
  const std::vector<skeleton::Joint> joints = skeleton::posedJoints(f.skeleton, angles, "pose");
  const ArticulatedPoser::MotionPath path = jointMotionPath(f.skeleton, joints, angles, f.mesh);
  const skeleton::PartMotions full = figureMotions(f.skeleton, angles);
  const Eigen::Vector3d elbow = f.skeleton.joint(JointId::RightElbow)->centre;
  const auto upper = std::size_t(Part::RightUpperArm), fore = std::size_t(Part::RightForearm);
  for (const double fraction : {0.25, 0.5, 0.75, 1.0}) {
    const std::vector<Eigen::Isometry3d> m = path(fraction);
    EXPECT_LT((m[upper] * elbow - m[fore] * elbow).norm(), 1e-6) << fraction;
  }
  for (std::size_t p = 0; p < full.size(); ++p) EXPECT_TRUE(path(1.0)[p].isApprox(full[p], 1e-12)) << p;
  const std::vector<Eigen::Isometry3d> given(full.begin(), full.end());
  EXPECT_GT((partMotionAt(given, Part::RightUpperArm, 0.5) * elbow - partMotionAt(given, Part::RightForearm, 0.5) * elbow).norm(), 10.0);
}

// A stride (one hip flexed, the other extended, that knee bent): the bones
// move with their parts exactly, and no tet inverts on the way.
TEST(ArticulatedPose, AStrideKeepsBonesRigidAndEveryTetPositive) {
  const Figure& f = figure();
  const std::vector<PoseJoint> angles = {jointAngles(JointId::RightHip, 30.0), jointAngles(JointId::LeftHip, -20.0),
                                         jointAngles(JointId::LeftKnee, 45.0)};
  const skeleton::PartMotions motions = figureMotions(f.skeleton, angles);
  ArticulatedPoser poser(f.mesh);
  const ArticulatedPoseReport r = poser.pose(motions);
  EXPECT_EQ(r.bridgingTets, 0u);
  ASSERT_EQ(r.stepMinRelativeVolume.size(), std::size_t(r.steps));
  for (const double v : r.stepMinRelativeVolume) EXPECT_GT(v, 0.05);
  EXPECT_EQ(r.invertedTets, 0u);
  EXPECT_GT(r.minRelativeVolume, 0.05);
  EXPECT_TRUE(r.reachedTargets);
  EXPECT_LT(r.maxSlidingGapMm, 2.0 * f.grid.geometry().spacing.minCoeff());
  const std::vector<Eigen::Vector3d>& p = poser.positions();
  for (std::size_t v = 0; v < p.size(); ++v)
    if (f.mesh.role[v] == VertexRole::Rigid) {
      EXPECT_LT((p[v] - motions[std::size_t(f.mesh.vertexPart[v])] * f.mesh.mesh.positions[v]).norm(), 1e-6);
    }
}

// A pose hurried through two steps of three SLIM iterations each leaves the
// bones behind, and the last step's jump onto their motions folds the
// tissue around them; the untangling unfolds it with the bones held. On the
// mesh without the wrists' bone-gap cut: on this figure the cut is a slit of
// five faces in tissue two tets thick, and the hurried wrist folds at its
// rim (19 tets left of 186, 18 within 12 mm of the wrist).
TEST(ArticulatedPose, UntanglingUnfoldsWhatAHurriedApproachLeaves) {
  const Figure& figureWithCut = figure();
  ArticulatedMeshOptions uncut;
  uncut.boneGapMm = 0.0;
  const Figure f{figureWithCut.grid, figureWithCut.organs, figureWithCut.skeleton,
                 buildArticulatedMesh(figureWithCut.grid, figureWithCut.organs, figureWithCut.skeleton, uncut)};
  const std::vector<PoseJoint> angles = {jointAngles(JointId::RightShoulder, 110.0), jointAngles(JointId::RightElbow, 120.0),
                                         jointAngles(JointId::RightWrist, 30.0)};
  const std::vector<skeleton::Joint> joints = skeleton::posedJoints(f.skeleton, angles, "pose");
  ArticulatedPoseOptions options;
  options.steps = 2;
  options.solve.maxIterations = 3;
  ArticulatedPoser poser(f.mesh, options);
  const ArticulatedPoseReport r = poser.pose(jointMotionPath(f.skeleton, joints, angles, f.mesh));
  EXPECT_GT(r.invertedBeforeUntangling, 50u);
  EXPECT_GT(r.untangledVertices, 0u);
  EXPECT_EQ(r.untangleRadiusMm, options.untangleRadiiMm.back());
  EXPECT_LE(r.invertedTets * 20, r.invertedBeforeUntangling);
  const std::vector<Eigen::Vector3d>& p = poser.positions();
  std::size_t inverted = 0;
  for (const Tet& t : f.mesh.mesh.tets) inverted += signedVolume(p, t) <= 0.0;
  EXPECT_EQ(inverted, r.invertedTets);
  // The bones stay on their motions.
  const std::vector<Eigen::Isometry3d> motions = jointMotionPath(f.skeleton, joints, angles, f.mesh)(1.0);
  for (std::size_t v = 0; v < p.size(); ++v)
    if (f.mesh.role[v] == VertexRole::Rigid) {
      EXPECT_LT((p[v] - partMotionAt(motions, Part(f.mesh.vertexPart[v]), 1.0) * f.mesh.mesh.positions[v]).norm(), 1e-6);
    }
}

// The figure's arms hang against its trunk: the limb cut parts them below
// the shoulder, and an elbow turned 90 degrees swings the forearm and hand
// away from the trunk without a tet inverted on the way.
TEST(ArticulatedPose, AnElbowAt90PartsTheForearmFromTheTrunk) {
  const Figure& f = figure();
  EXPECT_GT(f.mesh.limbCut.cutFaces, 0u);
  EXPECT_GT(f.mesh.limbCut.duplicatedVertices, 0u);
  const skeleton::PartMotions motions = figureMotions(f.skeleton, {jointAngles(JointId::RightElbow, 90.0)});
  ArticulatedPoser poser(f.mesh);
  const ArticulatedPoseReport r = poser.pose(motions);
  for (const double v : r.stepMinRelativeVolume) EXPECT_GT(v, 0.05);
  EXPECT_EQ(r.invertedTets, 0u);
  EXPECT_TRUE(r.reachedTargets);
  const std::vector<Eigen::Vector3d>& p = poser.positions();
  for (std::size_t v = 0; v < p.size(); ++v)
    if (f.mesh.role[v] == VertexRole::Rigid) {
      EXPECT_LT((p[v] - motions[std::size_t(f.mesh.vertexPart[v])] * f.mesh.mesh.positions[v]).norm(), 1e-6);
    }
}

// An elbow bent 150 degrees presses the forearm's skin into the upper
// arm's tissue across the crease; the contact draws it back to the boundary
// it crossed, with no tet inverted and the bones on their motions.
TEST(ArticulatedPose, ContactPartsTheElbowsCrease) {
  const Figure& f = figure();
  const skeleton::PartMotions motions = figureMotions(f.skeleton, {jointAngles(JointId::RightElbow, 150.0)});
  ArticulatedPoser poser(f.mesh);
  const ArticulatedPoseReport r = poser.pose(motions);
  EXPECT_GE(r.penetratingBeforeContact, 5u);
  EXPECT_GT(r.deepestPenetrationBeforeMm, 2.0);
  EXPECT_GT(r.contactRounds, 0);
  EXPECT_GT(r.contactVertices, 0u);
  EXPECT_LT(r.penetratingAfterContact, r.penetratingBeforeContact);
  EXPECT_LT(r.deepestPenetrationAfterMm, 0.5 * r.deepestPenetrationBeforeMm);
  EXPECT_EQ(r.invertedTets, 0u);
  // The report's count is what is left.
  const std::vector<Eigen::Vector3d>& p = poser.positions();
  std::vector<std::uint8_t> candidate(p.size(), 0), penetrable(f.mesh.mesh.tetCount(), 1);
  for (std::size_t v = 0; v < p.size(); ++v) candidate[v] = f.mesh.role[v] == VertexRole::Free;
  const std::vector<Penetration> left = findPenetrations(f.mesh.mesh.positions, f.mesh.mesh.tets, p, candidate, penetrable);
  EXPECT_LE(left.size(), r.penetratingAfterContact);
  for (std::size_t v = 0; v < p.size(); ++v)
    if (f.mesh.role[v] == VertexRole::Rigid) {
      EXPECT_LT((p[v] - motions[std::size_t(f.mesh.vertexPart[v])] * f.mesh.mesh.positions[v]).norm(), 1e-6);
    }
}

// Ctrl-C (the Python module's cancellation) stops the pose at its next
// step or iteration instead of after minutes of solving, and the mesh's
// build between its slices.
TEST(ArticulatedPose, CancellationStopsThePoseAndTheMesh) {
  const Figure& f = figure();
  const skeleton::PartMotions motions = figureMotions(f.skeleton, {jointAngles(JointId::RightElbow, 90.0)});
  struct Cancel {
    Cancel() { cancellationRequested() = true; }
    ~Cancel() { cancellationRequested() = false; }
  };
  {
    const Cancel cancel;
    ArticulatedPoser poser(f.mesh);
    EXPECT_THROW(poser.pose(motions), OperationCancelled);
    EXPECT_THROW(buildArticulatedMesh(f.grid, f.organs, f.skeleton), OperationCancelled);
  }
  ArticulatedPoser poser(f.mesh);
  EXPECT_EQ(poser.pose(motions).invertedTets, 0u);
}

// Tissue far from every moved bone is held at rest (stillBeyondMm): an
// elbow's turn leaves the legs' and the other arm's vertices exactly where
// they were, bones of unmoved parts included, with every tet positive and
// the bones on their motions; with the option off nothing is held.
TEST(ArticulatedPose, TissueFarFromTheMovedBonesStaysAtRest) {
  const Figure& f = figure();
  const skeleton::PartMotions motions = figureMotions(f.skeleton, {jointAngles(JointId::RightElbow, 90.0)});
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (const Eigen::Vector3d& p : f.mesh.mesh.positions) {
    low = std::min(low, p.z());
    high = std::max(high, p.z());
  }
  ArticulatedPoseOptions options;
  options.stillBeyondMm = 0.15 * (high - low);
  ArticulatedPoser poser(f.mesh, options);
  const ArticulatedPoseReport r = poser.pose(motions);
  EXPECT_GT(r.stillVertices, 0u);
  EXPECT_GT(r.stillTets, 0u);
  EXPECT_EQ(r.invertedTets, 0u);
  EXPECT_TRUE(r.reachedTargets);
  const std::vector<Eigen::Vector3d>& p = poser.positions();
  std::size_t legs = 0;
  for (std::size_t v = 0; v < p.size(); ++v) {
    const Eigen::Vector3d& rest = f.mesh.mesh.positions[v];
    if (f.mesh.role[v] == VertexRole::Rigid) {
      EXPECT_LT((p[v] - motions[std::size_t(f.mesh.vertexPart[v])] * rest).norm(), 1e-6);
    }
    // The lowest quarter of the figure: the legs, far from the elbow.
    if (rest.z() < low + 0.25 * (high - low)) {
      ++legs;
      EXPECT_EQ(p[v], rest) << "vertex " << v;
    }
  }
  EXPECT_GT(legs, 100u);
  options.stillBeyondMm = 0.0;
  ArticulatedPoser all(f.mesh, options);
  const ArticulatedPoseReport every = all.pose(motions);
  EXPECT_EQ(every.stillVertices, 0u);
  EXPECT_EQ(every.stillTets, 0u);
  EXPECT_GT(every.solvedTets, r.solvedTets);
}

// The pelvis' bones beyond the joints' reach are left to the soft tissue;
// the tissue around them is held where it is while the pose leaves the
// pelvis where it is, so a stride's thighs do not drag them.
TEST(ArticulatedPose, ThePelvisBonesLeftToTheTissueStayWhereThePelvisStays) {
  const Figure& f = figure();
  ArticulatedMeshOptions reach;
  reach.trunkBoneReachMm = reach.pelvisBoneReachMm = 0.0;
  const std::vector<Part> carried = tissueBoneParts(f.mesh, f.grid, f.organs, f.skeleton, reach);
  ASSERT_EQ(carried.size(), f.mesh.mesh.vertexCount());
  std::size_t held = 0;
  for (std::size_t v = 0; v < carried.size(); ++v) {
    EXPECT_TRUE(carried[v] == Part::None || carried[v] == Part::Pelvis) << "vertex " << v;
    held += carried[v] != Part::None && f.mesh.role[v] == VertexRole::Free;
  }
  EXPECT_GT(held, 0u);
  // With the default reach the figure's pelvis lies within reach of its
  // hips: fewer vertices are held than with no reach.
  const std::vector<Part> defaults = tissueBoneParts(f.mesh, f.grid, f.organs, f.skeleton);
  EXPECT_LT(std::size_t(std::count_if(defaults.begin(), defaults.end(), [](Part p) { return p != Part::None; })),
            std::size_t(std::count_if(carried.begin(), carried.end(), [](Part p) { return p != Part::None; })));

  const skeleton::PartMotions motions =
      figureMotions(f.skeleton, {jointAngles(JointId::RightHip, 30.0), jointAngles(JointId::LeftHip, -20.0)});
  ArticulatedPoseOptions options;
  options.stillBeyondMm = 0.0;  // every other tissue vertex solved
  options.tissueBoneParts = carried;
  ArticulatedPoser poser(f.mesh, options);
  const ArticulatedPoseReport r = poser.pose(motions);
  EXPECT_EQ(r.invertedTets, 0u);
  EXPECT_TRUE(r.reachedTargets);
  EXPECT_GE(r.stillVertices, held);
  ArticulatedPoseOptions free = options;
  free.tissueBoneParts.clear();
  ArticulatedPoser dragged(f.mesh, free);
  dragged.pose(motions);
  std::size_t moved = 0;
  for (std::size_t v = 0; v < carried.size(); ++v) {
    if (carried[v] == Part::None || f.mesh.role[v] != VertexRole::Free) continue;
    EXPECT_EQ(poser.positions()[v], f.mesh.mesh.positions[v]) << "vertex " << v;
    moved += (dragged.positions()[v] - f.mesh.mesh.positions[v]).norm() > 1e-3;
  }
  EXPECT_GT(moved, 0u);
}

// A pose that turns no joint leaves the mesh at rest: nothing is solved,
// every vertex stays where it is, and the bones are on their motions.
TEST(ArticulatedPose, APoseThatTurnsNoJointLeavesTheMeshAtRest) {
  const Figure& f = figure();
  const skeleton::PartMotions motions = figureMotions(f.skeleton, {jointAngles(JointId::RightKnee, 0.0), jointAngles(JointId::RightElbow, 0.0)});
  for (const Eigen::Isometry3d& m : segmentMotions(motions, f.skeleton, f.mesh)) EXPECT_TRUE(m.isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  ArticulatedPoser poser(f.mesh, {});
  const ArticulatedPoseReport r = poser.pose(motions);
  EXPECT_EQ(r.solvedTets, 0u);
  EXPECT_EQ(r.invertedTets, 0u);
  EXPECT_TRUE(r.reachedTargets);
  EXPECT_EQ(poser.positions(), f.mesh.mesh.positions);
}

// The knee's frame for the patella's motion: centre, flexion axis, e1 the
// anterior direction and down the long axis across the axis, e2 = axis x e1;
// at(r, degrees, a) the point r from the axis at `degrees` from e1 towards
// e2, `a` along the axis.
struct KneeFrame {
  explicit KneeFrame(const skeleton::Joint& knee)
      : c(knee.centre), axis(knee.axis(skeleton::Dof::Flexion).normalized()),
        e1((knee.anterior - knee.anterior.dot(axis) * axis).normalized()), e2(axis.cross(e1)),
        down((knee.longAxis - knee.longAxis.dot(axis) * axis).normalized()) {}
  Eigen::Vector3d at(double r, double degrees, double a) const {
    const double phi = degrees * std::numbers::pi / 180.0;
    return c + a * axis + r * (std::cos(phi) * e1 + std::sin(phi) * e2);
  }
  Eigen::Vector3d c, axis, e1, e2, down;
};

// Adds a vertex rigid with `segment` (no tets) to m.
void addRigid(ArticulatedMesh& m, const Eigen::Vector3d& p, int segment) {
  m.mesh.positions.push_back(p);
  m.role.push_back(VertexRole::Rigid);
  m.vertexPart.push_back(Part(segment));
  m.vertexBody.push_back(-1);
  ++m.rigidVertices[std::size_t(segment)];
}

// A patella slides along the femur's profile as its knee bends: relative
// to the thigh it keeps its height above the profile and its ligament's
// length, from its apex (its lowest vertex) to the tibial tuberosity; where
// the profile is round about the knee's axis it turns with the lower leg.
TEST(ArticulatedPose, APatellaSlidesAlongTheFemurKeepingItsLigament) {
  const Figure& f = figure();
  const skeleton::Joint& knee = *f.skeleton.joint(JointId::RightKnee);
  const KneeFrame k(knee);
  const Eigen::Vector3d &c = k.c, &e1 = k.e1, &e2 = k.e2, &down = k.down;
  const auto at = [&](double r, double degrees, double a) { return k.at(r, degrees, a); };
  const auto mesh = [&](const std::function<double(double)>& profile) {
    ArticulatedMesh m;
    const auto add = [&](const Eigen::Vector3d& p, int segment) { addRigid(m, p, segment); };
    for (int d = -180; d < 180; ++d)
      for (const double a : {-12.0, 0.0, 12.0}) {
        add(at(profile(d), d, a), int(Part::RightThigh));
        add(at(0.5 * profile(d), d, a), int(Part::RightThigh));
      }
    for (const double d : {-10.0, 0.0, 10.0})
      for (const double r : {3.0, 10.0})
        for (const double a : {-8.0, 0.0, 8.0}) add(at(profile(0.0) + r, d, a), kRightPatella);
    // The plateau's front rim, nearer the patella than the tuberosity.
    add(c + 25.0 * e1 + 12.0 * down, int(Part::RightLowerLeg));
    add(c + 30.0 * e1 + 45.0 * down, int(Part::RightLowerLeg));  // the tuberosity
    return m;
  };
  const skeleton::PartMotions motions = figureMotions(f.skeleton, {jointAngles(JointId::RightKnee, 60.0)});
  const Eigen::Isometry3d thigh = motions[std::size_t(Part::RightThigh)], leg = motions[std::size_t(Part::RightLowerLeg)];
  // Receding from 40 mm in front to 25 mm at a quarter turn either way.
  const auto receding = [](double d) { return 40.0 - 15.0 * std::min(std::abs(d), 90.0) / 90.0; };
  const ArticulatedMesh m = mesh(receding);
  const std::vector<Eigen::Isometry3d> segments = segmentMotions(motions, f.skeleton, m);
  const Eigen::Isometry3d patella = segments[std::size_t(kRightPatella)];
  EXPECT_FALSE(patella.isApprox(leg, 1e-3));
  Eigen::Vector3d pc = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (std::size_t v = 0; v < m.role.size(); ++v)
    if (int(m.vertexPart[v]) == kRightPatella) {
      pc += m.mesh.positions[v];
      ++n;
    }
  pc /= double(n);
  Eigen::Vector3d apex = pc;
  for (std::size_t v = 0; v < m.role.size(); ++v)
    if (int(m.vertexPart[v]) == kRightPatella && (m.mesh.positions[v] - c).dot(knee.longAxis) > (apex - c).dot(knee.longAxis))
      apex = m.mesh.positions[v];
  const Eigen::Vector3d tibia = m.mesh.positions.back();
  const Eigen::Vector3d moved = thigh.inverse() * patella * pc, tibiaMoved = thigh.inverse() * leg * tibia;
  // Its ligament's length kept (lifted off the profile under its upper end,
  // below, it lengthens by about a millimetre).
  EXPECT_NEAR((thigh.inverse() * patella * apex - tibiaMoved).norm(), (apex - tibia).norm(), 1.5);
  // Its ligament keeps the patella off the tibia: the centre no nearer to
  // the tuberosity than at rest.
  EXPECT_GE((moved - tibiaMoved).norm(), (pc - tibia).norm() - 1.0);
  const Eigen::Vector3d d = moved - c;
  const double degrees = std::atan2(d.dot(e2), d.dot(e1)) * 180.0 / std::numbers::pi;
  EXPECT_GT(std::abs(degrees), 5.0);  // it turned
  // At least its rest height above the profile (6.5 mm: 46.5 against 40),
  // within the profile's 6-degree window; and every vertex of it at least
  // its own rest clearance (the centre's at most): the upper end, turned
  // over the higher profile nearer the front, does not press into it.
  const double height = std::hypot(d.dot(e1), d.dot(e2)) - receding(degrees);
  EXPECT_GE(height, 6.5 - 1.5);
  EXPECT_LT(height, 6.5 + 5.0);
  const auto clearance = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d q = p - c;
    return std::hypot(q.dot(e1), q.dot(e2)) - receding(std::atan2(q.dot(e2), q.dot(e1)) * 180.0 / std::numbers::pi);
  };
  for (std::size_t v = 0; v < m.role.size(); ++v)
    if (int(m.vertexPart[v]) == kRightPatella) {
      const Eigen::Vector3d& p = m.mesh.positions[v];
      EXPECT_GE(clearance(thigh.inverse() * patella * p), std::min(clearance(p), 6.5) - 1.5) << v;
    }
  // Round about the axis: the lower leg's motion.
  const ArticulatedMesh round = mesh([](double) { return 40.0; });
  EXPECT_TRUE(segmentMotions(motions, f.skeleton, round)[std::size_t(kRightPatella)].isApprox(leg, 1e-6));
  // The knee straight: the patella stays at rest, also with a vertex below
  // the profile's highest within its 6-degree window (as on the AM, whose
  // straight knees otherwise lifted their patellae and moved the tissue
  // about them in poses that leave the legs alone).
  ArticulatedMesh deep = mesh(receding);
  addRigid(deep, at(receding(3.0) - 2.0, 3.0, 0.0), kRightPatella);
  const skeleton::PartMotions straight = figureMotions(f.skeleton, {jointAngles(JointId::RightKnee, 0.0)});
  EXPECT_TRUE(segmentMotions(straight, f.skeleton, deep)[std::size_t(kRightPatella)].isApprox(Eigen::Isometry3d::Identity(), 1e-9));
}

// The patella keeps at least half its rest clearance from the lower leg's
// bone: where the ligament's length fits about as well over a range of
// turns, the one that brings the patella onto the tibial plateau's front
// (the AM's seated knee: 1.3 mm from it, 15.5 mm at rest) is not taken.
TEST(ArticulatedPose, APatellaKeepsClearOfTheTibia) {
  const Figure& f = figure();
  const skeleton::Joint& knee = *f.skeleton.joint(JointId::RightKnee);
  const KneeFrame k(knee);
  const Eigen::Vector3d &c = k.c, &e1 = k.e1, &down = k.down;
  const auto at = [&](double r, double degrees, double a) { return k.at(r, degrees, a); };
  ArticulatedMesh m;
  const auto add = [&](const Eigen::Vector3d& p, int segment) { addRigid(m, p, segment); };
  // A femur receding from 30 mm in front to 18 mm a quarter turn either
  // way, a patella in front of it, the tuberosity below it and the
  // plateau's front rim behind and level with its lower end.
  const auto receding = [](double d) { return 30.0 - 12.0 * std::min(std::abs(d), 90.0) / 90.0; };
  for (int d = -180; d < 180; ++d)
    for (const double a : {-12.0, 0.0, 12.0}) add(at(receding(d), d, a), int(Part::RightThigh));
  for (const double d : {-10.0, 0.0, 10.0})
    for (const double r : {3.0, 10.0})
      for (const double a : {-8.0, 0.0, 8.0}) add(at(receding(d) + r, d, a), kRightPatella);
  const double tilt = 12.0 * std::numbers::pi / 180.0;
  const Eigen::Vector3d rim = c + 22.0 * (std::cos(tilt) * e1 + std::sin(tilt) * down);
  add(rim, int(Part::RightLowerLeg));
  add(c + 45.0 * e1 + 40.0 * down, int(Part::RightLowerLeg));  // the tuberosity
  const auto clearance = [&](const Eigen::Isometry3d& patella, const Eigen::Isometry3d& leg) {
    double d = std::numeric_limits<double>::infinity();
    for (std::size_t v = 0; v < m.role.size(); ++v)
      if (int(m.vertexPart[v]) == kRightPatella)
        for (std::size_t w = 0; w < m.role.size(); ++w)
          if (m.vertexPart[w] == Part::RightLowerLeg) d = std::min(d, (patella * m.mesh.positions[v] - leg * m.mesh.positions[w]).norm());
    return d;
  };
  const double rest = clearance(Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity());
  for (const double degrees : {45.0, 90.0, 120.0}) {
    const skeleton::PartMotions motions = figureMotions(f.skeleton, {jointAngles(JointId::RightKnee, degrees)});
    const std::vector<Eigen::Isometry3d> segments = segmentMotions(motions, f.skeleton, m);
    const double posed = clearance(segments[std::size_t(kRightPatella)], motions[std::size_t(Part::RightLowerLeg)]);
    std::printf("knee %.0f degrees: the patella %.1f mm from the tibia (%.1f at rest)\n", degrees, posed, rest);
    EXPECT_GE(posed, 0.5 * rest - 0.5) << degrees;
  }
}

// A large turn takes more pose steps: 16 per quarter turn of the largest
// joint angle, never fewer than the options' steps.
TEST(ArticulatedPose, ALargeTurnTakesMoreSteps) {
  const auto joint = [](const char* name, double flexion, double abduction = 0.0) {
    PoseJoint j;
    j.name = name;
    j.degrees = {flexion, abduction, 0.0};
    return j;
  };
  const ArticulatedPoseOptions options;
  EXPECT_EQ(articulatedPoseSteps(std::vector<PoseJoint>{}, options), 8);
  EXPECT_EQ(articulatedPoseSteps(std::vector<PoseJoint>{joint("left_knee", 30.0)}, options), 8);
  EXPECT_EQ(articulatedPoseSteps(std::vector<PoseJoint>{joint("right_hip", 90.0), joint("right_knee", 90.0)}, options), 16);
  EXPECT_EQ(articulatedPoseSteps(std::vector<PoseJoint>{joint("right_shoulder", 115.0, 10.0), joint("right_elbow", 120.0)}, options), 22);
  EXPECT_EQ(articulatedPoseSteps(std::vector<PoseJoint>{joint("left_hip", -100.0)}, options), 18);
  ArticulatedPoseOptions fixed;
  fixed.stepsPerQuarterTurn = 0;
  fixed.steps = 5;
  EXPECT_EQ(articulatedPoseSteps(std::vector<PoseJoint>{joint("right_elbow", 120.0)}, fixed), 5);
}

// How many of `split` (vertices of `cut`) lie where a vertex of `uncut`'s
// surface lies: the same mesh before the cut, so the skin opened there.
// The places of the vertices of `uncut`'s boundary faces: on the skin, or
// on a cut's faces, where the face's centroid lies on another boundary face
// (the cut's other side, which may be split where this one is not).
std::set<std::array<double, 3>> boundaryPlaces(const ArticulatedMesh& uncut, bool skin) {
  const std::vector<std::array<std::int32_t, 3>> faces = boundaryFaces(uncut.mesh.tets, uncut.mesh.vertexCount());
  const auto& x = uncut.mesh.positions;
  const double h = 8.0;
  std::map<std::array<int, 3>, std::vector<std::size_t>> cells;
  const auto cellOf = [h](const Eigen::Vector3d& p) {
    return std::array<int, 3>{int(std::floor(p.x() / h)), int(std::floor(p.y() / h)), int(std::floor(p.z() / h))};
  };
  for (std::size_t i = 0; i < faces.size(); ++i) {
    Eigen::Vector3d lo = x[std::size_t(faces[i][0])], hi = lo;
    for (const std::int32_t v : faces[i]) {
      lo = lo.cwiseMin(x[std::size_t(v)]);
      hi = hi.cwiseMax(x[std::size_t(v)]);
    }
    const std::array<int, 3> a = cellOf(lo), b = cellOf(hi);
    for (int i0 = a[0]; i0 <= b[0]; ++i0)
      for (int i1 = a[1]; i1 <= b[1]; ++i1)
        for (int i2 = a[2]; i2 <= b[2]; ++i2) cells[{i0, i1, i2}].push_back(i);
  }
  std::set<std::array<double, 3>> places;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const Eigen::Vector3d c = (x[std::size_t(faces[i][0])] + x[std::size_t(faces[i][1])] + x[std::size_t(faces[i][2])]) / 3.0;
    bool onAnother = false;
    for (const std::size_t j : cells[cellOf(c)])
      onAnother = onAnother || (j != i && (nearestPointOnTriangle(c, x[std::size_t(faces[j][0])], x[std::size_t(faces[j][1])],
                                                                  x[std::size_t(faces[j][2])]) - c).norm() < 1e-9);
    if (onAnother == skin) continue;
    for (const std::int32_t v : faces[i]) places.insert({x[std::size_t(v)].x(), x[std::size_t(v)].y(), x[std::size_t(v)].z()});
  }
  return places;
}

// How many of `split` (vertices of `cut`) lie on `uncut`'s skin, or on its
// cuts' faces.
std::size_t splitOn(const ArticulatedMesh& uncut, const ArticulatedMesh& cut, std::span<const std::int32_t> split, bool skin) {
  const std::set<std::array<double, 3>> places = boundaryPlaces(uncut, skin);
  std::size_t n = 0;
  for (const std::int32_t v : split) {
    const Eigen::Vector3d& x = cut.mesh.positions[std::size_t(v)];
    n += places.contains({x.x(), x.y(), x.z()});
  }
  return n;
}

std::size_t splitOnTheSkin(const ArticulatedMesh& uncut, const ArticulatedMesh& cut, std::span<const std::int32_t> split) {
  return splitOn(uncut, cut, split, true);
}

// A wrist turned with the hand's bones rigid beside the forearm's carries
// the carpals across the radius' end through tissue a tet or two thick.
// The bone-gap cut parts that tissue between the two bones, so each side
// moves with its own bone and the tissue between them is squeezed less. By
// default the tets that touch the skin stay uncut: the cut is a slit and
// the skin stays closed (no vertex of the skin split); without that rule
// the cut takes more faces.
TEST(ArticulatedPose, ABoneGapCutLetsTheCarpalsPassTheRadius) {
  const Figure& f = figure();
  const double spacing = f.grid.geometry().spacing.maxCoeff();
  ArticulatedMeshOptions options;
  options.wholePartBoneClearanceMm = 0.0;
  options.wholePartOwnBoneClearanceMm = 0.0;
  options.boneGapMm = 0.0;
  options.boneGapJoints = {JointId::RightWrist, JointId::LeftWrist};
  const ArticulatedMesh uncut = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  options.boneGapMm = 3.0 * spacing;
  options.boneGapReachMm = 6.0 * spacing;
  const ArticulatedMesh slit = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  options.boneGapKeepsSkin = false;
  const ArticulatedMesh cut = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  EXPECT_EQ(uncut.boneGapCut.cutFaces, 0u);
  EXPECT_GT(slit.boneGapCut.cutFaces, 0u);
  EXPECT_GT(cut.boneGapCut.cutFaces, slit.boneGapCut.cutFaces);
  EXPECT_GT(cut.boneGapCut.duplicatedVertices, 0u);
  EXPECT_NO_THROW(cut.mesh.validate("bone-gap cut mesh"));
  EXPECT_NO_THROW(slit.mesh.validate("bone-gap slit mesh"));
  EXPECT_EQ(splitOnTheSkin(uncut, slit, slit.boneGapCut.splitVertices), 0u);
  // Every vertex split lies about a wrist, within the cut's reach.
  const Eigen::Vector3d right = f.skeleton.joint(JointId::RightWrist)->centre, left = f.skeleton.joint(JointId::LeftWrist)->centre;
  for (const std::int32_t v : cut.boneGapCut.splitVertices) {
    const Eigen::Vector3d& x = cut.mesh.positions[std::size_t(v)];
    EXPECT_LE(std::min((x - right).norm(), (x - left).norm()), options.boneGapReachMm + spacing) << v;
  }
  // The wrist flexed 80 degrees: the most squeezed tet keeps about a tenth
  // of its rest volume uncut, more than twice as much cut through (the
  // injective solve inverts no tet on this figure either way).
  const std::vector<PoseJoint> angles = {jointAngles(JointId::RightWrist, 80.0)};
  const skeleton::PartMotions motions = figureMotions(f.skeleton, angles);
  ArticulatedPoser uncutPoser(uncut), cutPoser(cut);
  const ArticulatedPoseReport before = uncutPoser.pose(motions), after = cutPoser.pose(motions);
  std::printf("bone-gap cut: %zu faces (%zu as a slit); smallest relative volume %.3f -> %.3f; inverted %zu -> %zu\n",
              cut.boneGapCut.cutFaces, slit.boneGapCut.cutFaces, before.minRelativeVolume, after.minRelativeVolume, before.invertedTets,
              after.invertedTets);
  EXPECT_TRUE(after.reachedTargets);
  EXPECT_GT(after.minRelativeVolume, 2.0 * before.minRelativeVolume);
  EXPECT_LE(after.invertedTets, before.invertedTets);
}

// How many pieces of the mesh (tets joined through faces) hold no tet of a
// bone or a body and no rigid or sliding vertex: tissue that nothing places.
std::size_t tissueOnlyPieces(const ArticulatedMesh& m) {
  const std::vector<std::array<std::int32_t, 4>> neighbours = faceNeighbors(m.mesh);
  std::vector<std::uint8_t> seen(m.mesh.tetCount(), 0);
  std::size_t pieces = 0;
  for (std::size_t seed = 0; seed < m.mesh.tetCount(); ++seed) {
    if (seen[seed]) continue;
    bool held = false;
    std::vector<std::int32_t> stack = {std::int32_t(seed)};
    seen[seed] = 1;
    while (!stack.empty()) {
      const std::int32_t t = stack.back();
      stack.pop_back();
      held = held || m.mesh.labels[std::size_t(t)] != kSoftTissueTag;
      for (const std::int32_t v : m.mesh.tets[std::size_t(t)]) held = held || m.role[std::size_t(v)] != VertexRole::Free;
      for (const std::int32_t n : neighbours[std::size_t(t)])
        if (n >= 0 && !seen[std::size_t(n)]) {
          seen[std::size_t(n)] = 1;
          stack.push_back(n);
        }
    }
    pieces += !held;
  }
  return pieces;
}

// With boneGapBesideCuts the bone-gap cut at the elbows runs beside the
// elbow's sliding cut (the olecranon's tissue parted from the humerus' in
// its fossa): the tets that touch the sliding cut's faces may be cut, those
// that touch the skin may not, and without cutOffTissueRigid (the next
// test) no piece of tissue is cut off from every bone, body and sliding
// surface.
TEST(ArticulatedMesh, TheBoneGapCutAtTheElbowsRunsBesideTheSlidingCutNotToTheSkin) {
  const Figure& f = figure();
  const double spacing = f.grid.geometry().spacing.maxCoeff();
  ArticulatedMeshOptions options;
  options.cutOffTissueRigid = false;
  options.boneGapMm = 0.0;
  const ArticulatedMesh uncut = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  options.boneGapMm = 3.0 * spacing;
  options.boneGapReachMm = 6.0 * spacing;
  options.boneGapJoints = {JointId::RightElbow, JointId::LeftElbow};
  options.boneGapBesideCuts = true;
  const ArticulatedMesh slit = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  EXPECT_NO_THROW(slit.mesh.validate("bone-gap slit mesh at the elbows"));
  // Beside the other cuts, the bone-gap cut cuts no piece of tissue off
  // from every bone, body and sliding surface (at the elbows, and with the
  // wrists and hips too).
  EXPECT_EQ(tissueOnlyPieces(uncut), 0u);
  EXPECT_EQ(tissueOnlyPieces(slit), 0u);
  ArticulatedMeshOptions all = options;
  all.boneGapJoints = {JointId::RightWrist, JointId::LeftWrist, JointId::RightElbow, JointId::LeftElbow, JointId::RightHip, JointId::LeftHip};
  EXPECT_EQ(tissueOnlyPieces(buildArticulatedMesh(f.grid, f.organs, f.skeleton, all)), 0u);
  const std::size_t onSkin = splitOn(uncut, slit, slit.boneGapCut.splitVertices, true);
  const std::size_t onCuts = splitOn(uncut, slit, slit.boneGapCut.splitVertices, false);
  std::printf("bone-gap cut at the elbows: %zu faces, %zu vertices split, %zu of them on the cuts' faces, %zu on the skin\n",
              slit.boneGapCut.cutFaces, slit.boneGapCut.splitVertices.size(), onCuts, onSkin);
  EXPECT_GT(slit.boneGapCut.cutFaces, 0u);
  EXPECT_EQ(onSkin, 0u);
  EXPECT_GT(onCuts, 0u);
  const Eigen::Vector3d right = f.skeleton.joint(JointId::RightElbow)->centre, left = f.skeleton.joint(JointId::LeftElbow)->centre;
  for (const std::int32_t v : slit.boneGapCut.splitVertices) {
    const Eigen::Vector3d& x = slit.mesh.positions[std::size_t(v)];
    EXPECT_LE(std::min((x - right).norm(), (x - left).norm()), options.boneGapReachMm + spacing) << v;
  }
}

// With cutOffTissueRigid the bone-gap cut beside the other cuts may close
// pieces of tissue off (on this figure at every joint it cuts); each moves
// rigidly with the part of the bone nearest to it, so nothing is left that
// no constraint places, and the elbows bent 120 degrees and the hips 90
// invert no tet.
TEST(ArticulatedMesh, TissueTheBoneGapCutClosesOffMovesWithTheNearestBone) {
  const Figure& f = figure();
  const double spacing = f.grid.geometry().spacing.maxCoeff();
  ArticulatedMeshOptions options;
  EXPECT_EQ(options.boneGapJoints, (std::vector<JointId>{JointId::RightWrist, JointId::LeftWrist, JointId::RightElbow, JointId::LeftElbow,
                                                         JointId::RightHip, JointId::LeftHip}));
  EXPECT_TRUE(options.boneGapBesideCuts);
  EXPECT_TRUE(options.cutOffTissueRigid);
  options.boneGapMm = 3.0 * spacing;
  options.boneGapReachMm = 6.0 * spacing;
  const ArticulatedMesh m = buildArticulatedMesh(f.grid, f.organs, f.skeleton, options);
  EXPECT_NO_THROW(m.mesh.validate("bone-gap cut beside the cuts"));
  EXPECT_GT(m.cutOffTissueVertices, 0u);
  EXPECT_EQ(tissueOnlyPieces(m), 0u);
  // The same cut keeping its tets out instead: none closed off, fewer faces.
  ArticulatedMeshOptions held = options;
  held.cutOffTissueRigid = false;
  const ArticulatedMesh h = buildArticulatedMesh(f.grid, f.organs, f.skeleton, held);
  EXPECT_EQ(h.cutOffTissueVertices, 0u);
  EXPECT_GT(m.boneGapCut.cutFaces, h.boneGapCut.cutFaces);
  std::printf("bone-gap cut beside the cuts: %zu faces, %zu vertices of cut-off tissue rigid (%zu faces keeping it held)\n",
              m.boneGapCut.cutFaces, m.cutOffTissueVertices, h.boneGapCut.cutFaces);
  const std::vector<PoseJoint> angles = {jointAngles(JointId::RightElbow, 120.0), jointAngles(JointId::LeftElbow, 120.0),
                                         jointAngles(JointId::RightHip, 90.0), jointAngles(JointId::LeftHip, 90.0)};
  const skeleton::PartMotions motions = figureMotions(f.skeleton, angles);
  ArticulatedPoser poser(m);
  const ArticulatedPoseReport r = poser.pose(motions);
  EXPECT_TRUE(r.reachedTargets);
  EXPECT_EQ(r.invertedTets, 0u);
  const std::vector<Eigen::Vector3d>& p = poser.positions();
  for (std::size_t v = 0; v < p.size(); ++v)
    if (m.role[v] == VertexRole::Rigid) {
      EXPECT_LT((p[v] - motions[std::size_t(m.vertexPart[v])] * m.mesh.positions[v]).norm(), 1e-6) << v;
    }
}

}  // namespace
}  // namespace vox
