#pragma once
// prepareRestState: the rest state of a label grid, computed once for the
// poses to come and saved by `voxmorph prepare` (deform/prepared_state.h):
// the skeleton, then for each pose (or for none) the cage pipeline's
// pre-processing with the options deformGrid would give it
// (deformPipelineOptions), each cage, envelope and transfer mesh recorded
// once, and on request the articulated transfer mesh. `deform`, `render
// --pose` and `view` then take them (--prepared).

#include "geometry/deform/pose/pose.h"
#include "geometry/deform/prepared_state.h"
#include "geometry/organ_table.h"
#include "geometry/stage_timer.h"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace vox {

struct PrepareRequest {
  std::string input;  // label grid file
  std::optional<OrganTable> organs;
  std::string organsSource = "organ table";
  std::string parts;  // body-part grid file instead of the assignment from the bones; "" for none
  // Poses (grid frame: poseInGridFrame) whose separations and cuts the state
  // holds a cage and transfer mesh for; none: those of a pose without
  // separations (beside extraSeparations).
  std::vector<Pose> poses;
  std::vector<std::string> poseSources;  // one per pose, names it in errors
  std::vector<LimbSeparation> extraSeparations;  // beside each pose's, as deform --separate
  double dilationMm = CageOptions{}.dilationMm;
  int vertices = CageOptions{}.targetVertices;
  // Also the transfer mesh that resolves the skeleton (deform --articulated),
  // from the stored skeleton; needs an organ table that names the bones.
  bool articulated = false;
  double boneGapMm = ArticulatedMeshOptions{}.boneGapMm;  // its bone-gap cut, as deform --bone-gap
};

struct PrepareResult {
  PreparedState state;
  std::vector<StageTime> stages;  // read, skeleton, then each pose's pre-processing stages
};

// Throws what deformGrid's pre-processing throws for the same input
// (InputError for bad input, RuntimeFailure for an invalid automatic cage).
PrepareResult prepareRestState(const PrepareRequest& request);

}  // namespace vox
