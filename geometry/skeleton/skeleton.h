#pragma once
// The skeleton of a label grid: its body parts (body_parts.h) and joints
// (joints.h), from the bones its organ table names, and the report
// `voxmorph parts` writes.

#include "geometry/label_grid.h"
#include "geometry/organ_table.h"
#include "geometry/skeleton/body_parts.h"
#include "geometry/skeleton/joints.h"

#include <optional>
#include <string>
#include <vector>

namespace vox::skeleton {

struct Skeleton {
  BodyParts parts;
  std::vector<Joint> joints;  // the joints the bones allow, in JointId order
  double seconds = 0.0;       // wall time of buildSkeleton

  const Joint* joint(JointId id) const;
  // The joint whose centre is nearest p (the first of equals; null without
  // joints).
  const Joint* nearestJoint(const Eigen::Vector3d& p) const;
};

struct SkeletonSources {
  std::string grid = "grid", organs = "organ table", parts = "body parts";  // names in errors
};

// Body parts (the geodesic assignment, or `userParts` when given: checked
// against `grid` by userBodyParts) and joints. Throws InputError naming the
// organ table when it names no bones, the grid when it has none of them,
// the parts grid for other dims or values.
Skeleton buildSkeleton(const LabelGrid& grid, const OrganTable& organs, const SkeletonSources& sources,
                       std::optional<LabelGrid> userParts = std::nullopt, const BodyPartOptions& options = {});

// The report of `voxmorph parts`: per part its id, name, voxels, volume (mL)
// and seed bones; per joint its parts, centre, axes (world frame, mm: the
// grid's direction applied, world_frame.h), radius and methods; the
// anatomical frame (world directions).
std::string skeletonReportJson(const Skeleton& skeleton, const GridGeometry& grid, const std::string& input, const std::string& output);
// The same as a table a person reads.
std::string skeletonSummary(const Skeleton& skeleton, const GridGeometry& grid);

}  // namespace vox::skeleton
