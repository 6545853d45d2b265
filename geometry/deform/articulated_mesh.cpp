#include "geometry/deform/articulated_mesh.h"

#include "geometry/cancellation.h"
#include "geometry/cell_index.h"
#include "geometry/deform/solve/contact.h"
#include "geometry/deform/solve/injective_solve.h"
#include "geometry/disjoint_sets.h"
#include "geometry/distance_transform.h"
#include "geometry/error.h"
#include "geometry/nearest_vertex.h"
#include "geometry/raster/lattice_tets.h"
#include "geometry/scalar_grid.h"
#include "geometry/skeleton/bones.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <tuple>

namespace vox {

using skeleton::JointId;
using skeleton::Part;

bool ArticularBody::contains(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d d = p - centre;
  if (shape == ArticularShape::Sphere) return d.squaredNorm() < radius * radius;
  const double s = d.dot(axis);
  return std::abs(s) < halfLength && (d - s * axis).squaredNorm() < radius * radius;
}

Eigen::Vector3d ArticularBody::project(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d d = p - centre;
  if (shape == ArticularShape::Sphere) {
    const double n = d.norm();
    return n > 0 ? Eigen::Vector3d(centre + d * (radius / n)) : Eigen::Vector3d(centre + radius * attachment);
  }
  const double s = d.dot(axis);
  Eigen::Vector3d u = d - s * axis;
  const double r = u.norm();
  const Eigen::Vector3d dir = r > 0 ? Eigen::Vector3d(u / r) : attachment;
  // Nearest of the lateral surface and the two end discs.
  const double toSide = std::abs(r - radius), toEnd = std::abs(std::abs(s) - halfLength);
  if (std::abs(s) <= halfLength && (r > radius || toSide <= toEnd)) return centre + s * axis + radius * dir;
  if (r <= radius) return centre + std::copysign(halfLength, s) * axis + u;
  return centre + std::clamp(s, -halfLength, halfLength) * axis + radius * dir;
}

bool ArticularBody::cutAt(const Eigen::Vector3d& p) const {
  const double c = std::cos(attachmentHalfAngleDeg * std::numbers::pi / 180.0);
  Eigen::Vector3d d = p - centre;
  if (shape == ArticularShape::Cylinder) d -= d.dot(axis) * axis;
  const double n = d.norm();
  if (n < 1e-9 * std::max(1.0, radius)) return true;
  return d.dot(attachment) / n < c;
}

double ArticularBody::distanceOutside(const Eigen::Vector3d& p) const {
  return contains(p) ? 0.0 : (project(p) - p).norm();
}

Eigen::Vector3d ArticularBody::slide(const Eigen::Vector3d& p, const Eigen::Vector3d& rest) const {
  const Eigen::Vector3d r = rest - centre, d = p - centre;
  if (shape == ArticularShape::Sphere) {
    const double n = d.norm();
    return n > 0 ? Eigen::Vector3d(centre + d * (r.norm() / n)) : rest;
  }
  const double rs = r.dot(axis), ds = d.dot(axis);
  const double rr = (r - rs * axis).norm();
  // On an end disc at rest (inside the lateral surface, at or beyond an
  // end): the end's plane.
  if (rr < radius - 1e-6 * std::max(1.0, radius) && std::abs(rs) >= halfLength - 1e-6 * std::max(1.0, halfLength))
    return p + (rs - ds) * axis;
  const Eigen::Vector3d u = d - ds * axis;
  const double un = u.norm();
  const Eigen::Vector3d dir = un > 0 ? Eigen::Vector3d(u / un) : attachment;
  return centre + ds * axis + rr * dir;
}

Eigen::Vector3d slideOnBody(const ArticulatedMesh& mesh, std::size_t body, const Eigen::Vector3d& p, const Eigen::Vector3d& rest) {
  const ArticularBody& b = mesh.bodies[body];
  if (b.shape != ArticularShape::Cylinder || body >= mesh.bodySurfaces.size() || mesh.bodySurfaces[body].empty()) return b.slide(p, rest);
  Eigen::Vector3d best = p;
  double bestD2 = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.bodySurfaces[body]) {
    const Eigen::Vector3d q = nearestPointOnTriangle(p, t[0], t[1], t[2]);
    const double d2 = (q - p).squaredNorm();
    if (d2 < bestD2) {
      bestD2 = d2;
      best = q;
    }
  }
  return best;
}

bool rigidWithOneSegment(const ArticulatedMesh& mesh, const Tet& t) {
  for (const std::int32_t v : t)
    if (mesh.role[std::size_t(v)] != VertexRole::Rigid || mesh.vertexPart[std::size_t(v)] != mesh.vertexPart[std::size_t(t[0])]) return false;
  return true;
}

namespace {

// Whether a bone voxel of `part` at p is left to the soft tissue: a trunk or
// pelvis bone beyond the reach of every joint.
bool leftToTissue(Part part, const Eigen::Vector3d& p, const skeleton::Skeleton& skeleton, const ArticulatedMeshOptions& options) {
  if (part != Part::Trunk && part != Part::Pelvis) return false;
  const double reach = part == Part::Trunk ? options.trunkBoneReachMm : options.pelvisBoneReachMm;
  for (const skeleton::Joint& joint : skeleton.joints)
    if ((p - joint.centre).squaredNorm() < reach * reach) return false;
  return true;
}

}  // namespace

std::vector<Part> tissueBoneParts(const ArticulatedMesh& mesh, const LabelGrid& grid, const OrganTable& organs,
                                  const skeleton::Skeleton& skeleton, const ArticulatedMeshOptions& options) {
  const TetMesh& m = mesh.mesh;
  std::vector<Part> out(m.vertexCount(), Part::None);
  const LabelGrid boneParts = bonePartGrid(grid, organs, skeleton);
  const GridGeometry& g = grid.geometry();
  const std::vector<LatticeTet> tets = latticeTets(g, m.positions, m.tets);
  const std::int64_t slice = g.sliceVoxels();
  forEachLocatedSlab(tets, g, slabSlicesHolding(kSlabPoints / 2, slice), 0, [&](const SlabTets& slab, const std::uint32_t* state) {
    for (std::int64_t r = 0; r < std::int64_t(slab.z1 - slab.z0) * slice; ++r) {
      if (state[r] == kNoTet) continue;
      const std::int64_t voxel = std::int64_t(slab.z0) * slice + r;
      if (Part(boneParts.labels()[std::size_t(voxel)]) != Part::Pelvis) continue;
      const Eigen::Vector3d p = g.voxelCenter(voxel % g.dims[0], (voxel / g.dims[0]) % g.dims[1], voxel / slice);
      const Tet& t = m.tets[std::size_t(slab.tets[state[r]])];
      if (!leftToTissue(Part::Pelvis, p, skeleton, options) || rigidWithOneSegment(mesh, t)) continue;
      for (const std::int32_t v : t) out[std::size_t(v)] = Part::Pelvis;
    }
    throwIfCancelled();
  });
  return out;
}

LabelGrid bonePartGrid(const LabelGrid& grid, const OrganTable& organs, const skeleton::Skeleton& skeleton) {
  if (skeleton.parts.parts.dims() != grid.dims()) throw InputError("body parts", "the body-part grid's dims differ from the grid's");
  const std::vector<skeleton::Bone> boneOf = skeleton::boneOfLabels(organs, grid.maxLabel());
  LabelGrid out(grid.geometry(), 0);
  const std::vector<Label>& labels = grid.labels();
  const std::vector<Label>& parts = skeleton.parts.parts.labels();
  for (std::size_t v = 0; v < labels.size(); ++v) {
    const Label l = labels[v];
    if (l != 0 && l < boneOf.size() && boneOf[l] != skeleton::Bone::None) out.labels()[v] = parts[v];
  }
  return out;
}

namespace {

bool isBallJoint(JointId id) {
  return id == JointId::RightShoulder || id == JointId::LeftShoulder || id == JointId::RightHip || id == JointId::LeftHip;
}
bool isHingeJoint(JointId id) { return skeleton::isElbow(id) || id == JointId::RightKnee || id == JointId::LeftKnee; }

// Calls fn(voxel centre, part) for every bone voxel within `reach` mm of `c`.
template <class Fn>
void bonesNear(const LabelGrid& boneParts, const Eigen::Vector3d& c, double reach, Fn&& fn) {
  const GridGeometry& g = boneParts.geometry();
  const Eigen::Vector3d lo = g.continuousIndex(c - Eigen::Vector3d::Constant(reach));
  const Eigen::Vector3d hi = g.continuousIndex(c + Eigen::Vector3d::Constant(reach));
  std::int64_t i0[3], i1[3];
  for (int a = 0; a < 3; ++a) {
    i0[a] = std::max<std::int64_t>(0, std::int64_t(std::floor(std::min(lo[a], hi[a]))));
    i1[a] = std::min<std::int64_t>(g.dims[a] - 1, std::int64_t(std::ceil(std::max(lo[a], hi[a]))));
  }
  for (std::int64_t k = i0[2]; k <= i1[2]; ++k)
    for (std::int64_t j = i0[1]; j <= i1[1]; ++j)
      for (std::int64_t i = i0[0]; i <= i1[0]; ++i) {
        const Label part = boneParts.at(i, j, k);
        if (part != 0) fn(g.voxelCenter(i, j, k), Part(part));
      }
}

}  // namespace

std::vector<ArticularBody> articularBodies(const LabelGrid& grid, const LabelGrid& boneParts, const skeleton::Skeleton& skeleton,
                                           const ArticulatedMeshOptions& options) {
  const double finest = grid.geometry().spacing.minCoeff();
  const double margin = options.bodyMarginVoxels * finest;
  std::vector<ArticularBody> bodies;
  for (const skeleton::Joint& joint : skeleton.joints) {
    ArticularBody b;
    b.joint = joint.id;
    b.centre = joint.centre;
    b.attachmentHalfAngleDeg = options.attachmentHalfAngleDeg;
    const Part parent = joint.kind().parent, child = joint.kind().child;
    if (isBallJoint(joint.id) || (options.wristBodies && skeleton::isWrist(joint.id))) {
      // The head's sphere, up to the socket: the nearest bone voxel of
      // another part than the head's.
      b.shape = ArticularShape::Sphere;
      b.owner = child;
      b.other = parent;
      const double cap = joint.radius > 0 ? 1.25 * joint.radius : 30.0;
      double nearest = cap + margin;
      bonesNear(boneParts, b.centre, cap + margin, [&](const Eigen::Vector3d& p, Part part) {
        if (part != child) nearest = std::min(nearest, (p - b.centre).norm());
      });
      b.radius = nearest - margin;
      b.attachment = joint.longAxis.normalized();
    } else if (isHingeJoint(joint.id)) {
      // The cylinder about the flexion axis, as long as the parent's bone end
      // is wide, up to the child's bone.
      b.shape = ArticularShape::Cylinder;
      b.owner = parent;
      b.other = child;
      b.axis = joint.leftRight.normalized();
      constexpr double kReach = 60.0;
      double lo = std::numeric_limits<double>::max(), hi = -lo;
      bonesNear(boneParts, b.centre, kReach, [&](const Eigen::Vector3d& p, Part part) {
        const Eigen::Vector3d d = p - joint.centre;
        if (part != parent || std::abs(d.dot(joint.longAxis)) > 0.25 * kReach) return;
        lo = std::min(lo, d.dot(b.axis));
        hi = std::max(hi, d.dot(b.axis));
      });
      if (lo > hi) continue;
      b.centre = joint.centre + 0.5 * (lo + hi) * b.axis;  // along the axis: the same rotation
      b.halfLength = 0.5 * (hi - lo);
      double nearest = 40.0 + margin;
      bonesNear(boneParts, b.centre, kReach, [&](const Eigen::Vector3d& p, Part part) {
        if (part == parent) return;
        const Eigen::Vector3d d = p - b.centre;
        const double s = d.dot(b.axis);
        if (std::abs(s) <= b.halfLength + margin) nearest = std::min(nearest, (d - s * b.axis).norm());
      });
      b.radius = nearest - margin;
      Eigen::Vector3d shaft = -joint.longAxis;
      shaft -= shaft.dot(b.axis) * b.axis;
      if (shaft.norm() < 1e-6) continue;
      b.attachment = shaft.normalized();
      if (skeleton::isElbow(joint.id) && options.elbowAttachmentHalfAngleDeg >= 0.0) b.attachmentHalfAngleDeg = options.elbowAttachmentHalfAngleDeg;
    } else {
      continue;
    }
    if (b.radius < options.minBodyRadiusVoxels * finest) continue;
    bodies.push_back(b);
  }
  return bodies;
}

const char* segmentName(int segment) {
  if (segment == kRightScapula) return "right_scapula";
  if (segment == kLeftScapula) return "left_scapula";
  if (segment == kRightPatella) return "right_patella";
  if (segment == kLeftPatella) return "left_patella";
  return skeleton::partName(Part(segment));
}

Part segmentPart(int segment) {
  if (segment == kRightScapula || segment == kLeftScapula) return Part::Trunk;
  if (segment == kRightPatella) return Part::RightLowerLeg;
  if (segment == kLeftPatella) return Part::LeftLowerLeg;
  return Part(segment);
}

void markPatellae(LabelGrid& boneParts, const skeleton::Skeleton& skeleton) {
  const GridGeometry& g = boneParts.geometry();
  for (const auto& [knee, leg, patella] : {std::tuple{JointId::RightKnee, Part::RightLowerLeg, kRightPatella},
                                            std::tuple{JointId::LeftKnee, Part::LeftLowerLeg, kLeftPatella}}) {
    const skeleton::Joint* joint = skeleton.joint(knee);
    if (!joint) continue;
    std::vector<std::uint8_t> marked(boneParts.labels().size(), 0);
    for (std::size_t v = 0; v < marked.size(); ++v) marked[v] = boneParts.labels()[v] == Label(leg);
    std::vector<std::vector<std::int64_t>> pieces;
    skeleton::forEachComponent(g, marked, [&](std::uint8_t, const std::vector<std::int64_t>& piece) { pieces.push_back(piece); });
    if (pieces.size() < 2) continue;
    const auto largest = std::max_element(pieces.begin(), pieces.end(), [](const auto& a, const auto& b) { return a.size() < b.size(); });
    for (auto it = pieces.begin(); it != pieces.end(); ++it) {
      if (it == largest) continue;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const std::int64_t v : *it) {
        const Index3 ijk = g.ijk(v);
        c += g.voxelCenter(ijk[0], ijk[1], ijk[2]);
      }
      c /= double(it->size());
      if ((c - joint->centre).dot(joint->longAxis) >= 0.0) continue;
      for (const std::int64_t v : *it) boneParts.labels()[std::size_t(v)] = Label(patella);
    }
  }
}

namespace {

// The patella's motion (segmentMotions): in the thigh's rest frame it
// turns about the knee's axis by psi, between none and the lower leg's
// turn, at its rest height above the femur's profile there, the psi that
// keeps its ligament's length (its apex to the tibial tuberosity) best
// among those that keep the patella at least half its rest clearance from
// the lower leg's bone (none: the clearest): the ligament's length alone
// varies by a millimetre or two over the last quarter of the turn, and the
// psi that fits it to a tenth turned the AM's seated patella with its
// tibia, onto the tibial plateau's front (1.3 mm from it, 15.5 mm at rest)
// across the fat pad between them.
constexpr double kPatellaLegReachMm = 150.0;  // the lower leg's bone this near the knee's centre
constexpr double kPatellaCellMm = 8.0;

Eigen::Isometry3d patellaMotion(const skeleton::Joint& joint, const ArticulatedMesh& mesh, std::span<const Eigen::Isometry3d> motions,
                                Part thighPart, Part legPart, int patella) {
  const Eigen::Isometry3d thigh = motions[std::size_t(thighPart)], leg = motions[std::size_t(legPart)];
  const Eigen::Isometry3d rel = thigh.inverse() * leg;
  const Eigen::Vector3d axis = joint.axis(skeleton::Dof::Flexion).normalized();
  Eigen::Vector3d e1 = joint.anterior - joint.anterior.dot(axis) * axis;
  if (e1.norm() < 1e-9) return leg;
  e1.normalize();
  const Eigen::Vector3d e2 = axis.cross(e1);
  const Eigen::Vector3d& c = joint.centre;
  const std::vector<Eigen::Vector3d>& rest = mesh.mesh.positions;
  // The patella's vertices, centre, width along the axis, and apex (its
  // lowest rigid vertex: the ligament's upper end).
  std::vector<Eigen::Vector3d> patellaRest;
  Eigen::Vector3d pc = Eigen::Vector3d::Zero(), apex = Eigen::Vector3d::Zero();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, lowest = -lo;
  for (std::size_t v = 0; v < rest.size(); ++v)
    if (mesh.role[v] == VertexRole::Rigid && int(mesh.vertexPart[v]) == patella) {
      patellaRest.push_back(rest[v]);
      pc += rest[v];
      lo = std::min(lo, (rest[v] - c).dot(axis));
      hi = std::max(hi, (rest[v] - c).dot(axis));
      if ((rest[v] - c).dot(joint.longAxis) > lowest) {
        lowest = (rest[v] - c).dot(joint.longAxis);
        apex = rest[v];
      }
    }
  if (patellaRest.empty()) return leg;
  pc /= double(patellaRest.size());
  // Its lower end: the tibial tuberosity, the lower leg's most anterior
  // rigid vertex between 20 and 70 mm below the knee's centre within the
  // patella's width.
  Eigen::Vector3d tibia = pc;
  double front = -std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < rest.size(); ++v) {
    if (mesh.role[v] != VertexRole::Rigid || mesh.vertexPart[v] != legPart) continue;
    const Eigen::Vector3d d = rest[v] - c;
    const double below = d.dot(joint.longAxis), a = d.dot(axis);
    if (below < 20.0 || below > 70.0 || a < lo || a > hi) continue;
    if (d.dot(joint.anterior) > front) {
      front = d.dot(joint.anterior);
      tibia = rest[v];
    }
  }
  if (!std::isfinite(front)) return leg;
  const double ligament = (apex - tibia).norm();
  const Eigen::Vector3d tibiaNow = rel * tibia;
  // The lower leg's bone about the knee: the patella's clearance from it at
  // rest, and from it turned (the thigh's frame, in cells) at each psi up to
  // the clearance wanted.
  std::vector<Eigen::Vector3d> legNow;
  double restClearance2 = std::numeric_limits<double>::infinity();
  Eigen::Vector3d legLo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (std::size_t v = 0; v < rest.size(); ++v)
    if (mesh.role[v] == VertexRole::Rigid && mesh.vertexPart[v] == legPart && (rest[v] - c).norm() < kPatellaLegReachMm) {
      for (const Eigen::Vector3d& p : patellaRest) restClearance2 = std::min(restClearance2, (p - rest[v]).squaredNorm());
      legNow.push_back(rel * rest[v]);
      legLo = legLo.cwiseMin(legNow.back());
    }
  const double wanted = std::isfinite(restClearance2) ? 0.5 * std::sqrt(restClearance2) : 0.0;
  CellIndex legCells(kPatellaCellMm, legNow.empty() ? Eigen::Vector3d::Zero() : legLo);
  for (std::size_t i = 0; i < legNow.size(); ++i) legCells.add(std::int32_t(i), legNow[i], legNow[i]);
  legCells.finish();
  const auto clearance = [&](const std::vector<Eigen::Vector3d>& patellaNow) {
    double d2 = wanted * wanted;
    const Eigen::Vector3d box = Eigen::Vector3d::Constant(wanted);
    for (const Eigen::Vector3d& p : patellaNow)
      legCells.forEachIn(p - box, p + box, [&](std::int32_t i) { d2 = std::min(d2, (legNow[std::size_t(i)] - p).squaredNorm()); });
    return std::sqrt(d2);
  };
  std::vector<Eigen::Vector3d> patellaNow(patellaRest.size());
  // The femur's profile: per 2 degrees about the axis, the farthest rigid
  // vertex of the thigh across the patella's width.
  constexpr int kBins = 180;
  std::array<double, kBins> profile;
  profile.fill(-1.0);
  const auto binOf = [](double phi) {
    const double turns = phi / (2.0 * std::numbers::pi);
    return int(std::floor((turns - std::floor(turns)) * kBins)) % kBins;
  };
  for (std::size_t v = 0; v < rest.size(); ++v) {
    if (mesh.role[v] != VertexRole::Rigid || mesh.vertexPart[v] != thighPart) continue;
    const Eigen::Vector3d d = rest[v] - c;
    const double a = d.dot(axis);
    if (a < lo || a > hi) continue;
    double& r = profile[std::size_t(binOf(std::atan2(d.dot(e2), d.dot(e1))))];
    r = std::max(r, std::hypot(d.dot(e1), d.dot(e2)));
  }
  const auto height = [&](double phi) {  // the profile within 6 degrees of phi
    double r = -1.0;
    for (int k = -3; k <= 3; ++k) r = std::max(r, profile[std::size_t((binOf(phi) + k + kBins) % kBins)]);
    return r;
  };
  const Eigen::Vector3d d = pc - c;
  const double phi0 = std::atan2(d.dot(e2), d.dot(e1)), axial = d.dot(axis);
  const double r0 = std::hypot(d.dot(e1), d.dot(e2)), base = height(phi0);
  if (base < 0.0) return leg;
  const double gap = r0 - base;
  const Eigen::AngleAxisd turn(rel.linear());
  const double theta = turn.angle() * (turn.axis().dot(axis) < 0.0 ? -1.0 : 1.0);
  // psi from none to theta in half-degree steps.
  const int steps = std::max(1, int(std::ceil(std::abs(theta) / (0.5 * std::numbers::pi / 180.0))));
  // The cost: first the millimetres short of the clearance wanted, then
  // the ligament's error.
  double bestPsi = 0.0;
  std::pair<double, double> bestCost{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Eigen::Vector3d bestPlace = pc;
  for (int i = 0; i <= steps; ++i) {
    const double psi = theta * double(i) / double(steps), h = height(phi0 + psi);
    if (h < 0.0) continue;
    const Eigen::Vector3d place =
        c + axial * axis + (h + gap) * (std::cos(phi0 + psi) * e1 + std::sin(phi0 + psi) * e2);
    const Eigen::AngleAxisd turnPsi(psi, axis);
    const Eigen::Vector3d apexNow = place + turnPsi * (apex - pc);
    for (std::size_t k = 0; k < patellaRest.size(); ++k) patellaNow[k] = place + turnPsi * (patellaRest[k] - pc);
    const double closer = wanted > 0.0 ? std::max(0.0, wanted - clearance(patellaNow)) : 0.0;
    const std::pair<double, double> cost{closer, std::abs((apexNow - tibiaNow).norm() - ligament)};
    if (cost < bestCost) {
      bestCost = cost;
      bestPsi = psi;
      bestPlace = place;
    }
  }
  Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
  local.linear() = Eigen::AngleAxisd(bestPsi, axis).toRotationMatrix();
  local.translation() = bestPlace - local.linear() * pc;
  // Every vertex of the patella at least its own rest clearance above the
  // femur's profile (at most the centre's): where the profile under an end
  // of the patella rises above the one under its centre, the patella is
  // lifted off it along the radius, instead of pressing that end into the
  // trochlea and crushing the tissue between. A vertex that lies below the
  // profile at rest (the profile is the highest within 6 degrees) keeps
  // that depth, so that the knee at rest leaves the patella where it is.
  const auto polar = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d q = p - c;
    return std::pair{std::atan2(q.dot(e2), q.dot(e1)), std::hypot(q.dot(e1), q.dot(e2))};
  };
  const Eigen::Vector3d radial = std::cos(phi0 + bestPsi) * e1 + std::sin(phi0 + bestPsi) * e2;
  for (int pass = 0; pass < 3; ++pass) {
    double lift = 0.0;
    for (std::size_t v = 0; v < rest.size(); ++v) {
      if (mesh.role[v] != VertexRole::Rigid || int(mesh.vertexPart[v]) != patella) continue;
      const auto [phiRest, rRest] = polar(rest[v]);
      const auto [phiNow, rNow] = polar(local * rest[v]);
      const double hRest = height(phiRest), hNow = height(phiNow);
      if (hRest < 0.0 || hNow < 0.0) continue;
      lift = std::max(lift, hNow + std::min(rRest - hRest, std::max(gap, 0.0)) - rNow);
    }
    if (lift <= 1e-6) break;
    local.translation() += lift * radial;
  }
  return thigh * local;
}

}  // namespace

std::vector<Eigen::Isometry3d> segmentMotions(std::span<const Eigen::Isometry3d> partMotions, const skeleton::Skeleton& skeleton,
                                              const ArticulatedMesh& mesh, const ScapularRhythm& rhythm) {
  std::vector<Eigen::Isometry3d> out(kSegmentCount + 1, Eigen::Isometry3d::Identity());
  for (std::size_t p = 0; p < partMotions.size() && p <= std::size_t(skeleton::kPartCount); ++p) out[p] = partMotions[p];
  struct Side {
    JointId shoulder;
    int scapula;
    std::array<Part, 3> arm;
  };
  const std::array<Side, 2> sides = {Side{JointId::RightShoulder, kRightScapula, {Part::RightUpperArm, Part::RightForearm, Part::RightHand}},
                                     Side{JointId::LeftShoulder, kLeftScapula, {Part::LeftUpperArm, Part::LeftForearm, Part::LeftHand}}};
  for (const Side& side : sides) {
    const skeleton::Joint* joint = skeleton.joint(side.shoulder);
    if (!joint || mesh.rigidVertices[std::size_t(side.scapula)] == 0) continue;
    const Eigen::Isometry3d arm = out[std::size_t(side.arm[0])];
    const Eigen::Vector3d d = joint->longAxis.normalized(), posed = arm.linear() * d;
    const double elevation = std::acos(std::clamp(d.dot(posed), -1.0, 1.0));
    const double turn = rhythm.ratio * (elevation - rhythm.thresholdDeg * std::numbers::pi / 180.0);
    const Eigen::Vector3d axis = d.cross(posed);
    if (turn <= 0.0 || axis.norm() < 1e-9) continue;
    // The acromion: the scapula's most superior rigid vertex.
    Eigen::Vector3d pivot = joint->centre;
    double top = -std::numeric_limits<double>::infinity();
    for (std::size_t v = 0; v < mesh.role.size(); ++v)
      if (mesh.role[v] == VertexRole::Rigid && int(mesh.vertexPart[v]) == side.scapula &&
          mesh.mesh.positions[v].dot(joint->superior) > top) {
        top = mesh.mesh.positions[v].dot(joint->superior);
        pivot = mesh.mesh.positions[v];
      }
    Eigen::Isometry3d scapula = Eigen::Isometry3d::Identity();
    scapula.linear() = Eigen::AngleAxisd(turn, axis.normalized()).toRotationMatrix();
    scapula.translation() = pivot - scapula.linear() * pivot;
    // The glenohumeral turn about the joint centre that, after the
    // scapula's, gives the humerus its posed orientation.
    Eigen::Isometry3d glenohumeral = Eigen::Isometry3d::Identity();
    glenohumeral.linear() = scapula.linear().transpose() * arm.linear();
    glenohumeral.translation() = joint->centre - glenohumeral.linear() * joint->centre;
    const Eigen::Isometry3d carry = scapula * glenohumeral * arm.inverse();
    out[std::size_t(side.scapula)] = scapula;
    for (const Part p : side.arm) out[std::size_t(p)] = carry * out[std::size_t(p)];
  }
  for (const auto& [knee, thighPart, legPart, patella] :
       {std::tuple{JointId::RightKnee, Part::RightThigh, Part::RightLowerLeg, kRightPatella},
        std::tuple{JointId::LeftKnee, Part::LeftThigh, Part::LeftLowerLeg, kLeftPatella}}) {
    out[std::size_t(patella)] = out[std::size_t(legPart)];
    const skeleton::Joint* joint = skeleton.joint(knee);
    if (joint && mesh.rigidVertices[std::size_t(patella)] > 0) out[std::size_t(patella)] = patellaMotion(*joint, mesh, out, thighPart, legPart, patella);
  }
  return out;
}

Eigen::Isometry3d partMotionAt(std::span<const Eigen::Isometry3d> motions, Part part, double fraction) {
  const auto p = std::size_t(part);
  return p < motions.size() ? screwInterpolate(motions[p], fraction) : Eigen::Isometry3d::Identity();
}

void placeRigidVertices(const ArticulatedMesh& mesh, std::span<const Eigen::Isometry3d> motions, double fraction,
                        std::span<Eigen::Vector3d> positions) {
  std::array<Eigen::Isometry3d, kSegmentCount + 1> m;
  for (int p = 0; p <= kSegmentCount; ++p) m[std::size_t(p)] = partMotionAt(motions, Part(p), fraction);
  for (std::size_t v = 0; v < mesh.role.size(); ++v)
    if (mesh.role[v] == VertexRole::Rigid) positions[v] = m[std::size_t(mesh.vertexPart[v])] * mesh.mesh.positions[v];
}

void projectSlidingVertices(const ArticulatedMesh& mesh, std::span<const Eigen::Isometry3d> motions, double fraction,
                            std::span<Eigen::Vector3d> positions) {
  std::vector<Eigen::Isometry3d> m;
  for (const ArticularBody& b : mesh.bodies) m.push_back(partMotionAt(motions, b.owner, fraction));
  for (std::size_t v = 0; v < mesh.role.size(); ++v) {
    if (mesh.role[v] != VertexRole::Sliding) continue;
    const auto b = std::size_t(mesh.vertexBody[v]);
    positions[v] = m[b] * slideOnBody(mesh, b, m[b].inverse() * positions[v], mesh.mesh.positions[v]);
  }
}

namespace {

// Splits every edge between vertices that two different parts place (soft
// tissue tets spanning the thin gap between two bones): its midpoint, a
// free vertex, goes into every tet around it, so that no tet has all its
// vertices prescribed by parts that move against each other.
void splitBridgingEdges(ArticulatedMesh& out) {
  TetMesh& m = out.mesh;
  const auto bridging = [&](std::int32_t a, std::int32_t b) {
    return out.role[std::size_t(a)] == VertexRole::Rigid && out.role[std::size_t(b)] == VertexRole::Rigid &&
           out.vertexPart[std::size_t(a)] != out.vertexPart[std::size_t(b)];
  };
  std::vector<std::pair<std::int32_t, std::int32_t>> edges;
  for (const Tet& t : m.tets)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        if (bridging(t[std::size_t(i)], t[std::size_t(j)]))
          edges.emplace_back(std::min(t[std::size_t(i)], t[std::size_t(j)]), std::max(t[std::size_t(i)], t[std::size_t(j)]));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  if (edges.empty()) return;
  std::vector<std::vector<std::int32_t>> around(m.vertexCount());
  for (std::size_t t = 0; t < m.tetCount(); ++t)
    for (const std::int32_t v : m.tets[t]) around[std::size_t(v)].push_back(std::int32_t(t));
  for (const auto& [a, b] : edges) {
    std::vector<std::int32_t> shared;
    for (const std::int32_t t : around[std::size_t(a)])
      if (std::find(m.tets[std::size_t(t)].begin(), m.tets[std::size_t(t)].end(), b) != m.tets[std::size_t(t)].end()) shared.push_back(t);
    if (shared.empty()) continue;
    const auto mid = std::int32_t(m.positions.size());
    m.positions.push_back(0.5 * (m.positions[std::size_t(a)] + m.positions[std::size_t(b)]));
    out.role.push_back(VertexRole::Free);
    out.vertexPart.push_back(Part::None);
    out.vertexBody.push_back(-1);
    around.emplace_back();
    for (const std::int32_t t : shared) {
      // t keeps a (b -> mid); its copy keeps b (a -> mid).
      Tet copy = m.tets[std::size_t(t)];
      for (std::int32_t& x : m.tets[std::size_t(t)])
        if (x == b) x = mid;
      for (std::int32_t& x : copy)
        if (x == a) x = mid;
      const auto c = std::int32_t(m.tets.size());
      m.tets.push_back(copy);
      m.labels.push_back(m.labels[std::size_t(t)]);
      auto& ofB = around[std::size_t(b)];
      std::replace(ofB.begin(), ofB.end(), t, c);
      around[std::size_t(mid)].push_back(t);
      around[std::size_t(mid)].push_back(c);
      for (const std::int32_t x : copy)
        if (x != mid && x != b) around[std::size_t(x)].push_back(c);
    }
    ++out.splitEdges;
  }
}

// Every piece of the mesh (vertices joined through tets) that no rigid or
// sliding vertex holds, tissue a bone-gap cut beside the other cuts closed
// off (the olecranon's fat pad in the humerus' fossa), made rigid with the
// part of the rigid vertex nearest to it at rest: it moves as one block
// with the bone it lay against, so no tet of it inverts and none is left
// where nothing places it. Returns the vertices so placed.
std::size_t holdCutOffTissue(ArticulatedMesh& out) {
  const TetMesh& m = out.mesh;
  const std::size_t nv = m.vertexCount();
  DisjointSets pieces(nv);
  for (const Tet& t : m.tets)
    for (int k = 1; k < 4; ++k) pieces.unite(t[0], t[std::size_t(k)]);
  const std::vector<std::int32_t> piece = pieces.representatives();
  std::vector<std::uint8_t> held(nv, 0), inTet(nv, 0);
  for (const Tet& t : m.tets)
    for (const std::int32_t v : t) inTet[std::size_t(v)] = 1;
  for (std::size_t v = 0; v < nv; ++v)
    if (out.role[v] != VertexRole::Free) held[std::size_t(piece[v])] = 1;
  std::vector<std::int32_t> loose;
  for (std::size_t v = 0; v < nv; ++v)
    if (inTet[v] && !held[std::size_t(piece[v])]) loose.push_back(std::int32_t(v));
  if (loose.empty()) return 0;
  // Per piece (by representative): its vertices' nearest rigid vertex, the
  // nearest of them; the smaller index among equals (a cut's copies of a
  // vertex, rigid with two parts, lie on each other).
  std::vector<std::int32_t> rigid;
  for (std::size_t v = 0; v < nv; ++v)
    if (out.role[v] == VertexRole::Rigid) rigid.push_back(std::int32_t(v));
  if (rigid.empty()) return 0;
  const NearestVertex nearestRigid(m.positions, rigid);
  std::vector<std::pair<double, std::int32_t>> nearest(nv, {std::numeric_limits<double>::infinity(), -1});
  for (const std::int32_t v : loose) {
    const std::int32_t w = nearestRigid.query(m.positions[std::size_t(v)]);
    const std::pair<double, std::int32_t> found{(m.positions[std::size_t(w)] - m.positions[std::size_t(v)]).norm(), w};
    std::pair<double, std::int32_t>& n = nearest[std::size_t(piece[std::size_t(v)])];
    n = std::min(n, found);
  }
  for (const std::int32_t v : loose) {
    const std::int32_t w = nearest[std::size_t(piece[std::size_t(v)])].second;
    const Part p = out.vertexPart[std::size_t(w)];
    out.role[std::size_t(v)] = VertexRole::Rigid;
    out.vertexPart[std::size_t(v)] = p;
    ++out.rigidVertices[std::size_t(p)];
  }
  return loose.size();
}

// The part a tet of the mesh belongs to: its bone's or body's, else the
// skeleton's part at its centroid.
std::vector<Part> tetParts(const ArticulatedMesh& out, const skeleton::Skeleton& skeleton) {
  const TetMesh& m = out.mesh;
  const LabelGrid& parts = skeleton.parts.parts;
  std::vector<Part> result(m.tetCount(), Part::None);
  for (std::size_t t = 0; t < m.tetCount(); ++t) {
    const std::int32_t tag = m.labels[t];
    if (tag > kBoneTag && tag <= kBoneTag + kSegmentCount) {
      // A scapula goes with the trunk's group, a patella with its leg's.
      result[t] = segmentPart(tag - kBoneTag);
      continue;
    }
    if (tag >= kBodyTag) {
      for (const ArticularBody& b : out.bodies)
        if (b.tag() == tag) result[t] = b.owner;
      continue;
    }
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const std::int32_t v : m.tets[t]) c += 0.25 * m.positions[std::size_t(v)];
    if (Index3 ijk; parts.geometry().voxelAt(c, ijk)) result[t] = Part(parts.at(ijk[0], ijk[1], ijk[2]));
  }
  return result;
}

// Adds one cut's counts and split vertices to `total`.
void addCut(CutReport& total, const CutReport& r) {
  total.cutFaces += r.cutFaces;
  total.duplicatedVertices += r.duplicatedVertices;
  total.openedRimFaces += r.openedRimFaces;
  total.contactVertices += r.contactVertices;
  total.splitVertices.insert(total.splitVertices.end(), r.splitVertices.begin(), r.splitVertices.end());
}

constexpr double kDefaultHeadRadiusMm = 24.0;  // where a joint has no fitted head

// The limb cuts (see the header): tets relabelled by label group for the
// cut, their tags restored after it (the cut keeps the tets' order).
CutReport cutLimbs(ArticulatedMesh& out, const skeleton::Skeleton& skeleton, double marginRadii, ArticulatedMeshOptions::LegTrunkCut legTrunk,
                    double behindMm) {
  const std::vector<Part> part = tetParts(out, skeleton);
  const std::vector<std::int32_t> tags = out.mesh.labels;
  std::vector<std::int32_t>& group = out.mesh.labels;
  for (std::size_t t = 0; t < part.size(); ++t) group[t] = part[t] == Part::None ? 0 : std::int32_t(skeleton::labelGroupOf(part[t]));
  // Islands: a face-connected piece of one group that holds no bone of
  // its group (a few tets the part grid gives a limb inside the trunk's
  // tissue) joins the group it shares the most faces with, so no cut
  // leaves tissue that nothing holds.
  const TetMesh& m = out.mesh;
  const std::vector<std::array<std::int32_t, 4>> neighbours = faceNeighbors(m, "articulated transfer mesh");
  for (bool changed = true; changed;) {
    changed = false;
    std::vector<std::int32_t> component(m.tetCount(), -1);
    for (std::size_t seed = 0; seed < m.tetCount(); ++seed) {
      if (component[seed] >= 0) continue;
      std::vector<std::int32_t> members{std::int32_t(seed)}, stack{std::int32_t(seed)};
      component[seed] = std::int32_t(seed);
      bool holdsBone = tags[seed] != kSoftTissueTag;
      while (!stack.empty()) {
        const std::int32_t t = stack.back();
        stack.pop_back();
        for (const std::int32_t n : neighbours[std::size_t(t)])
          if (n >= 0 && component[std::size_t(n)] < 0 && group[std::size_t(n)] == group[seed]) {
            component[std::size_t(n)] = std::int32_t(seed);
            holdsBone = holdsBone || tags[std::size_t(n)] != kSoftTissueTag;
            members.push_back(n);
            stack.push_back(n);
          }
      }
      if (holdsBone) continue;
      std::array<std::size_t, kLabelGroupCount + 1> shared{};
      for (const std::int32_t t : members)
        for (const std::int32_t n : neighbours[std::size_t(t)])
          if (n >= 0 && group[std::size_t(n)] != group[seed]) ++shared[std::size_t(group[std::size_t(n)])];
      const auto best = std::int32_t(std::max_element(shared.begin(), shared.end()) - shared.begin());
      if (shared[std::size_t(best)] == 0) continue;
      for (const std::int32_t t : members) group[std::size_t(t)] = best;
      changed = true;
    }
  }
  // The joint that carries each limb group.
  std::array<const skeleton::Joint*, kLabelGroupCount + 1> top{};
  top[std::size_t(LabelGroup::RightArm)] = skeleton.joint(JointId::RightShoulder);
  top[std::size_t(LabelGroup::LeftArm)] = skeleton.joint(JointId::LeftShoulder);
  top[std::size_t(LabelGroup::RightLeg)] = skeleton.joint(JointId::RightHip);
  top[std::size_t(LabelGroup::LeftLeg)] = skeleton.joint(JointId::LeftHip);
  const auto beyond = [&](std::int32_t group, const Eigen::Vector3d& p) {
    const skeleton::Joint* j = group > 0 && group <= kLabelGroupCount ? top[std::size_t(group)] : nullptr;
    return !j || (p - j->centre).dot(j->longAxis.normalized()) > marginRadii * (j->radius > 0 ? j->radius : kDefaultHeadRadiusMm);
  };
  CutReport total;
  // One cut per limb against every other group (the limb's tets take the
  // copies), each only where the face lies beyond the limb's joint (a pair
  // of limbs once, beyond the first's: the hips lie level).
  for (int limb = 1; limb <= kLabelGroupCount; ++limb) {
    if (!top[std::size_t(limb)]) continue;
    for (int other = 1; other <= kLabelGroupCount; ++other) {
      if (other == limb || (top[std::size_t(other)] && other < limb)) continue;
      using enum ArticulatedMeshOptions::LegTrunkCut;
      const bool legTrunkPair = (limb == int(LabelGroup::RightLeg) || limb == int(LabelGroup::LeftLeg)) && other == int(LabelGroup::Trunk);
      if (legTrunkPair && legTrunk == None) continue;
      const bool frontOnly = legTrunkPair && legTrunk == Front;
      CutSides sides;
      sides.sideA = [other](std::int32_t l) { return l == other; };
      sides.sideB = [limb](std::int32_t l) { return l == limb; };
      sides.inRegion = [&, limb, frontOnly](const Eigen::Vector3d& p) {
        const skeleton::Joint* hip = top[std::size_t(limb)];
        return beyond(limb, p) && (!frontOnly || (p - hip->centre).dot(hip->anterior) > -behindMm);
      };
      addCut(total, cutTransferMesh(out.mesh, sides));
    }
  }
  out.mesh.labels = tags;
  return total;
}

// Per tet of `mesh`: whether its piece of the mesh (tets joined through
// faces) holds no tet of a bone or a body (`tags`) and no vertex of a
// sliding cut's outer side (`sliding`): tissue that nothing would place.
std::vector<std::uint8_t> tissueOnly(const TetMesh& mesh, std::span<const std::int32_t> tags, std::span<const std::uint8_t> sliding) {
  const std::vector<std::array<std::int32_t, 4>> neighbours = faceNeighbors(mesh, "articulated transfer mesh");
  DisjointSets pieces(mesh.tetCount());
  for (std::size_t t = 0; t < mesh.tetCount(); ++t)
    for (const std::int32_t n : neighbours[t])
      if (n >= 0) pieces.unite(std::int32_t(t), n);
  const std::vector<std::int32_t> piece = pieces.representatives();
  std::vector<std::uint8_t> held(mesh.tetCount(), 0), alone(mesh.tetCount(), 0);
  for (std::size_t t = 0; t < mesh.tetCount(); ++t) {
    bool h = tags[t] != kSoftTissueTag;
    for (const std::int32_t v : mesh.tets[t]) h = h || (std::size_t(v) < sliding.size() && sliding[std::size_t(v)]);
    if (h) held[std::size_t(piece[t])] = 1;
  }
  for (std::size_t t = 0; t < mesh.tetCount(); ++t) alone[t] = !held[std::size_t(piece[t])];
  return alone;
}

// One joint's bone-gap cut (boneGapBesideCuts) that closes no piece of
// tissue off from every bone, body and sliding surface (nothing would place
// its vertices): such a piece's tets stay out of the cut, and those of the
// cut that share a vertex with it (a piece may be cut off where the cut
// splits a vertex that its tets share with the cut's), and the cut is made
// again. mesh.labels holds the cut's sides.
CutReport cutKeepingTissueHeld(ArticulatedMesh& out, const CutSides& sides, std::span<const std::int32_t> tags) {
  const TetMesh uncut = out.mesh;
  std::vector<std::uint8_t> sliding(uncut.vertexCount(), 0);
  for (const CutReport& c : out.cuts)
    for (const std::int32_t v : c.splitVertices) sliding[std::size_t(v)] = 1;
  const std::vector<std::uint8_t> aloneBefore = tissueOnly(uncut, tags, sliding);
  for (;;) {
    const CutReport report = cutTransferMesh(out.mesh, sides);
    const std::vector<std::uint8_t> alone = tissueOnly(out.mesh, tags, sliding);
    std::vector<std::uint8_t> near(uncut.vertexCount(), 0);
    for (std::size_t t = 0; t < alone.size(); ++t)
      if (alone[t] && !aloneBefore[t])
        for (const std::int32_t v : uncut.tets[t]) near[std::size_t(v)] = 1;
    std::vector<std::int32_t> labels = out.mesh.labels;
    bool changed = false;
    for (std::size_t t = 0; t < labels.size(); ++t)
      if (labels[t] != 0 && std::any_of(uncut.tets[t].begin(), uncut.tets[t].end(), [&](std::int32_t v) { return near[std::size_t(v)] != 0; })) {
        labels[t] = 0;
        changed = true;
      }
    if (!changed) return report;  // none cut off, or nothing of the cut beside it
    out.mesh = uncut;
    out.mesh.labels = std::move(labels);
  }
}

// The bone-gap cuts (ArticulatedMeshOptions::boneGapJoints): tets about
// each joint relabelled by side for the cut (the parent's bone and the
// tissue nearer it, the child's and the tissue nearer it), their tags
// restored after it. A face is cut where the two bones' nearest rigid
// vertices lie within `gap` of each other through it.
CutReport cutBoneGaps(ArticulatedMesh& out, const skeleton::Skeleton& skeleton, const ArticulatedMeshOptions& options) {
  CutReport total;
  if (options.boneGapMm <= 0.0) return total;
  const std::vector<std::int32_t> tags = out.mesh.labels;
  const auto partOfTag = [&](std::int32_t tag) {
    if (tag > kBoneTag && tag <= kBoneTag + kSegmentCount) return Part(tag - kBoneTag);
    for (const ArticularBody& b : out.bodies)
      if (b.tag() == tag) return b.owner;
    return Part::None;
  };
  // The vertices on the mesh's surface: a tet that touches it stays uncut,
  // so the cut is a slit inside the tissue and the skin stays closed. With
  // boneGapBesideCuts the skin alone: the boundary less the faces of the
  // cuts before this one, whose two sides lie on each other (the copies of
  // a cut vertex keep its place until the snapping after the cuts).
  std::vector<std::uint8_t> surface(out.mesh.vertexCount(), 0);
  if (options.boneGapKeepsSkin && !options.boneGapBesideCuts) {
    for (const auto& f : boundaryFaces(out.mesh.tets, out.mesh.vertexCount()))
      for (const std::int32_t v : f) surface[std::size_t(v)] = 1;
  } else if (options.boneGapKeepsSkin) {
    const std::vector<std::array<std::int32_t, 3>> faces = boundaryFaces(out.mesh.tets, out.mesh.vertexCount());
    using Key = std::array<double, 9>;
    const auto key = [&](const std::array<std::int32_t, 3>& f) {
      std::array<std::array<double, 3>, 3> p;
      for (std::size_t k = 0; k < 3; ++k) {
        const Eigen::Vector3d& x = out.mesh.positions[std::size_t(f[k])];
        p[k] = {x.x(), x.y(), x.z()};
      }
      std::sort(p.begin(), p.end());
      return Key{p[0][0], p[0][1], p[0][2], p[1][0], p[1][1], p[1][2], p[2][0], p[2][1], p[2][2]};
    };
    std::vector<std::pair<Key, std::size_t>> keys(faces.size());
    for (std::size_t i = 0; i < faces.size(); ++i) keys[i] = {key(faces[i]), i};
    std::sort(keys.begin(), keys.end());
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const bool twin = (i > 0 && keys[i - 1].first == keys[i].first) || (i + 1 < keys.size() && keys[i + 1].first == keys[i].first);
      if (!twin)
        for (const std::int32_t v : faces[keys[i].second]) surface[std::size_t(v)] = 1;
    }
  }
  for (const JointId id : options.boneGapJoints) {
    const skeleton::Joint* joint = skeleton.joint(id);
    if (!joint) continue;
    const Part parent = joint->kind().parent, child = joint->kind().child;
    const Eigen::Vector3d centre = joint->centre;
    const double reach = options.boneGapReachMm, gap = options.boneGapMm;
    // The two bones' vertices about the joint.
    std::array<std::vector<Eigen::Vector3d>, 2> bone;
    std::vector<std::uint8_t> seen(out.mesh.vertexCount(), 0);
    for (std::size_t t = 0; t < out.mesh.tetCount(); ++t) {
      const Part p = partOfTag(tags[t]);
      if (p != parent && p != child) continue;
      for (const std::int32_t v : out.mesh.tets[t]) {
        const Eigen::Vector3d& x = out.mesh.positions[std::size_t(v)];
        const std::uint8_t bit = p == parent ? 1 : 2;
        if ((seen[std::size_t(v)] & bit) || (x - centre).norm() > reach + gap) continue;
        seen[std::size_t(v)] |= bit;
        bone[p == parent ? 0 : 1].push_back(x);
      }
    }
    if (bone[0].empty() || bone[1].empty()) continue;
    // Each side's vertices in cells of the gap's size: a query of the box
    // [p - gap, p + gap] finds every vertex within the gap of p. The
    // distance is exact up to the gap and more than the gap beyond it, all
    // the cut compares.
    const Eigen::Vector3d origin = centre - Eigen::Vector3d::Constant(reach + gap), g = Eigen::Vector3d::Constant(gap);
    std::array<CellIndex, 2> cells{CellIndex(gap, origin), CellIndex(gap, origin)};
    for (std::size_t s = 0; s < 2; ++s) {
      for (std::size_t i = 0; i < bone[s].size(); ++i) cells[s].add(std::int32_t(i), bone[s][i], bone[s][i]);
      cells[s].finish();
    }
    const auto distance = [&](int side, const Eigen::Vector3d& p) {
      double d2 = std::numeric_limits<double>::infinity();
      cells[std::size_t(side)].forEachIn(p - g, p + g, [&](std::int32_t i) {
        d2 = std::min(d2, (bone[std::size_t(side)][std::size_t(i)] - p).squaredNorm());
      });
      return std::sqrt(d2);
    };
    std::vector<std::int32_t>& side = out.mesh.labels;
    for (std::size_t t = 0; t < side.size(); ++t) {
      if (options.boneGapKeepsSkin && std::any_of(out.mesh.tets[t].begin(), out.mesh.tets[t].end(),
                                                  [&](std::int32_t v) { return surface[std::size_t(v)]; })) {
        side[t] = 0;
        continue;
      }
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const std::int32_t v : out.mesh.tets[t]) c += 0.25 * out.mesh.positions[std::size_t(v)];
      const Part p = partOfTag(tags[t]);
      std::int32_t s = 0;
      if ((c - centre).norm() <= reach) {
        if (p == parent) s = 1;
        else if (p == child) s = 2;
        else if (tags[t] == kSoftTissueTag) {
          const double dp = distance(0, c), dc = distance(1, c);
          if (std::min(dp, dc) < gap) s = dp <= dc ? 1 : 2;
        }
      }
      side[t] = s;
    }
    CutSides sides;
    sides.sideA = [](std::int32_t l) { return l == 1; };
    sides.sideB = [](std::int32_t l) { return l == 2; };
    sides.inRegion = [&](const Eigen::Vector3d& p) { return (p - centre).norm() <= reach && distance(0, p) + distance(1, p) <= gap; };
    addCut(total, options.boneGapBesideCuts && !options.cutOffTissueRigid ? cutKeepingTissueHeld(out, sides, tags)
                                                                        : cutTransferMesh(out.mesh, sides));
    out.mesh.labels = tags;
    // The copies the cut added lie inside the tissue, off the surface.
    surface.resize(out.mesh.vertexCount(), 0);
  }
  return total;
}

}  // namespace

ArticulatedMesh buildArticulatedMesh(const LabelGrid& grid, const OrganTable& organs, const skeleton::Skeleton& skeleton,
                                     const ArticulatedMeshOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  ArticulatedMesh out;
  const GridGeometry& g = grid.geometry();
  LabelGrid boneParts = bonePartGrid(grid, organs, skeleton);
  if (options.movingPatellae) markPatellae(boneParts, skeleton);
  out.bodies = articularBodies(grid, boneParts, skeleton, options);

  // Tags: the bones that move against each other resolved, the rest soft;
  // the distal parts (head, hands, feet) rigid whole but near their joint.
  LabelGrid tags(g, 0);
  const double clear2 = options.jointClearanceMm * options.jointClearanceMm;
  const LabelGrid& parts = skeleton.parts.parts;
  const bool scapula = options.movingScapulae;
  const double shell = options.yieldingShellVoxels * g.spacing.maxCoeff();
  const auto yields = [&](JointId joint) {
    return std::find(options.yieldingShellJoints.begin(), options.yieldingShellJoints.end(), joint) != options.yieldingShellJoints.end();
  };
  const std::vector<skeleton::Bone> boneOf = skeleton::boneOfLabels(organs, grid.maxLabel());
  const auto wholePart = [&](Part part) {
    return std::find(options.rigidWholeParts.begin(), options.rigidWholeParts.end(), part) != options.rigidWholeParts.end();
  };
  // Distance to the bones of the parts that are not rigid whole.
  ScalarGrid otherBone;
  if (options.wholePartBoneClearanceMm > 0.0) {
    std::vector<std::uint8_t> seeds(std::size_t(g.voxelCount()), 0);
    for (std::size_t v = 0; v < seeds.size(); ++v) {
      const auto b = Part(boneParts.labels()[v]);
      seeds[v] = b != Part::None && !wholePart(b);
    }
    otherBone = euclideanDistanceTransform(g, seeds).distance;
  }
  for (std::int64_t k = 0; k < g.dims[2]; ++k, throwIfCancelled())
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const std::int64_t v = g.index(i, j, k);
        if (grid.labels()[std::size_t(v)] == 0) continue;
        const Eigen::Vector3d p = g.voxelCenter(i, j, k);
        auto part = Part(boneParts.labels()[std::size_t(v)]);
        const auto region = Part(parts.labels()[std::size_t(v)]);
        const double toOtherBone =
            options.wholePartBoneClearanceMm > 0.0 ? double(otherBone.values[std::size_t(v)]) : std::numeric_limits<double>::infinity();
        if (wholePart(region)) {
          const auto id = skeleton::jointMoving(region);
          const skeleton::Joint* joint = id ? skeleton.joint(*id) : nullptr;
          if (!joint || ((p - joint->centre).squaredNorm() >= clear2 && toOtherBone >= options.wholePartBoneClearanceMm)) part = region;
        }
        // A whole part's own bone beside another part's (the carpals' face
        // on the radius) is tissue too: resolved, the two rigid bones would
        // crush the voxel of tissue between them as the joint turns.
        if (part != Part::None && wholePart(part) &&
            toOtherBone < std::min(options.wholePartOwnBoneClearanceMm, options.wholePartBoneClearanceMm))
          part = Part::None;
        if (scapula && part == Part::Trunk) {
          const Label l = grid.labels()[std::size_t(v)];
          if (l < boneOf.size() && boneOf[l] == skeleton::Bone::Scapula) {
            const skeleton::Joint* right = skeleton.joint(JointId::RightShoulder);
            const skeleton::Joint* left = skeleton.joint(JointId::LeftShoulder);
            const double dr = right ? (p - right->centre).squaredNorm() : std::numeric_limits<double>::infinity();
            const double dl = left ? (p - left->centre).squaredNorm() : std::numeric_limits<double>::infinity();
            if (right || left) part = Part(dr <= dl ? kRightScapula : kLeftScapula);
          }
        }
        if (part != Part::None && shell > 0.0)
          for (const ArticularBody& b : out.bodies) {
            if (b.shape != ArticularShape::Sphere || (part != b.owner && part != b.other) || !yields(b.joint)) continue;
            const double d = (p - b.centre).norm();
            if (d > b.radius && d < b.radius + shell) part = Part::None;
          }
        const bool resolved = part != Part::None && !leftToTissue(part, p, skeleton, options);
        tags.labels()[std::size_t(v)] = Label(resolved ? kBoneTag + std::int32_t(part) : kSoftTissueTag);
        out.resolvedBoneVoxels += resolved && boneParts.labels()[std::size_t(v)] != 0;
      }

  // Sizing: fine at the interfaces between tags and at the bodies' surfaces,
  // graded to coarse away from them.
  std::vector<std::uint8_t> fine(std::size_t(g.voxelCount()), 0);
  const double finest = g.spacing.minCoeff();
  for (std::int64_t k = 0; k < g.dims[2]; ++k, throwIfCancelled())
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const Label t = tags.at(i, j, k);
        if (t == 0) continue;
        bool interface = false;
        for (int a = 0; a < 3 && !interface; ++a)
          for (const int step : {-1, 1}) {
            Index3 n{i, j, k};
            n[std::size_t(a)] += step;
            const Label u = tags.atOr(n[0], n[1], n[2], 0);
            interface = interface || (u != 0 && u != t);
          }
        const Eigen::Vector3d p = g.voxelCenter(i, j, k);
        for (const ArticularBody& b : out.bodies) interface = interface || (b.project(p) - p).norm() < finest;
        fine[std::size_t(g.index(i, j, k))] = interface;
      }
  const double fineMm = options.fineSizeVoxels * finest;
  ScalarGrid sizing(g, float(options.coarseSizeMm));
  if (std::find(fine.begin(), fine.end(), 1) != fine.end()) {
    const DistanceTransform dt = euclideanDistanceTransform(g, fine);
    for (std::size_t v = 0; v < sizing.values.size(); ++v) {
      const double t = std::min(1.0, double(dt.distance.values[v]) / options.gradingMm);
      sizing.values[v] = float(fineMm + (options.coarseSizeMm - fineMm) * t);
    }
  }
  const std::vector<ArticularBody>& bodies = out.bodies;
  const TransferMeshRelabel relabel = [&bodies](const Eigen::Vector3d& p, int tag) {
    for (const ArticularBody& b : bodies)
      if (b.contains(p)) return int(b.tag());
    return tag;
  };
  out.mesh = buildTransferMesh(tags, sizing, options.transferMesh, relabel);

  // The owner's bone beside each body joins it: within ownerShellVoxels of
  // its surface, and at a hinge within hingeOwnerReachMm.
  const double ownerShell = options.ownerShellVoxels * g.spacing.maxCoeff();
  const auto shellOf = [&](const ArticularBody& b) {
    return b.shape == ArticularShape::Cylinder ? std::max(ownerShell, options.hingeOwnerReachMm) : ownerShell;
  };
  if (ownerShell > 0.0 || options.hingeOwnerReachMm > 0.0)
    for (std::size_t t = 0; t < out.mesh.tetCount(); ++t) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const std::int32_t v : out.mesh.tets[t]) c += 0.25 * out.mesh.positions[std::size_t(v)];
      for (const ArticularBody& b : out.bodies)
        if (out.mesh.labels[t] == kBoneTag + std::int32_t(b.owner) && b.cutAt(c) &&
            b.distanceOutside(c) < shellOf(b)) {
          out.mesh.labels[t] = b.tag();
          break;
        }
    }

  // The sliding cuts: between each body and what is neither it nor its
  // owner's bone.
  for (const ArticularBody& b : out.bodies) {
    CutSides sides;
    const std::int32_t tag = b.tag(), ownerBone = kBoneTag + std::int32_t(b.owner);
    sides.sideB = [tag](std::int32_t l) { return l == tag; };
    sides.sideA = [tag, ownerBone](std::int32_t l) { return l != tag && l != ownerBone; };
    sides.inRegion = [&b](const Eigen::Vector3d& p) { return b.cutAt(p); };
    out.cuts.push_back(cutTransferMesh(out.mesh, sides));
  }

  if (options.limbCutMarginRadii > 0) out.limbCut = cutLimbs(out, skeleton, options.limbCutMarginRadii, options.legTrunkCut, options.legTrunkCutBehindMm);
  out.boneGapCut = cutBoneGaps(out, skeleton, options);

  // The cut's vertices onto the body's surface: the mesher puts them on
  // some interface, but where a bone's surface runs within a tet of the
  // body's, on that one. Every copy of a vertex moves together, and only
  // where no tet around them degenerates.
  {
    const VertexTets around = vertexTets(out.mesh.tets, out.mesh.vertexCount());
    const auto volume = [&](const Tet& t) { return signedVolume(out.mesh.positions, t); };
    for (std::size_t b = 0; b < out.bodies.size(); ++b) {
      std::vector<std::int32_t> split = out.cuts[b].splitVertices;
      const auto key = [&](std::int32_t v) {
        const Eigen::Vector3d& p = out.mesh.positions[std::size_t(v)];
        return std::array<double, 3>{p.x(), p.y(), p.z()};
      };
      std::sort(split.begin(), split.end(), [&](std::int32_t a, std::int32_t c) { return key(a) < key(c) || (key(a) == key(c) && a < c); });
      // Groups of copies (equal positions), then passes: a vertex refused
      // may fit once its neighbours moved.
      std::vector<std::pair<std::size_t, std::size_t>> groups;
      for (std::size_t i = 0; i < split.size();) {
        std::size_t j = i + 1;
        while (j < split.size() && key(split[j]) == key(split[i])) ++j;
        groups.emplace_back(i, j);
        i = j;
      }
      std::vector<std::pair<std::size_t, std::size_t>> refused;
      for (int pass = 0; pass < 4 && !groups.empty(); ++pass, groups.swap(refused), refused.clear())
      for (const auto& [i, j] : groups) {
        const Eigen::Vector3d from = out.mesh.positions[std::size_t(split[i])];
        const Eigen::Vector3d to = out.bodies[b].project(from);
        // A vertex on the owner's bone beside the body stays there.
        if ((to - from).norm() > 0.5 * finest) continue;
        std::vector<std::pair<std::int32_t, double>> before;
        for (std::size_t k = i; k < j; ++k)
          for (const std::int32_t t : around.of(split[k])) before.emplace_back(t, volume(out.mesh.tets[std::size_t(t)]));
        for (std::size_t k = i; k < j; ++k) out.mesh.positions[std::size_t(split[k])] = to;
        bool valid = true;
        for (const auto& [t, v0] : before) valid = valid && volume(out.mesh.tets[std::size_t(t)]) > 0.05 * v0;
        if (valid) {
          ++out.snappedVertices;
        } else {
          for (std::size_t k = i; k < j; ++k) out.mesh.positions[std::size_t(split[k])] = from;
          refused.emplace_back(i, j);
        }
      }
      out.unsnappedVertices += groups.size();
    }
  }

  // Roles.
  const std::size_t nv = out.mesh.vertexCount();
  std::array<std::int32_t, skeleton::kJointCount> bodyOfJoint;
  bodyOfJoint.fill(-1);
  for (std::size_t b = 0; b < out.bodies.size(); ++b) bodyOfJoint[std::size_t(out.bodies[b].joint)] = std::int32_t(b);
  const auto partOfTag = [&](std::int32_t tag) {
    if (tag > kBoneTag && tag <= kBoneTag + kSegmentCount) return Part(tag - kBoneTag);
    if (tag >= kBodyTag && tag < kBodyTag + skeleton::kJointCount) {
      const std::int32_t b = bodyOfJoint[std::size_t(tag - kBodyTag)];
      if (b >= 0) return out.bodies[std::size_t(b)].owner;
    }
    return Part::None;
  };
  constexpr auto kConflict = Part(0xff);
  std::vector<Part> part(nv, Part::None);
  std::vector<std::int8_t> touchesBody(nv, -1);
  for (std::size_t t = 0; t < out.mesh.tetCount(); ++t) {
    const std::int32_t tag = out.mesh.labels[t];
    const Part p = partOfTag(tag);
    for (const std::int32_t v : out.mesh.tets[t]) {
      if (tag >= kBodyTag) touchesBody[std::size_t(v)] = std::int8_t(bodyOfJoint[std::size_t(tag - kBodyTag)]);
      if (p == Part::None) continue;
      Part& q = part[std::size_t(v)];
      q = q == Part::None || q == p ? p : kConflict;
    }
  }
  out.role.assign(nv, VertexRole::Free);
  out.vertexPart.assign(nv, Part::None);
  out.vertexBody.assign(nv, -1);
  for (std::size_t v = 0; v < nv; ++v) {
    if (part[v] == kConflict) {
      ++out.conflictVertices;
    } else if (part[v] != Part::None) {
      out.role[v] = VertexRole::Rigid;
      out.vertexPart[v] = part[v];
      ++out.rigidVertices[std::size_t(part[v])];
    }
  }
  for (std::size_t b = 0; b < out.cuts.size(); ++b)
    for (const std::int32_t v : out.cuts[b].splitVertices)
      if (out.role[std::size_t(v)] == VertexRole::Free && part[std::size_t(v)] != kConflict && touchesBody[std::size_t(v)] < 0) {
        out.role[std::size_t(v)] = VertexRole::Sliding;
        out.vertexBody[std::size_t(v)] = std::int8_t(b);
      }
  if (options.boneGapBesideCuts && options.cutOffTissueRigid) out.cutOffTissueVertices = holdCutOffTissue(out);
  splitBridgingEdges(out);
  // Each body's side of its cut: its tets' faces that the cut opened.
  {
    const std::vector<std::array<std::int32_t, 4>> neighbours = faceNeighbors(out.mesh, "articulated transfer mesh");
    out.bodySurfaces.resize(out.bodies.size());
    std::array<std::int32_t, skeleton::kJointCount> bodyOf;
    bodyOf.fill(-1);
    for (std::size_t b = 0; b < out.bodies.size(); ++b) bodyOf[std::size_t(out.bodies[b].joint)] = std::int32_t(b);
    for (std::size_t t = 0; t < out.mesh.tetCount(); ++t) {
      const std::int32_t tag = out.mesh.labels[t];
      if (tag < kBodyTag || tag >= kBodyTag + skeleton::kJointCount || bodyOf[std::size_t(tag - kBodyTag)] < 0) continue;
      const auto b = std::size_t(bodyOf[std::size_t(tag - kBodyTag)]);
      const Tet& tet = out.mesh.tets[t];
      for (int f = 0; f < 4; ++f) {
        if (neighbours[t][std::size_t(f)] >= 0) continue;
        // Face f is the one opposite vertex f.
        std::array<Eigen::Vector3d, 3> tri;
        for (int k = 0, n = 0; k < 4; ++k)
          if (k != f) tri[std::size_t(n++)] = out.mesh.positions[std::size_t(tet[std::size_t(k)])];
        if (out.bodies[b].cutAt((tri[0] + tri[1] + tri[2]) / 3.0)) out.bodySurfaces[b].push_back(tri);
      }
    }
  }
  // Bone and body tets first: where the two sides of a sliding cut overlap
  // (the owner's bone staircase turned past the socket's), the
  // rasterization's lowest-index tet gives the posed voxel the rigid bone's
  // label, not the tissue's it sweeps over.
  {
    std::vector<std::size_t> order(out.mesh.tetCount());
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::stable_partition(order.begin(), order.end(), [&](std::size_t t) { return out.mesh.labels[t] != kSoftTissueTag; });
    std::vector<Tet> tets(order.size());
    std::vector<std::int32_t> labels(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) {
      tets[i] = out.mesh.tets[order[i]];
      labels[i] = out.mesh.labels[order[i]];
    }
    out.mesh.tets = std::move(tets);
    out.mesh.labels = std::move(labels);
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

std::vector<std::int32_t> limbGroupSides(const ArticulatedMesh& mesh, const skeleton::Skeleton& skeleton) {
  const std::vector<Part> part = tetParts(mesh, skeleton);
  std::vector<std::int32_t> side(mesh.mesh.vertexCount(), -2);  // -2: no tet yet
  for (std::size_t t = 0; t < part.size(); ++t) {
    const std::int32_t group = part[t] == Part::None ? -1 : std::int32_t(skeleton::labelGroupOf(part[t]));
    for (const std::int32_t v : mesh.mesh.tets[t]) {
      std::int32_t& s = side[std::size_t(v)];
      s = s == -2 || s == group ? group : -1;
    }
  }
  for (std::int32_t& s : side) s = std::max(s, -1);
  return side;
}

}  // namespace vox
