#include "geometry/deform/run/prepare_run.h"

#include "geometry/deform/pipeline.h"
#include "geometry/deform/run/deform_run.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/raster/out_of_core.h"
#include "geometry/skeleton/bones.h"
#include "geometry/skeleton/skeleton.h"

#include <algorithm>
#include <memory>

namespace vox {

PrepareResult prepareRestState(const PrepareRequest& o) {
  PrepareResult result;
  if (o.poses.size() != o.poseSources.size()) throw RuntimeFailure("prepareRestState: one source per pose");
  StageTimer readTimer("read source");
  const LabelGrid grid = readGrid(o.input);
  // The working grid as deformGrid makes it in core.
  const int factor = downsampleFactor(grid.geometry(), kDefaultWorkingVoxels);
  LabelGrid downsampled;
  if (factor > 1) {
    downsampled = downsampleLabels(grid, factor);
  }
  const LabelGrid& working = factor > 1 ? downsampled : grid;
  result.stages.push_back(readTimer.stop());

  auto state = std::make_shared<PreparedState>();
  state->inputs = preparedInputs(o.input, o.organs, o.organsSource, o.parts, factor, working.dims());
  state->recording = true;
  std::vector<Pose> poses = o.poses;
  std::vector<std::string> sources = o.poseSources;
  if (poses.empty()) {
    poses.emplace_back();
    sources.emplace_back("prepare");
  }
  // The skeleton wherever deform would build one or the body parts: an
  // organ table that names bones, or a parts grid. Unless the first pose
  // compiles against it (joints, selections by body part) or a parts grid
  // is given, the first pipeline builds it while it builds its transfer mesh.
  const bool withSkeleton = !o.parts.empty() || (o.organs && skeleton::namesBones(*o.organs));
  const bool skeletonMeanwhile = withSkeleton && o.parts.empty() && poses[0].joints.empty() && !usesBodyParts(poses[0]);
  if (!skeletonMeanwhile) {
    StageTimer timer("skeleton");
    if (withSkeleton) {
      requireOrganTable(o.organs.has_value(), OrganTableNeed::Bones, "--parts");
      std::optional<LabelGrid> userParts;
      if (!o.parts.empty()) {
        LabelGrid parts = readGrid(o.parts);
        if (parts.dims() != grid.dims()) throw InputError(o.parts, "has other dims than the grid " + o.input);
        if (factor > 1) parts = downsampleLabels(parts, factor);
        userParts = std::move(parts);
      }
      try {
        state->skeleton = skeleton::buildSkeleton(working, *o.organs, {o.input, o.organsSource, o.parts}, std::move(userParts));
      } catch (const InputError&) {
        // A table that names bones the grid does not hold: deform builds no
        // body parts either (and refuses a pose that needs them).
        if (!o.parts.empty()) throw;
      }
    }
    result.stages.push_back(timer.stop());
  }
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (poses[i].articulated) continue;  // no cage: the articulated transfer mesh below
    DeformGridRequest r;
    r.input = o.input;
    r.pose = poses[i];
    r.poseSource = sources[i];
    r.organs = o.organs;
    r.organsSource = o.organsSource;
    r.parts = o.parts;
    r.extraSeparations = o.extraSeparations;
    r.dilationMm = o.dilationMm;
    r.vertices = o.vertices;
    PipelineOptions options = deformPipelineOptions(r, working, factor, state.get());
    // The rest state only: no handles, no embedding.
    options.pose.reset();
    options.prepared = state;
    if (i == 0 && skeletonMeanwhile)
      options.bodyPartsMeanwhile = [&]() -> std::optional<LabelGrid> {
        try {
          state->skeleton = skeleton::buildSkeleton(working, *o.organs, {o.input, o.organsSource, o.parts});
        } catch (const InputError&) {
          return std::nullopt;  // as above: no body parts
        }
        return state->skeleton->parts.parts;
      };
    const DeformationPipeline pipeline(working, options);
    for (StageTime t : pipeline.stats().stages) {
      if (poses.size() > 1) t.name = sources[i] + ": " + t.name;
      result.stages.push_back(std::move(t));
    }
  }
  if (o.articulated || std::any_of(poses.begin(), poses.end(), [](const Pose& p) { return p.articulated; })) {
    StageTimer timer("articulated transfer mesh");
    if (!state->skeleton) throw InputError("--articulated", "needs an organ table that names the bones the grid holds (or a --parts grid)");
    ArticulatedMeshOptions options;
    options.boneGapMm = o.boneGapMm;
    state->articulatedMeshes.push_back({articulatedMeshOptionsKey(options), buildArticulatedMesh(working, *o.organs, *state->skeleton, options)});
    result.stages.push_back(timer.stop());
  }
  state->recording = false;
  result.state = std::move(*state);
  return result;
}

}  // namespace vox
