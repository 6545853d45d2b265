#pragma once
// Body parts from the skeleton: the bones of the organ table (bones.h), split
// left / right, seed a geodesic nearest-bone assignment of every foreground
// voxel, measured inside the body.
//
//  1. Anatomical frame (grid frame): superior from the pelvis to the head
//     bones, anterior from the thoracic spine to the sternum, each snapped
//     to the nearest grid axis, right = anterior x superior (right-handed,
//     so a mirrored body would be told apart). Without those bones the ICRP
//     storage convention is assumed
//     (i from the body's right to its left, j front to back, k toes to
//     vertex). The mid-sagittal plane passes through the centroid of the
//     midline bones (spine, sacrum, sternum, cranium) with normal `right`.
//  2. Paired bones (humeri, forearm and hand bones, femora, lower-leg and
//     foot bones, clavicles, scapulae): each 26-connected component goes to
//     the side of the mid-sagittal plane its centroid lies on; a component
//     with at least 10 % of its voxels on the other side (two bones touching
//     across the midline) is split voxel by voxel at the plane. A side in
//     the organ name wins.
//  3. Each bone voxel seeds its part (bonePart); every other foreground
//     voxel takes the part of the bone nearest to it along paths through
//     foreground voxels (multi-source Dijkstra over the 26-neighbourhood,
//     edge lengths from the voxel spacing in mm). Paths do not run through
//     skin: a skin voxel (organ name "Skin...") is reached but passes
//     nothing on, so an arm lying against the trunk, skin on skin, keeps its
//     own tissue. Voxels only skin reaches (a skin fold) are reached through
//     the skin in a second pass, and foreground pieces without a bone
//     through the background in a third.
// Memory: the part grid (uint8), one float distance per voxel and the
// Dijkstra heap (8 bytes an entry).

#include "geometry/skeleton/label_groups.h"
#include "geometry/label_grid.h"
#include "geometry/organ_table.h"
#include "geometry/skeleton/bones.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace vox::skeleton {

// Values of the body-part grid; 0 is background.
enum class Part : std::uint8_t {
  None = 0,
  Head,
  Neck,
  Trunk,
  Pelvis,
  RightUpperArm,
  RightForearm,
  RightHand,
  LeftUpperArm,
  LeftForearm,
  LeftHand,
  RightThigh,
  RightLowerLeg,
  RightFoot,
  LeftThigh,
  LeftLowerLeg,
  LeftFoot,
};
inline constexpr int kPartCount = 16;

// "head", "neck", "trunk", "pelvis", "right_upper_arm", ..., "left_foot".
const char* partName(Part part);
// Inverse of partName ('-' accepted for '_', any case); nullopt when unknown.
std::optional<Part> partFromName(const std::string& name);
// "head, neck, trunk, ..." for messages.
std::string partNames();
// The part a bone seeds (clavicles, scapulae, ribs, sternum, thoracic and
// lumbar spine: the trunk; sacrum and pelvis: the pelvis; cervical spine:
// the neck; cranium and mandible: the head).
Part bonePart(Bone bone, Side side);
// The label group (label_groups.h) a part belongs to: head and neck -> head,
// trunk and pelvis -> trunk, a limb's parts -> that limb.
LabelGroup labelGroupOf(Part part);

// Directions of the body in the grid frame (unit vectors) and a point of the
// mid-sagittal plane.
struct AnatomicalFrame {
  Eigen::Vector3d right = -Eigen::Vector3d::UnitX();
  Eigen::Vector3d anterior = -Eigen::Vector3d::UnitY();
  Eigen::Vector3d superior = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d midpoint = Eigen::Vector3d::Zero();
  bool fromBones = false;  // superior and anterior measured (else the ICRP convention)
};

// The bone voxels of one bone on one side (linear voxel indices, increasing).
struct BoneVoxels {
  Bone bone = Bone::None;
  Side side = Side::Axial;
  std::vector<std::int64_t> voxels;  // linear indices, sorted
};

struct BodyParts {
  LabelGrid parts;  // Part per voxel (0 background), the grid's geometry
  AnatomicalFrame frame;
  std::vector<BoneVoxels> bones;  // non-empty sets, by bone then side
  // Per part (index = Part): voxels, and the bones that seeded it.
  std::array<std::int64_t, kPartCount + 1> voxels{};
  std::array<std::vector<Bone>, kPartCount + 1> seedBones;
  // Voxels reached only through skin (second pass) or through the
  // background (third pass).
  std::int64_t reachedThroughSkin = 0, reachedThroughBackground = 0;

  const BoneVoxels* find(Bone bone, Side side) const;
};

struct BodyPartOptions {
  // A paired bone's component is split voxel by voxel at the mid-sagittal
  // plane when this fraction of it lies on its minority side.
  double straddleFraction = 0.1;
  // Paths do not pass through skin (organ names starting with "skin").
  bool skinBlocksPaths = true;
  // The frame's directions are the grid axes nearest the measured ones:
  // phantoms are stored along the body, and centroids of bones are off the
  // body's axes by a few degrees (the ICRP adult male's sternum-to-spine
  // direction by 4), which would tilt every joint angle.
  bool snapToGridAxes = true;
};

// Bones and anatomical frame of `grid` without the assignment (cheap).
// Throws InputError(organsSource, ...) when the table names no bone, and
// InputError(gridSource, ...) when the grid holds no voxel of them.
BodyParts findBones(const LabelGrid& grid, const OrganTable& organs, const std::string& gridSource,
                    const std::string& organsSource, const BodyPartOptions& options = {});

// The body-part grid of `grid` (geodesic nearest bone, above).
BodyParts bodyParts(const LabelGrid& grid, const OrganTable& organs, const std::string& gridSource,
                    const std::string& organsSource, const BodyPartOptions& options = {});

// A user-supplied body-part grid (a corrected `voxmorph parts` output) in
// place of the assignment: other dims or voxel size than `grid`, or a value
// above kPartCount, is an InputError(partsSource, ...). The bones and the
// frame still come from the organ table (the joints need them).
BodyParts userBodyParts(const LabelGrid& grid, const OrganTable& organs, LabelGrid parts, const std::string& gridSource,
                        const std::string& organsSource, const std::string& partsSource, const BodyPartOptions& options = {});

// The nearest-bone assignment by straight-line distance (no paths): what the
// geodesic assignment is compared with (tests, reports).
LabelGrid euclideanBodyParts(const LabelGrid& grid, const BodyParts& bones);

// The label-group grid (label_groups.h values) of a body-part grid.
LabelGrid labelGroupsOfParts(const LabelGrid& parts);

// 26-connected components of each part's voxels (index = Part; 0 for absent
// parts).
std::array<int, kPartCount + 1> partComponents(const LabelGrid& parts);

// Components of `marked` voxels (26-connected; `marked` holds a class per
// voxel, 0 for none, and a component keeps to one class): calls
// fn(class, voxels) per component and clears what it visits.
void forEachComponent(const GridGeometry& g, std::vector<std::uint8_t>& marked,
                      const std::function<void(std::uint8_t, const std::vector<std::int64_t>&)>& fn);

}  // namespace vox::skeleton
