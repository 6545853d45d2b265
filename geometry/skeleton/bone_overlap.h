#pragma once
// Bones pressed through each other by a pose: every bone voxel of a part,
// moved by its part's rigid motion, is looked up in the bones of every other
// part moved by theirs. Rigid bones cannot share space, and no deformation of
// the tissue between them can make room, so a pose whose bones overlap is
// physically wrong.
//
// At a ball joint (shoulder, hip: a joint with a fitted sphere) the head
// turns in its socket, and at the grid's resolution the two staircased
// surfaces cross where they meet: voxels of the parent and the child within
// the sphere's radius plus one voxel (the largest spacing) of the joint's
// centre are the articular surfaces and are not counted between those two
// parts. At a wrist (its sphere about the carpus' centre up to the forearm
// bones) the voxels of either side within a voxel of the other
// side's bone at rest are not counted either: the carpals' face rolls on the
// radius' across the wrist's width, beyond the sphere. Everywhere else, and
// between parts that do not share a joint, every overlapping voxel counts.

#include "geometry/skeleton/body_parts.h"
#include "geometry/skeleton/joints.h"

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace vox::skeleton {

struct BoneOverlap {
  Part first = Part::None, second = Part::None;  // first < second
  // The larger of the two counts: first's bone voxels landing in second's
  // bones, and second's in first's.
  std::size_t voxels = 0;
  double volumeMm3 = 0.0;
  Part smaller = Part::None;  // the one of the two with fewer bone voxels
  double fractionOfSmaller = 0.0;  // voxels over smaller's bone voxels
};

// The bones of a skeleton's parts, indexed once, so that each pose's
// overlaps cost only the moved bone voxels' lookups (the viewer asks at
// every change of a joint's angle).
class BoneOverlapIndex {
public:
  explicit BoneOverlapIndex(const BodyParts& parts);
  // The bones' overlaps under `motions` (indexed by Part, grid frame mm; the
  // identity for a part at rest), one entry per pair of parts that overlap,
  // the largest fraction first. Parts with the same motion are not compared
  // (their bones are apart at rest, as every voxel has one part).
  std::vector<BoneOverlap> under(std::span<const Joint> joints, std::span<const Eigen::Isometry3d> motions) const;

private:
  GridGeometry grid_;
  std::array<std::vector<Eigen::Vector3d>, kPartCount + 1> points_;  // bone voxel centres per part
  std::array<Eigen::AlignedBox3d, kPartCount + 1> boxes_;
  std::vector<std::uint8_t> bonePart_;  // per voxel: the part whose bone it is (0: none)
  // Per point of a wrist's two parts: 1 where it lies within a voxel of the
  // other part's bone at rest (the articular faces); empty for other parts.
  std::array<std::vector<std::uint8_t>, kPartCount + 1> face_;
};

// BoneOverlapIndex(parts).under(joints, motions).
std::vector<BoneOverlap> boneOverlaps(const BodyParts& parts, std::span<const Joint> joints, std::span<const Eigen::Isometry3d> motions);

// The parts that move with `part` (it and every part below it in the tree).
std::vector<Part> partSubtree(Part part);

}  // namespace vox::skeleton
