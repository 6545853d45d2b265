#include "geometry/skeleton/bone_overlap.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace vox::skeleton {

std::vector<Part> partSubtree(Part part) {
  std::vector<Part> out;
  for (int p = 1; p <= kPartCount; ++p)
    for (Part q = Part(p); q != Part::None; q = parentPart(q))
      if (q == part) {
        out.push_back(Part(p));
        break;
      }
  return out;
}

BoneOverlapIndex::BoneOverlapIndex(const BodyParts& parts) : grid_(parts.parts.geometry()) {
  const GridGeometry& g = grid_;
  const Label* labels = parts.parts.data();
  bonePart_.assign(std::size_t(g.voxelCount()), 0);
  for (const BoneVoxels& b : parts.bones)
    for (const std::int64_t v : b.voxels) {
      const Label p = labels[std::size_t(v)];
      if (p == 0 || p > kPartCount) continue;
      const Index3 c = g.ijk(v);
      const Eigen::Vector3d x = g.voxelCenter(c[0], c[1], c[2]);
      points_[p].push_back(x);
      bonePart_[std::size_t(v)] = std::uint8_t(p);
      boxes_[p].extend(x);
    }
  // The wrists' articular faces: each side's bone voxels within a voxel
  // (the largest spacing) of the other side's bone at rest.
  const double slack = g.spacing.maxCoeff();
  for (const JointId id : {JointId::RightWrist, JointId::LeftWrist}) {
    const Part sides[2] = {jointKind(id).parent, jointKind(id).child};
    for (int s = 0; s < 2; ++s) {
      const Part p = sides[s], other = sides[1 - s];
      std::vector<std::uint8_t>& face = face_[std::size_t(p)];
      face.assign(points_[std::size_t(p)].size(), 0);
      Eigen::AlignedBox3d near = boxes_[std::size_t(other)];
      if (near.isEmpty()) continue;
      near.extend(near.min() - Eigen::Vector3d::Constant(slack)).extend(near.max() + Eigen::Vector3d::Constant(slack));
      std::array<std::int64_t, 3> reach{};
      for (int a = 0; a < 3; ++a) reach[std::size_t(a)] = std::int64_t(std::floor(slack / g.spacing[a]));
      for (std::size_t i = 0; i < face.size(); ++i) {
        const Eigen::Vector3d& x = points_[std::size_t(p)][i];
        if (!near.contains(x)) continue;
        const Eigen::Vector3d q = g.continuousIndex(x);
        const std::int64_t ci = std::llround(q[0]), cj = std::llround(q[1]), ck = std::llround(q[2]);
        for (std::int64_t k = ck - reach[2]; k <= ck + reach[2] && !face[i]; ++k)
          for (std::int64_t j = cj - reach[1]; j <= cj + reach[1] && !face[i]; ++j)
            for (std::int64_t ii = ci - reach[0]; ii <= ci + reach[0] && !face[i]; ++ii)
              if (g.contains(ii, j, k) && bonePart_[std::size_t(g.index(ii, j, k))] == std::uint8_t(other) &&
                  (g.voxelCenter(ii, j, k) - x).norm() <= slack)
                face[i] = 1;
      }
    }
  }
}

std::vector<BoneOverlap> BoneOverlapIndex::under(std::span<const Joint> joints, std::span<const Eigen::Isometry3d> motions) const {
  const GridGeometry& g = grid_;
  const double slack = g.spacing.maxCoeff();
  // Bone voxels of a landing in b's bones, for each ordered pair.
  std::array<std::array<std::size_t, kPartCount + 1>, kPartCount + 1> landed{};
  for (int a = 1; a <= kPartCount; ++a) {
    if (points_[std::size_t(a)].empty() || std::size_t(a) >= motions.size()) continue;
    for (int b = 1; b <= kPartCount; ++b) {
      if (a == b || points_[std::size_t(b)].empty() || std::size_t(b) >= motions.size()) continue;
      if (motions[std::size_t(a)].isApprox(motions[std::size_t(b)], 1e-12)) continue;
      // a's bones in b's rest frame.
      const Eigen::Isometry3d t = motions[std::size_t(b)].inverse() * motions[std::size_t(a)];
      Eigen::AlignedBox3d moved;
      for (int corner = 0; corner < 8; ++corner) moved.extend(t * boxes_[std::size_t(a)].corner(Eigen::AlignedBox3d::CornerType(corner)));
      Eigen::AlignedBox3d target = boxes_[std::size_t(b)];
      target.extend(target.min() - Eigen::Vector3d::Constant(slack)).extend(target.max() + Eigen::Vector3d::Constant(slack));
      if (!moved.intersects(target)) continue;
      // A joint between them with an articular sphere (a fitted ball, a
      // wrist's) leaves its shell out; the rigid map between two parts that share a joint fixes its
      // centre, so the shell is the same in both parts' frames.
      const std::optional<JointId> between = jointBetween(Part(a), Part(b));
      const Joint* joint = between ? findJoint(joints, *between) : nullptr;
      const double shell = joint && joint->radius > 0.0 ? joint->radius + slack : -1.0;
      // At a wrist, the faces that meet at rest are left out as well: the
      // carpals roll on the radius, and their staircases cross as the hand
      // turns about the carpus.
      const std::vector<std::uint8_t>* face = joint && isWrist(joint->id) && !face_[std::size_t(a)].empty() ? &face_[std::size_t(a)] : nullptr;
      std::size_t n = 0;
      for (std::size_t at = 0; at < points_[std::size_t(a)].size(); ++at) {
        const Eigen::Vector3d& x = points_[std::size_t(a)][at];
        if (shell > 0.0 && (x - joint->centre).norm() <= shell) continue;
        if (face && (*face)[at]) continue;
        const Eigen::Vector3d q = g.continuousIndex(t * x);
        const std::int64_t i = std::llround(q[0]), j = std::llround(q[1]), k = std::llround(q[2]);
        n += g.contains(i, j, k) && bonePart_[std::size_t(g.index(i, j, k))] == std::uint8_t(b);
      }
      landed[std::size_t(a)][std::size_t(b)] = n;
    }
  }
  std::vector<BoneOverlap> out;
  for (int a = 1; a <= kPartCount; ++a)
    for (int b = a + 1; b <= kPartCount; ++b) {
      const std::size_t n = std::max(landed[std::size_t(a)][std::size_t(b)], landed[std::size_t(b)][std::size_t(a)]);
      if (n == 0) continue;
      const int smaller = points_[std::size_t(a)].size() <= points_[std::size_t(b)].size() ? a : b;
      out.push_back(BoneOverlap{Part(a), Part(b), n, double(n) * g.spacing.prod(), Part(smaller), double(n) / double(points_[std::size_t(smaller)].size())});
    }
  std::sort(out.begin(), out.end(), [](const BoneOverlap& x, const BoneOverlap& y) { return x.fractionOfSmaller > y.fractionOfSmaller; });
  return out;
}

std::vector<BoneOverlap> boneOverlaps(const BodyParts& parts, std::span<const Joint> joints, std::span<const Eigen::Isometry3d> motions) {
  return BoneOverlapIndex(parts).under(joints, motions);
}

}  // namespace vox::skeleton
