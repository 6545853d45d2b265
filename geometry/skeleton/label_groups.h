#pragma once
// Label groups (thesis 4.1): the limb segmentation S beside the organ
// segmentation G. S drives limb separation: the inset cage erodes at the
// interface of two groups and the transfer mesh is cut along it.
//
// Groups come from organ names ("Muscle, arms", "Humeri, upper half,
// cortical", "Skin, legs"...). The ICRP tables name most limb structures
// without a side, so left and right are decided by geometry: each connected
// piece of a limb goes to the side of the body's midline its centre lies on.

#include "geometry/label_grid.h"
#include "geometry/organ_table.h"

#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

namespace vox {

// Values of the label-group grid S built from organ names; 0 is background.
enum class LabelGroup : Label {
  Trunk = 1,
  Head = 2,
  RightArm = 3,
  LeftArm = 4,
  RightLeg = 5,
  LeftLeg = 6,
};
inline constexpr int kLabelGroupCount = 6;

// "trunk", "head", "right_arm", "left_arm", "right_leg", "left_leg".
const char* labelGroupName(LabelGroup part);
// Inverse of labelGroupName; also accepts "arm_right" style and '-' for '_'.
// Throws InputError(source, ...) naming the accepted names.
LabelGroup labelGroupFromName(const std::string& name, const std::string& source = "label group");

enum class Limb { Trunk, Head, Arm, Leg };
enum class BodySide { Unknown, Right, Left };
struct OrganLabelGroup {
  Limb limb = Limb::Trunk;
  BodySide side = BodySide::Unknown;
  bool operator==(const OrganLabelGroup&) const = default;
};

// Classifies an organ by the words of its name (case-insensitive word
// prefixes): arms ("arm", "humer", "uln", "radi", "wrist", "hand"), legs
// ("leg", "femor", "femur", "tibi", "fibul", "patell", "ankle", "foot",
// "feet"), head ("head", "cranium", "brain", "mandible", "eye", "lens",
// "teeth", "nasal", "oral", "tongue", "saliva", "pituitary", "tonsil"),
// otherwise trunk. The side is read from the words "left" / "right".
OrganLabelGroup classifyOrganName(const std::string& name);

struct LabelGroupOptions {
  // ICRP 110 grids store i from the body's right to its left
  // (shared/data/README.md), so the body's right side is at low x.
  bool rightSideAtLowX = true;
  // A limb piece (6-connected component of one limb's voxels whose names
  // carry no side) is split voxel by voxel at the midline when at least this
  // fraction of it lies on its minority side (legs touching at the thighs);
  // otherwise it goes whole to the side of its centroid.
  double straddleFraction = 0.1;
};

// The label-group grid S (same geometry as `grid`): 0 where `grid` is 0,
// else the LabelGroup of the voxel's organ. Labels missing from `organs` are
// trunk. The midline is the x centroid of the trunk voxels (of the whole
// foreground when there is no trunk).
LabelGrid labelGroupGrid(const LabelGrid& grid, const OrganTable& organs, const LabelGroupOptions& options = {});

// S without limb separation: the binary grid B, 1 on the foreground.
LabelGrid binaryGroupGrid(const LabelGrid& grid);

// Per point (grid frame, mm): the value of the nearest non-zero voxel of
// `groups` (voxel centres, Euclidean distance in mm; ties to the lowest voxel
// index), 0 when `groups` has no foreground. Pose selections by label group
// use it to tell the cage vertices of a limb from those of the trunk beside it.
std::vector<Label> nearestGroups(std::span<const Eigen::Vector3d> points, const LabelGrid& groups);

}  // namespace vox
