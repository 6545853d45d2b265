#include "geometry/skeleton/joints.h"

#include "geometry/ascii_text.h"
#include "geometry/cancellation.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

namespace vox::skeleton {

namespace {

constexpr std::array<const char*, kDofCount> kAxial = {"flexion", "lateral_flexion", "rotation"};
constexpr std::array<const char*, kDofCount> kBall = {"flexion", "abduction", "rotation"};
constexpr std::array<const char*, kDofCount> kHinge = {"flexion", nullptr, nullptr};
constexpr std::array<const char*, kDofCount> kWrist = {"flexion", "abduction", nullptr};
using Ranges = std::array<std::array<double, 2>, kDofCount>;
constexpr Ranges kNeckRange = {{{-40, 40}, {-35, 35}, {-45, 45}}};
constexpr Ranges kHeadRange = {{{-25, 25}, {-15, 15}, {-40, 40}}};
constexpr Ranges kShoulderRange = {{{-60, 180}, {-30, 180}, {-90, 90}}};
constexpr Ranges kElbowRange = {{{0, 150}, {0, 0}, {0, 0}}};
constexpr Ranges kWristRange = {{{-70, 80}, {-30, 30}, {0, 0}}};
constexpr Ranges kHipRange = {{{-20, 120}, {-30, 45}, {-45, 45}}};
constexpr Ranges kKneeRange = {{{0, 140}, {0, 0}, {0, 0}}};
constexpr Ranges kAnkleRange = {{{-50, 20}, {0, 0}, {0, 0}}};

const std::array<JointKind, kJointCount> kKinds = {{
    {JointId::Neck, "neck", Part::Trunk, Part::Neck, Side::Axial, -1.0, kAxial, kNeckRange},
    {JointId::Head, "head", Part::Neck, Part::Head, Side::Axial, -1.0, kAxial, kHeadRange},
    {JointId::RightShoulder, "right_shoulder", Part::Trunk, Part::RightUpperArm, Side::Right, 1.0, kBall, kShoulderRange},
    {JointId::RightElbow, "right_elbow", Part::RightUpperArm, Part::RightForearm, Side::Right, 1.0, kHinge, kElbowRange},
    {JointId::RightWrist, "right_wrist", Part::RightForearm, Part::RightHand, Side::Right, 1.0, kWrist, kWristRange},
    {JointId::LeftShoulder, "left_shoulder", Part::Trunk, Part::LeftUpperArm, Side::Left, 1.0, kBall, kShoulderRange},
    {JointId::LeftElbow, "left_elbow", Part::LeftUpperArm, Part::LeftForearm, Side::Left, 1.0, kHinge, kElbowRange},
    {JointId::LeftWrist, "left_wrist", Part::LeftForearm, Part::LeftHand, Side::Left, 1.0, kWrist, kWristRange},
    {JointId::RightHip, "right_hip", Part::Pelvis, Part::RightThigh, Side::Right, 1.0, kBall, kHipRange},
    {JointId::RightKnee, "right_knee", Part::RightThigh, Part::RightLowerLeg, Side::Right, -1.0, kHinge, kKneeRange},
    {JointId::RightAnkle, "right_ankle", Part::RightLowerLeg, Part::RightFoot, Side::Right, 1.0, kHinge, kAnkleRange},
    {JointId::LeftHip, "left_hip", Part::Pelvis, Part::LeftThigh, Side::Left, 1.0, kBall, kHipRange},
    {JointId::LeftKnee, "left_knee", Part::LeftThigh, Part::LeftLowerLeg, Side::Left, -1.0, kHinge, kKneeRange},
    {JointId::LeftAnkle, "left_ankle", Part::LeftLowerLeg, Part::LeftFoot, Side::Left, 1.0, kHinge, kAnkleRange},
}};

constexpr double kDegrees = std::numbers::pi / 180.0;

// A bone's voxel centres along its principal axis.
struct BoneShape {
  std::vector<Eigen::Vector3d> points;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  std::vector<double> along;  // per point: (p - centroid) . axis
  double lo = 0.0, hi = 0.0;  // 0.5 % and 99.5 % quantiles of `along`

  double length() const { return hi - lo; }
  double project(const Eigen::Vector3d& p) const { return (p - centroid).dot(axis); }
  // True when p projects nearer the `hi` end than the `lo` end.
  bool nearerHigh(const Eigen::Vector3d& p) const { return std::abs(project(p) - hi) < std::abs(project(p) - lo); }
  // The points within `depth` mm (along the axis) of one end.
  std::vector<Eigen::Vector3d> end(bool high, double depth) const {
    std::vector<Eigen::Vector3d> out;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (high ? along[i] >= hi - depth : along[i] <= lo + depth) out.push_back(points[i]);
    return out;
  }
};

Eigen::Vector3d mean(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) s += p;
  return s / double(std::max<std::size_t>(points.size(), 1));
}

std::vector<Eigen::Vector3d> centres(const GridGeometry& g, const std::vector<std::int64_t>& voxels) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(voxels.size());
  for (const std::int64_t v : voxels) {
    const Index3 c = g.ijk(v);
    out.push_back(g.voxelCenter(c[0], c[1], c[2]));
  }
  return out;
}

BoneShape shapeOf(const GridGeometry& g, const std::vector<std::int64_t>& voxels) {
  throwIfCancelled();  // a bone of millions of voxels
  BoneShape s;
  s.points = centres(g, voxels);
  s.centroid = mean(s.points);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : s.points) cov += (p - s.centroid) * (p - s.centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  s.axis = eig.eigenvectors().col(2).normalized();
  s.along.reserve(s.points.size());
  for (const Eigen::Vector3d& p : s.points) s.along.push_back(s.project(p));
  std::vector<double> sorted = s.along;
  std::sort(sorted.begin(), sorted.end());
  const auto quantile = [&](double q) { return sorted[std::size_t(std::lround(q * double(sorted.size() - 1)))]; };
  s.lo = quantile(0.005);
  s.hi = quantile(0.995);
  return s;
}

// The widest direction of `points` across `axis`, when the spread along it
// is at least `ratio` times the spread across it; nullopt otherwise.
std::optional<Eigen::Vector3d> widestAcross(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& axis, double ratio) {
  if (points.size() < 4) return std::nullopt;
  const Eigen::Vector3d c = mean(points);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d d = (p - c) - (p - c).dot(axis) * axis;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  // Eigenvalues increase; the smallest is ~0 (along the axis).
  const double wide = eig.eigenvalues()(2), deep = eig.eigenvalues()(1);
  if (!(wide > ratio * ratio * deep)) return std::nullopt;  // variances: ratio of widths squared
  return Eigen::Vector3d(eig.eigenvectors().col(2).normalized());
}

// `direction` made perpendicular to `axis` and pointing to the body's right;
// nullopt when (nearly) parallel to the axis.
std::optional<Eigen::Vector3d> acrossTowardsRight(const Eigen::Vector3d& direction, const Eigen::Vector3d& axis, const Eigen::Vector3d& right) {
  const Eigen::Vector3d d = direction - direction.dot(axis) * axis;
  if (d.norm() < 0.1 * direction.norm()) return std::nullopt;
  const Eigen::Vector3d u = d.normalized();
  return u.dot(right) < 0.0 ? Eigen::Vector3d(-u) : u;
}

// The flexion axis: a hinge found on the bone end, made perpendicular to the
// bone, else the body's left-right axis itself.
void setLeftRight(Joint& joint, const std::optional<Eigen::Vector3d>& hinge, const AnatomicalFrame& frame) {
  joint.anterior = frame.anterior;
  joint.superior = frame.superior;
  if (hinge) {
    if (const auto u = acrossTowardsRight(*hinge, joint.longAxis, frame.right)) {
      joint.leftRight = *u;
      return;
    }
  }
  joint.leftRight = frame.right;
  joint.axisMethod = "body axis";
}

bool contains(const std::vector<std::int64_t>& sorted, std::int64_t v) { return std::binary_search(sorted.begin(), sorted.end(), v); }

// Voxels of `voxels` (sorted) with a 6-neighbour outside the set.
std::vector<std::int64_t> surfaceVoxels(const GridGeometry& g, const std::vector<std::int64_t>& voxels) {
  std::vector<std::int64_t> out;
  for (const std::int64_t v : voxels) {
    const Index3 c = g.ijk(v);
    static constexpr int kSteps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& s : kSteps) {
      const std::int64_t i = c[0] + s[0], j = c[1] + s[1], k = c[2] + s[2];
      if (!g.contains(i, j, k) || !contains(voxels, g.index(i, j, k))) {
        out.push_back(v);
        break;
      }
    }
  }
  return out;
}

// The wrist's centre: the hand's bones this near the forearm bones (a
// share of the forearm bones' length: 24 to 26 mm on the ICRP adults) are
// the carpus, whose centroid (about the capitate's head) the hand turns
// about: deeper reaches the metacarpals; the proximal row alone turns the
// carpals into the radius over the wrist's range.
constexpr double kCarpusDepth = 0.1;

// The points of `points` within `reach` mm of a point of `other`, on a cell
// grid of `reach` over `other`.
std::vector<Eigen::Vector3d> pointsNear(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& other, double reach) {
  std::vector<Eigen::Vector3d> out;
  if (points.empty() || other.empty() || !(reach > 0.0)) return out;
  const auto cellOf = [reach](const Eigen::Vector3d& p) {
    return std::array<std::int64_t, 3>{std::int64_t(std::floor(p[0] / reach)), std::int64_t(std::floor(p[1] / reach)), std::int64_t(std::floor(p[2] / reach))};
  };
  std::map<std::array<std::int64_t, 3>, std::vector<Eigen::Vector3d>> cells;
  for (const Eigen::Vector3d& q : other) cells[cellOf(q)].push_back(q);
  const double r2 = reach * reach;
  for (const Eigen::Vector3d& p : points) {
    const std::array<std::int64_t, 3> c = cellOf(p);
    bool near = false;
    for (std::int64_t dz = -1; dz <= 1 && !near; ++dz)
      for (std::int64_t dy = -1; dy <= 1 && !near; ++dy)
        for (std::int64_t dx = -1; dx <= 1 && !near; ++dx) {
          const auto it = cells.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == cells.end()) continue;
          for (const Eigen::Vector3d& q : it->second)
            if ((p - q).squaredNorm() <= r2) {
              near = true;
              break;
            }
        }
    if (near) out.push_back(p);
  }
  return out;
}

// The point of `child` nearest to any point of `parent` (brute force over
// the parent points within `reach` mm of the child's bounding box).
std::optional<Eigen::Vector3d> nearestTo(const std::vector<Eigen::Vector3d>& child, const std::vector<Eigen::Vector3d>& parent, double reach) {
  if (child.empty() || parent.empty()) return std::nullopt;
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : child) box.extend(p);
  std::vector<Eigen::Vector3d> near;
  for (const Eigen::Vector3d& q : parent)
    if (box.exteriorDistance(q) <= reach) near.push_back(q);
  const std::vector<Eigen::Vector3d>& candidates = near.empty() ? parent : near;
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d at = child.front();
  for (const Eigen::Vector3d& p : child)
    for (const Eigen::Vector3d& q : candidates)
      if (const double d = (p - q).squaredNorm(); d < best) {
        best = d;
        at = p;
      }
  return at;
}

// Centre of a ball joint: a sphere fitted to the head's surface voxels near
// the contact with the parent's bones.
void ballCentre(Joint& joint, const GridGeometry& g, const BoneVoxels& bone, const BoneShape& shape, const Eigen::Vector3d& contact,
                double headFraction) {
  const double reach = headFraction * shape.length();
  std::vector<Eigen::Vector3d> region;
  for (const Eigen::Vector3d& p : centres(g, surfaceVoxels(g, bone.voxels)))
    if ((p - contact).norm() <= reach) region.push_back(p);
  const double tolerance = 0.5 * g.spacing.norm();
  std::optional<SphereFit> fit;
  std::vector<Eigen::Vector3d> used = region;
  for (int round = 0; round < 4 && used.size() >= 10; ++round) {
    fit = fitSphere(used);
    if (!fit) break;
    std::vector<Eigen::Vector3d> kept;
    for (const Eigen::Vector3d& p : region)
      if (std::abs((p - fit->centre).norm() - fit->radius) <= tolerance) kept.push_back(p);
    if (kept.size() == used.size() || kept.size() < 10) break;
    used = std::move(kept);
  }
  const double length = shape.length();
  // The contact voxel lies on the head's surface: the centre is a radius away.
  if (fit && fit->radius >= 0.02 * length && fit->radius <= 0.2 * length &&
      std::abs((fit->centre - contact).norm() - fit->radius) <= 2.0 * tolerance) {
    joint.centre = fit->centre;
    joint.radius = fit->radius;
    joint.method = "sphere fit";
  } else {
    joint.centre = region.empty() ? contact : mean(region);
    joint.method = "head centroid";
  }
}

// std::llround (halves away from zero) without the library call: the hinge
// search rounds every child point at every trial centre and turn. The
// fraction x - trunc(x) is exact below 2^52.
std::int64_t roundHalfAway(double x) {
  if (!(std::abs(x) < 4503599627370496.0)) return std::llround(x);
  const auto t = std::int64_t(x);
  const double rest = x - double(t);
  return rest >= 0.5 ? t + 1 : rest <= -0.5 ? t - 1 : t;
}

// A bone's voxels as a bitmap over their bounding box (constant-time lookup).
class VoxelBitmap {
public:
  VoxelBitmap(const GridGeometry& g, const std::vector<std::int64_t>& voxels) : g_(g) {
    lo_ = {std::numeric_limits<std::int64_t>::max(), std::numeric_limits<std::int64_t>::max(), std::numeric_limits<std::int64_t>::max()};
    hi_ = {-1, -1, -1};
    for (const std::int64_t v : voxels) {
      const Index3 c = g.ijk(v);
      for (int a = 0; a < 3; ++a) {
        lo_[std::size_t(a)] = std::min(lo_[std::size_t(a)], c[a]);
        hi_[std::size_t(a)] = std::max(hi_[std::size_t(a)], c[a]);
      }
    }
    if (voxels.empty()) return;
    for (int a = 0; a < 3; ++a) size_[std::size_t(a)] = hi_[std::size_t(a)] - lo_[std::size_t(a)] + 1;
    bits_.assign(std::size_t(size_[0] * size_[1] * size_[2]), false);
    for (const std::int64_t v : voxels) {
      const Index3 c = g.ijk(v);
      bits_[offset(c[0], c[1], c[2])] = true;
    }
  }
  // Whether the voxel nearest the grid-frame point p is set.
  bool at(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d c = g_.continuousIndex(p);
    const std::int64_t i = roundHalfAway(c[0]), j = roundHalfAway(c[1]), k = roundHalfAway(c[2]);
    if (bits_.empty() || i < lo_[0] || j < lo_[1] || k < lo_[2] || i > hi_[0] || j > hi_[1] || k > hi_[2]) return false;
    return bits_[offset(i, j, k)];
  }

private:
  std::size_t offset(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return std::size_t(((k - lo_[2]) * size_[1] + (j - lo_[1])) * size_[0] + (i - lo_[0]));
  }
  const GridGeometry& g_;
  std::array<std::int64_t, 3> lo_{}, hi_{}, size_{};
  std::vector<bool> bits_;
};

// Child bone voxels (`child`: surface voxel centres) that the hinge's
// flexion, every 10 degrees up to the top of its range, carries into the
// parent's bone: how well `centre` serves as the hinge's centre (0: the
// child's bone end turns clear of the parent's). Counting stops past
// `enough`.
std::size_t hingeOverlaps(const std::vector<Eigen::Matrix3d>& turns, const Eigen::Vector3d& centre, const std::vector<Eigen::Vector3d>& child,
                          const VoxelBitmap& parent, std::size_t enough) {
  std::size_t n = 0;
  for (const Eigen::Matrix3d& r : turns)
    for (const Eigen::Vector3d& p : child)
      if (parent.at(centre + r * (p - centre)) && ++n > enough) return n;
  return n;
}

// ", cleared over flexion and abduction": how clearHinge moved a centre.
std::string clearedOver(const JointKind& kind) {
  std::vector<std::string> dofs;
  for (int d = 0; d < kDofCount; ++d)
    if (kind.dofNames[std::size_t(d)] && kind.range[std::size_t(d)][0] < kind.range[std::size_t(d)][1]) dofs.push_back(kind.dofNames[std::size_t(d)]);
  return ", cleared over " + joinedWords(dofs);
}

// The joint's centre moved across its flexion axis to where the child's bone
// end turns clear of the parent's bone over the joint's whole range, every 10
// degrees of each degree of freedom it has, the nearest such place to the
// estimate (the parent bone's end, which lies on its shaft, while the
// trochlea and the femoral condyles turn about a centre in front of the
// humeral shaft and behind the femoral one; the cervical spine's ends, about
// which a single pivot turns the vertebrae into their neighbours). Searched within an
// eighth of the parent bone's length, on a grid of two finest voxels, then of
// half a voxel about the best; the fewest overlaps win, then the nearest to
// the estimate; a move under a finest voxel is not made. With
// `minClearance` (mm), among the places with the fewest overlaps those whose
// flexion axis passes at least that far from the child's bone come first: the
// elbow's and knee's axis runs through the trochlea and the condyles, which
// the ulna's notch and the tibia's plateaus wrap at a distance, so an axis
// that grazes the child's bone is the estimate's error, and the articular
// mesh could cut no cylinder about it. Returns the distance moved (mm).
double clearHinge(Joint& joint, const GridGeometry& g, const BoneVoxels& parent, const BoneShape& parentShape, const BoneVoxels& child,
                  double minClearance = 0.0) {
  const double reach = 0.3 * parentShape.length(), range = 0.125 * parentShape.length();
  std::vector<Eigen::Vector3d> near;
  for (const Eigen::Vector3d& p : centres(g, surfaceVoxels(g, child.voxels)))
    if ((p - joint.centre).norm() < reach) near.push_back(p);
  // At most kSamples of them, evenly strided (fine grids).
  constexpr std::size_t kSamples = 4000;
  if (near.size() > kSamples) {
    std::vector<Eigen::Vector3d> kept;
    kept.reserve(kSamples);
    for (std::size_t i = 0; i < kSamples; ++i) kept.push_back(near[i * near.size() / kSamples]);
    near.swap(kept);
  }
  const Eigen::Vector3d axis = joint.axis(Dof::Flexion).normalized();
  Eigen::Vector3d u = joint.longAxis - joint.longAxis.dot(axis) * axis;
  if (near.empty() || range <= 0.0 || u.norm() < 1e-6) return 0.0;
  u.normalize();
  const Eigen::Vector3d w = axis.cross(u);
  std::vector<Eigen::Matrix3d> turns;
  for (const Dof dof : {Dof::Flexion, Dof::Abduction, Dof::Rotation}) {
    const std::array<double, 2>& r = joint.kind().range[std::size_t(dof)];
    for (double degrees = r[0]; degrees < r[1] + 10.0; degrees += 10.0) {
      std::array<double, kDofCount> angles{};
      angles[std::size_t(dof)] = std::min(degrees, r[1]);  // the range's ends too
      if (angles[std::size_t(dof)] != 0.0) turns.push_back(joint.rotation(angles));
    }
  }
  const VoxelBitmap parentBits(g, parent.voxels);
  const Eigen::Vector3d estimate = joint.centre;
  // Whether the flexion axis through `centre` passes minClearance or more
  // from every child point.
  const auto clears = [&](const Eigen::Vector3d& centre) {
    const double limit = minClearance * minClearance;
    for (const Eigen::Vector3d& p : near) {
      const Eigen::Vector3d d = p - centre;
      if ((d - d.dot(axis) * axis).squaredNorm() < limit) return false;
    }
    return true;
  };
  std::size_t best = hingeOverlaps(turns, estimate, near, parentBits, std::numeric_limits<std::size_t>::max());
  bool bestClears = clears(estimate);
  if (best == 0 && bestClears) return 0.0;
  Eigen::Vector2d bestOffset = Eigen::Vector2d::Zero();
  const auto consider = [&](const Eigen::Vector2d& o) {
    if (o.norm() > range) return;
    const Eigen::Vector3d centre = estimate + o[0] * u + o[1] * w;
    const std::size_t n = hingeOverlaps(turns, centre, near, parentBits, best);
    if (n > best) return;
    const bool c = clears(centre);
    if (n < best || (c && !bestClears) || (c == bestClears && o.norm() < bestOffset.norm())) {
      best = n;
      bestClears = c;
      bestOffset = o;
    }
  };
  const double coarse = 2.0 * g.spacing.minCoeff();
  const int steps = int(std::ceil(range / coarse));
  for (int a = -steps; a <= steps; ++a)
    for (int b = -steps; b <= steps; ++b) consider(Eigen::Vector2d(a, b) * coarse);
  const Eigen::Vector2d around = bestOffset;
  for (int a = -4; a <= 4; ++a)
    for (int b = -4; b <= 4; ++b) consider(around + Eigen::Vector2d(a, b) * (0.25 * coarse));
  // A move under a finest voxel is within what the bone end's voxels say.
  if (bestOffset.norm() < g.spacing.minCoeff()) return 0.0;
  joint.centre = estimate + bestOffset[0] * u + bestOffset[1] * w;
  return bestOffset.norm();
}

std::vector<Eigen::Vector3d> partBonePoints(const GridGeometry& g, const BodyParts& bones, Part part) {
  std::vector<Eigen::Vector3d> out;
  for (const BoneVoxels& b : bones.bones)
    if (bonePart(b.bone, b.side) == part) {
      throwIfCancelled();
      const std::vector<Eigen::Vector3d> p = centres(g, b.voxels);
      out.insert(out.end(), p.begin(), p.end());
    }
  return out;
}

struct Limb {
  Bone upper, middle, end;
  JointId top, mid, low;
  double headFraction;
  bool lowHinge;  // the lowest joint's axis from its bone end (ankle) or the body (wrist)
};

void estimateLimb(std::array<std::optional<Joint>, kJointCount>& found, const GridGeometry& g, const BodyParts& bones, const Limb& limb,
                  Side side, const std::vector<Eigen::Vector3d>& parentBones) {
  const AnatomicalFrame& f = bones.frame;
  const BoneVoxels* upper = bones.find(limb.upper, side);
  const BoneVoxels* middle = bones.find(limb.middle, side);
  const BoneVoxels* end = bones.find(limb.end, side);
  std::optional<BoneShape> upperShape, middleShape, endShape;
  if (upper) upperShape = shapeOf(g, upper->voxels);
  if (middle) middleShape = shapeOf(g, middle->voxels);
  if (end) endShape = shapeOf(g, end->voxels);

  // Which end of the upper bone is proximal: the one away from the middle
  // bone, else the one nearest the parent's bones. The top joint (shoulder,
  // hip) is fitted at that end, where it comes nearest the parent's bones.
  std::optional<bool> upperProximalHigh;
  if (upperShape && middleShape) upperProximalHigh = !upperShape->nearerHigh(middleShape->centroid);
  if (upperShape && !parentBones.empty()) {
    const BoneShape& s = *upperShape;
    std::vector<Eigen::Vector3d> ends;
    for (const bool high : {true, false})
      if (!upperProximalHigh || *upperProximalHigh == high) {
        const std::vector<Eigen::Vector3d> e = s.end(high, 0.25 * s.length());
        ends.insert(ends.end(), e.begin(), e.end());
      }
    if (const auto contact = nearestTo(ends, parentBones, 40.0)) {
      Joint j;
      j.id = limb.top;
      ballCentre(j, g, *upper, s, *contact, limb.headFraction);
      if (!upperProximalHigh) upperProximalHigh = s.nearerHigh(*contact);
      found[std::size_t(limb.top)] = j;
    }
  }

  // Middle joint (elbow, knee): the upper bone's distal end, hinge from its width.
  if (upperShape && middleShape && upperProximalHigh) {
    const BoneShape& s = *upperShape;
    const std::vector<Eigen::Vector3d> tip = s.end(!*upperProximalHigh, 0.08 * s.length());
    Joint j;
    j.id = limb.mid;
    j.centre = mean(tip);
    j.method = "distal end";
    found[std::size_t(limb.mid)] = j;
  }
  // Low joint (wrist, ankle): the middle bone's end nearer the end bones.
  // The wrist's, where the hand turns: the centroid of the hand's bones
  // within the carpus' depth of the forearm bones (the carpals, about the
  // capitate), if any lie that near.
  if (middleShape && endShape) {
    const BoneShape& s = *middleShape;
    const bool distalHigh = s.nearerHigh(endShape->centroid);
    Joint j;
    j.id = limb.low;
    j.centre = mean(s.end(distalHigh, 0.06 * s.length()));
    j.method = "distal end";
    if (!limb.lowHinge) {
      const std::vector<Eigen::Vector3d> forearm = centres(g, surfaceVoxels(g, middle->voxels));
      const std::vector<Eigen::Vector3d> carpus = pointsNear(centres(g, end->voxels), forearm, kCarpusDepth * s.length());
      if (!carpus.empty()) {
        j.centre = mean(carpus);
        j.method = "centroid of the carpus";
        // The sphere about it up to the forearm bones: the articular
        // surfaces within it, as a ball's (bone_overlap.h).
        j.radius = std::numeric_limits<double>::infinity();
        for (const Eigen::Vector3d& p : forearm) j.radius = std::min(j.radius, (p - j.centre).norm());
      }
    }
    found[std::size_t(limb.low)] = j;
  }

  // Long axes down the chain, then the left-right (flexion) axes.
  auto& top = found[std::size_t(limb.top)];
  auto& mid = found[std::size_t(limb.mid)];
  auto& low = found[std::size_t(limb.low)];
  const auto towards = [](Joint& j, const Eigen::Vector3d& target, const Eigen::Vector3d& fallback) {
    const Eigen::Vector3d d = target - j.centre;
    j.longAxis = d.norm() > 1e-6 ? Eigen::Vector3d(d.normalized()) : fallback;
  };
  const auto setAxes = [&] {
    if (top) {
      const Eigen::Vector3d distal = mid ? mid->centre : mean(upperShape->end(!*upperProximalHigh, 0.02 * upperShape->length()));
      towards(*top, distal, -f.superior);
      setLeftRight(*top, std::nullopt, f);
    }
    if (mid) {
      towards(*mid, low ? low->centre : middleShape->centroid, -f.superior);
      const BoneShape& s = *upperShape;
      const std::optional<Eigen::Vector3d> hinge = widestAcross(s.end(!*upperProximalHigh, 0.08 * s.length()), s.axis, 1.5);
      mid->axisMethod = "bone end width";
      setLeftRight(*mid, hinge, f);
    }
    if (low) {
      towards(*low, endShape->centroid, -f.superior);
      std::optional<Eigen::Vector3d> hinge;
      if (limb.lowHinge) {
        const BoneShape& s = *middleShape;
        hinge = widestAcross(s.end(s.nearerHigh(endShape->centroid), 0.06 * s.length()), s.axis, 1.5);
      }
      low->axisMethod = "bone end width";
      setLeftRight(*low, hinge, f);
    }
  };
  setAxes();
  // The hinge's centre where the child's bone end turns clear of the
  // parent's, then the axes again from it.
  // The wrist's and ankle's first: the elbow's and knee's long axis points
  // at them.
  // (The carpus' centre is where the hand turns: cleared over the wrist's
  // whole range it moved about 50 mm up the forearm, and the hand swung
  // about a point inside the radius.)
  if (low && middle && end && low->method == "distal end" && clearHinge(*low, g, *middle, *middleShape, *end) > 0.0) {
    low->method += clearedOver(low->kind());
    setAxes();
  }
  // The elbow's and knee's axis at least three finest voxels from the
  // forearm's and lower leg's bone.
  if (mid && upper && middle && clearHinge(*mid, g, *upper, *upperShape, *middle, 3.0 * g.spacing.minCoeff()) > 0.0) {
    mid->method = "distal end" + clearedOver(mid->kind());
    setAxes();
  }
}

}  // namespace

const JointKind& jointKind(JointId id) { return kKinds[std::size_t(id)]; }

std::optional<JointId> jointFromName(const std::string& name) {
  std::string n;
  for (const unsigned char c : name) n += c == '-' ? '_' : char(std::tolower(c));
  for (const JointKind& k : kKinds)
    if (n == k.name) return k.id;
  return std::nullopt;
}

std::string jointNames() {
  std::string s;
  for (const JointKind& k : kKinds) s += std::string(s.empty() ? "" : ", ") + k.name;
  return s;
}

std::optional<JointId> jointMoving(Part part) {
  for (const JointKind& k : kKinds)
    if (k.child == part) return k.id;
  return std::nullopt;
}

const Joint* findJoint(std::span<const Joint> joints, JointId id) {
  for (const Joint& j : joints)
    if (j.id == id) return &j;
  return nullptr;
}

std::optional<JointId> jointBetween(Part a, Part b) {
  for (const JointKind& k : kKinds)
    if ((k.parent == a && k.child == b) || (k.parent == b && k.child == a)) return k.id;
  return std::nullopt;
}

Part parentPart(Part part) {
  if (part == Part::Pelvis) return Part::Trunk;
  if (const auto j = jointMoving(part)) return jointKind(*j).parent;
  return Part::None;
}

Eigen::Vector3d Joint::axis(Dof dof) const {
  const double side = kind().side == Side::Left ? -1.0 : 1.0;
  switch (dof) {
    case Dof::Flexion: return kind().flexionSign * leftRight;
    // About the front-back axis; the sign follows whether the part hangs
    // down (limbs) or stands up (neck, head) from the joint.
    case Dof::Abduction: return (longAxis.dot(superior) < 0.0 ? -side : side) * anterior;
    case Dof::Rotation: return -side * longAxis;
  }
  return leftRight;
}

Eigen::Matrix3d Joint::rotation(const std::array<double, kDofCount>& degrees) const {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  for (int d = 0; d < kDofCount; ++d)
    if (degrees[std::size_t(d)] != 0.0) r = r * Eigen::AngleAxisd(degrees[std::size_t(d)] * kDegrees, axis(Dof(d))).toRotationMatrix();
  return r;
}

std::optional<SphereFit> fitSphere(std::span<const Eigen::Vector3d> points) {
  const Eigen::Index n = Eigen::Index(points.size());
  if (n < 4) return std::nullopt;
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) m += p;
  m /= double(n);
  // Algebraic fit: |p - m|^2 = 2 c'.(p - m) + k, linear in c' and k.
  Eigen::MatrixX4d a(n, 4);
  Eigen::VectorXd b(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d q = points[std::size_t(i)] - m;
    a.row(i) << 2.0 * q.x(), 2.0 * q.y(), 2.0 * q.z(), 1.0;
    b(i) = q.squaredNorm();
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixX4d> qr(a);
  if (qr.rank() < 4) return std::nullopt;
  const Eigen::Vector4d x = qr.solve(b);
  Eigen::Vector3d c = x.head<3>();
  const double r2 = x(3) + c.squaredNorm();
  if (!(r2 > 0.0)) return std::nullopt;
  double r = std::sqrt(r2);
  // Gauss-Newton on the geometric residuals |p - c| - r.
  for (int it = 0; it < 20; ++it) {
    Eigen::Matrix4d jtj = Eigen::Matrix4d::Zero();
    Eigen::Vector4d jtr = Eigen::Vector4d::Zero();
    for (const Eigen::Vector3d& p : points) {
      const Eigen::Vector3d d = (p - m) - c;
      const double l = d.norm();
      if (l == 0.0) continue;
      Eigen::Vector4d jrow;
      jrow << -d / l, -1.0;
      jtj += jrow * jrow.transpose();
      jtr += jrow * (l - r);
    }
    const Eigen::Vector4d step = jtj.ldlt().solve(-jtr);
    if (!step.allFinite()) break;
    c += step.head<3>();
    r += step(3);
    if (step.norm() < 1e-9 * (1.0 + r)) break;
  }
  SphereFit fit;
  fit.centre = c + m;
  fit.radius = std::abs(r);
  double ss = 0.0;
  for (const Eigen::Vector3d& p : points) ss += std::pow((p - fit.centre).norm() - fit.radius, 2);
  fit.rms = std::sqrt(ss / double(n));
  fit.points = points.size();
  if (!fit.centre.allFinite() || !std::isfinite(fit.radius)) return std::nullopt;
  return fit;
}

std::vector<Joint> estimateJoints(const GridGeometry& g, const BodyParts& bones) {
  const AnatomicalFrame& f = bones.frame;
  std::array<std::optional<Joint>, kJointCount> found;
  const std::vector<Eigen::Vector3d> trunk = partBonePoints(g, bones, Part::Trunk);
  const std::vector<Eigen::Vector3d> pelvis = partBonePoints(g, bones, Part::Pelvis);
  const std::vector<Eigen::Vector3d> head = partBonePoints(g, bones, Part::Head);

  if (const BoneVoxels* cervical = bones.find(Bone::CervicalSpine, Side::Axial)) {
    const BoneShape s = shapeOf(g, cervical->voxels);
    const bool upperHigh = s.axis.dot(f.superior) > 0.0;
    const Eigen::Vector3d lowCentre = mean(s.end(!upperHigh, 0.15 * s.length()));
    const Eigen::Vector3d highCentre = mean(s.end(upperHigh, 0.15 * s.length()));
    const Eigen::Vector3d up = (highCentre - lowCentre).norm() > 1e-6 ? Eigen::Vector3d((highCentre - lowCentre).normalized()) : f.superior;
    if (!trunk.empty()) {
      Joint j;
      j.id = JointId::Neck;
      j.centre = lowCentre;
      j.longAxis = up;
      j.method = "cervical spine, lower end";
      setLeftRight(j, std::nullopt, f);
      if (const BoneVoxels* thoracic = bones.find(Bone::ThoracicSpine, Side::Axial))
        if (clearHinge(j, g, *thoracic, shapeOf(g, thoracic->voxels), *cervical) > 0.0) j.method += clearedOver(j.kind());
      found[std::size_t(JointId::Neck)] = j;
    }
    if (!head.empty()) {
      Joint j;
      j.id = JointId::Head;
      j.centre = highCentre;
      const Eigen::Vector3d d = mean(head) - highCentre;
      j.longAxis = d.norm() > 1e-6 ? Eigen::Vector3d(d.normalized()) : up;
      j.method = "cervical spine, upper end";
      setLeftRight(j, std::nullopt, f);
      if (const BoneVoxels* cranium = bones.find(Bone::Cranium, Side::Axial))
        if (clearHinge(j, g, *cervical, s, *cranium) > 0.0) {
          j.method += clearedOver(j.kind());
          const Eigen::Vector3d e = mean(head) - j.centre;
          if (e.norm() > 1e-6) j.longAxis = e.normalized();
        }
      found[std::size_t(JointId::Head)] = j;
    }
  }
  for (const Side side : {Side::Right, Side::Left}) {
    const bool right = side == Side::Right;
    estimateLimb(found, g, bones,
                 {Bone::Humerus, Bone::ForearmBones, Bone::HandBones, right ? JointId::RightShoulder : JointId::LeftShoulder,
                  right ? JointId::RightElbow : JointId::LeftElbow, right ? JointId::RightWrist : JointId::LeftWrist, 0.12, false},
                 side, trunk);
    estimateLimb(found, g, bones,
                 {Bone::Femur, Bone::LowerLegBones, Bone::FootBones, right ? JointId::RightHip : JointId::LeftHip,
                  right ? JointId::RightKnee : JointId::LeftKnee, right ? JointId::RightAnkle : JointId::LeftAnkle, 0.10, true},
                 side, pelvis);
  }
  std::vector<Joint> out;
  for (auto& j : found)
    if (j) out.push_back(std::move(*j));
  return out;
}

}  // namespace vox::skeleton
