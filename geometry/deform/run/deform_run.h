#pragma once
// deformGrid: re-poses a label grid file and writes the posed full-resolution
// grid (thesis chapters 3 and 4), as `voxmorph deform` and the viewer's export
// both run it, on the engines the caller chooses (raster/raster_engines.h:
// the GPU kernels of gpu/raster_engines.h, or the CPU references):
//   a pose with joints compiled against the skeleton (deform/pose/joint_pose.h) ->
//   pre-process (label groups, cage, transfer mesh, embedding; not the
//   envelope, which only the interactive display draws) ->
//   deformation (ARAP -> Green coordinates -> propagation) ->
//   deformation-adaptive refinement (eq. 4.5-4.6, the marked tets bisected;
//   the engines' field interpolation) -> rasterization of G' (the engines' rasterizer), streamed
//   slab by slab to the output file (held in memory and corrected with
//   preserveVolumes) -> report.
// The memory budgets of the out-of-core path and the report's assembly live
// here, not in the callers. With maxMemoryMb the source is read once (downsampled for the
// pipeline, spooled to an unlinked raw temporary when compressed) and G' is
// rasterized from source windows under the budget.

#include "geometry/deform/articulated_mesh.h"
#include "geometry/deform/articulated_pose.h"
#include "geometry/deform/solve/adaptive_refinement.h"
#include "geometry/deform/report/deformation_report.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/organ_table.h"
#include "geometry/raster/raster_engines.h"
#include "geometry/provenance.h"
#include "geometry/tri_mesh.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace vox {

struct PipelineOptions;
class PreparedState;

struct DeformGridRequest {
  std::string input;          // label grid file (with inputGrid: only its name in errors and the report)
  std::string output;         // posed grid file (any grid format in core); "" with posedGrid: none
  // The label grid in memory instead of the file `input` (the Python
  // module's Grid), read in place: the rasterization, the statistics and the
  // volume correction read its labels where they are; the pipeline reads it
  // as it is, or, when the grid borrows its labels, a working grid of its
  // own (the downsampled grid, or a copy when no larger than the working
  // grid). Must outlive deformGrid. Not with `prepared`, which is checked
  // against a file.
  const LabelGrid* inputGrid = nullptr;
  // Receives G' in memory once it is committed, beside its file or, with
  // `output` "", instead of it.
  LabelGrid* posedGrid = nullptr;
  Pose pose;                        // in the grid frame (poseInGridFrame)
  std::string poseSource = "pose";  // names the pose in errors and the report
  std::optional<OrganTable> organs;
  std::string organsSource = "organ table";      // names the organ table in errors
  // A body-part grid (skeleton/body_parts.h values, the input's dims) to use
  // instead of the assignment from the bones; "" for none.
  std::string parts;
  std::vector<LimbSeparation> extraSeparations;  // beside the pose's own
  std::optional<TriMesh> cage;                   // instead of the automatic cage (grid frame)
  double dilationMm = CageOptions{}.dilationMm;
  int vertices = CageOptions{}.targetVertices;
  int samples = 1;
  std::int64_t maxMemoryMb = 0;  // 0: in core
  bool preserveVolumes = false;
  // What --preserve-volumes brings each label to: the volume the deformation
  // gives it (Jacobians of the transfer mesh), or its rest volume (the
  // source's voxels), so organ masses are kept whatever the deformation does.
  enum class VolumeTarget { Deformed, Rest } volumeTarget = VolumeTarget::Deformed;
  // With preserveVolumes and an organ table that names skin: the tissue the
  // pose bared relabelled skin (skin_cover.h), after the correction.
  bool coverSkin = true;
  bool rigidBones = false;   // with body parts: bones held rigid (rigid_bones.h)
  // A joint pose on the transfer mesh that resolves the skeleton
  // (articulated_mesh.h, articulated_pose.h) instead of the cage pipeline:
  // bones on their parts' motions, sliding shoulders, hips, elbows and knees,
  // the soft tissue by the injective solve; no cage, no refinement. A pose
  // the solve cannot reach without inverting a tet is refused (unless force).
  // A pose file's "articulated": true asks for it as well (posesArticulated).
  bool articulated = false;
  // With articulated: the bone-gap cuts (ArticulatedMeshOptions
  // boneGapMm, mm; 0: none). Part of the prepared mesh's key.
  double boneGapMm = ArticulatedMeshOptions{}.boneGapMm;
  bool allowGrowth = false;  // accept a posed grid of more than 8x the source's voxels (posed_extent.h)
  // Physically wrong results are refused with nothing written: a bone whose
  // volume (through the transfer mesh, report.bones) changes by more than
  // maxBoneChangePercent, checked before the rasterization, or a whole body
  // (G''s foreground) by more than maxBodyChangePercent, checked before G'
  // and the extra outputs are committed; a joint pose whose bones pass
  // through each other by more than maxBoneOverlapPercent of the smaller
  // part's bones (skeleton::bonesThroughEachOther), checked before the
  // transfer mesh is built; two parts' tissue pressed through each other
  // (report.collisions) over more than maxTissueOverlapPercent of the body,
  // checked before the rasterization. `force` writes them anyway, with a
  // warning and "forced" in the report.
  double maxBodyChangePercent = 2.0;
  double maxBoneChangePercent = 10.0;
  double maxBoneOverlapPercent = skeleton::kMaxBoneOverlapPercent;
  double maxTissueOverlapPercent = 0.5;
  bool force = false;
  std::int64_t maxTets = RefinementOptions{}.maxTets;
  int refineIterations = RefinementOptions{}.maxIterations;
  std::string posedCage, posedMesh;  // optional extra outputs, written in the world frame
  // With body parts: the collision mask (collisions.h, 1 where two parts'
  // tissue overlaps) on the posed grid's lattice at the working grid's
  // spacing; "" for none.
  std::string collisionMask;
  // A rest state saved by `voxmorph prepare` (deform/prepared_state.h) to
  // take the skeleton, cage, envelope and transfer mesh from; "" for none.
  // One made from another grid, organ table or parts grid, another working
  // grid, or without this pose's separations and cage options is refused
  // (InputError naming the file and what differs). In core only.
  std::string prepared;
  // Copied into the report: the caller's command line and input digests.
  Provenance provenance;
  // Warnings (foreground outside the cage).
  std::function<void(const std::string&)> warn;
};

// Checks what can be checked cheaply (options that exclude each other, output
// extensions, separations and label groups without an organ table, joints
// without one or with one that names no bones, a parts grid whose dims are
// not the grid's, from the headers): throws InputError naming the file or
// option (UsageError for options that exclude each other).
void checkDeformGridRequest(const DeformGridRequest& request);

// Runs the whole deformation on `engines` and writes request.output (and the
// optional outputs); the returned report has every field of the JSON report.
DeformationReport deformGrid(const DeformGridRequest& request, RasterEngines& engines);

// The options deformGrid gives the cage pipeline for `request` on `working`
// (the source block-downsampled by `factor`): the pose compiled against the
// skeleton (prepared->skeleton when it holds one, else built), the body
// parts of a grid whose organ table names bones (prepared->skeleton's, else
// computed by the pipeline while it builds the transfer mesh:
// bodyPartsMeanwhile, which holds `working` by reference), the cage options
// and the extra separations. prepare_run.h prepares with the same options. With
// `bonesFault`, a joint pose's bones pressed through each other are checked
// against the skeleton the options were compiled with
// (skeleton::bonesThroughEachOther, request.maxBoneOverlapPercent): the
// fault, or nullopt.
PipelineOptions deformPipelineOptions(const DeformGridRequest& request, const LabelGrid& working, int factor,
                                      const PreparedState* prepared = nullptr,
                                      std::optional<std::string>* bonesFault = nullptr);

// Whether the run poses on the articulated transfer mesh: --articulated, or
// the pose file asks for it.
inline bool posesArticulated(const DeformGridRequest& request) { return request.articulated || request.pose.articulated; }

// A joint pose on the articulated transfer mesh, every step of the way kept:
// what deformGrid runs with `articulated` before its checks, the collisions
// and the rasterization, for a caller that shows the posed mesh rather than
// writing a grid (`voxmorph render --articulated`). Nothing is refused here:
// the report tells what the steps did.
struct ArticulatedStepsRequest {
  const LabelGrid& grid;
  const OrganTable& organs;
  Pose pose;  // in the grid frame, joints only
  std::string gridSource = "grid", organsSource = "organ table", poseSource = "pose";
  double boneGapMm = ArticulatedMeshOptions{}.boneGapMm;
  const PreparedState* prepared = nullptr;  // its skeleton and articulated mesh, when it holds them
  std::function<void(const std::string&)> warn;
  std::function<void(int step)> onStep;  // after each step (1-based), on the solving thread
};

struct ArticulatedSteps {
  TetMesh rest;  // the articulated transfer mesh at rest (grid frame)
  // Where each step left every vertex (ArticulatedPoseOptions::onStep): the
  // approach's steps, then the last one with the bones on their motions,
  // untangled and in contact; the last is the posed mesh deformGrid rasterizes.
  std::vector<std::vector<Eigen::Vector3d>> steps;
  ArticulatedPoseReport report;
};

ArticulatedSteps poseArticulatedSteps(const ArticulatedStepsRequest& request);

// The steps poseArticulatedSteps gives `pose` (the approach's and the last).
int articulatedStepCount(const Pose& pose);

}  // namespace vox
