#pragma once
// The VoxMorph pipeline (thesis 3.2 and 4.2) as library calls, shared by
// `voxmorph deform`, `voxmorph render --pose` and the viewer:
//
//   DeformationPipeline pipeline(workingGrid, options);  // pre-process
//   pipeline.setPose(pose, "pose.json");                  // handles, factorizations
//   pipeline.deform();                                    // one frame
//   pipeline.refine(refinementOptions, interpolation);    // post-process, eq. 4.5-4.6
//   ... rasterize pipeline.transferMesh() / deformedTransferMesh() (rasterize.h,
//       gpu/kernels/rasterize.h, out_of_core.h), or ray-cast them.
//
// Pre-processing, on the working grid G (the source, or its block-downsampled
// copy for grids larger than the working budget, see kDefaultWorkingVoxels):
//  - label groups: S from the organ names (label_groups.h), or from the body
//    parts when given (a joint pose), when separations are requested, else
//    the binary grid B;
//  - cage: automatic from S (inset where separations are requested), or the
//    caller's (validated); foreground voxels outside it are counted;
//  - envelope of B (optional: only the interactive display needs it);
//  - sizing field F: a constant fraction of G's diagonal;
//  - transfer mesh under F: from B, or, with separations, from S reduced to
//    the separated groups (every other group merged into one) and cut
//    between each separated pair inside its region. It does not depend on
//    the cage: it is built on a thread of its own meanwhile (CGAL's mesher
//    holds one core; the cage's parallel loops take the others), with the
//    same bytes as one built after it;
//  - the frame deformer's precomputation (Green coordinates, ARAP and
//    propagation factorizations) once the pose gives the handles. With
//    separations, the TM vertices on a cut, and those of a separated group
//    that the inset cage would move with the other group (nearest cage
//    vertex of that group, small inside islands, or "torn": most of their
//    edges stretched past e in the full pose), are placed by the
//    propagation from their own group's tets.
//
// An identity pose gives the rest positions bit for bit (FrameDeformer), so
// rasterizing it reproduces the source voxel for voxel wherever the TM
// covers it (countUncoveredVoxels is reported).

#include "geometry/deform/solve/adaptive_refinement.h"
#include "geometry/deform/cage/cage_builder.h"
#include "geometry/deform/cage/envelope.h"
#include "geometry/deform/solve/frame_deformer.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/deform/solve/rigid_bones.h"
#include "geometry/raster/rasterize.h"
#include "geometry/deform/transfer_mesh.h"
#include "geometry/body_projection.h"
#include "geometry/label_grid.h"
#include "geometry/organ_table.h"
#include "geometry/scalar_grid.h"
#include "geometry/stage_timer.h"
#include "geometry/tet_mesh.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace vox {

class PreparedState;

struct PipelineOptions {
  // Organ table of the grid: label groups for limb separation. Required when
  // cage.separations is not empty (unless bodyParts is given).
  std::optional<OrganTable> organs;
  // Body parts of the grid (skeleton/body_parts.h, same dims): selections by
  // body part take the cage vertices nearest each part, and the label groups
  // (separations, selections by group) are those the parts form
  // (skeleton::labelGroupsOfParts) instead of those the organ names give.
  std::optional<LabelGrid> bodyParts;
  // With bodyParts and an organ table: false takes the label groups from the
  // organ names all the same (a joint pose's "joint_options": {"groups": "organs"}).
  bool groupsFromParts = true;
  // Instead of bodyParts, with an organ table and groupsFromParts false: the
  // body parts computed while the transfer mesh is built (the label groups,
  // and so the mesh, do not depend on them). Called once on the
  // constructing thread once the mesh's thread has started, timed as the
  // "skeleton" stage; what it returns takes the place of bodyParts.
  std::function<std::optional<LabelGrid>()> bodyPartsMeanwhile;
  // With bodyParts and an organ table that names bones: the TM tets holding
  // each part's bone voxels move rigidly (rigid_bones.h). Off by default: on
  // the coarse TM the tets between two bones that turn against each other
  // fold (docs/POSES.md, rigid bones). The bones' rigidity is measured
  // (rigidBones()) either way.
  bool rigidBones = false;
  int rigidJointRings = 2;  // tet rings left free around the vertices between two parts' bones (rigidBoneGroups)
  // Per body part (index = skeleton::Part; empty: none): the rigid motion its
  // bones take (a joint pose's forward kinematics, deform/pose/joint_pose.h),
  // applied by the frame's fraction. Without it each part's bones take the
  // rigid fit to where the cage puts them.
  std::vector<PoseTransform> partMotions;
  // Automatic cage; its separations (groups are LabelGroup values) also cut
  // the transfer mesh.
  CageOptions cage;
  // Where the transfer mesh is cut (cutTransferMesh); empty: the cage's
  // separations. A joint that the cage separates into two components (so
  // that each part's Green coordinates ignore the other part's motion) must
  // stay connected in the TM, where the propagation blends the two motions.
  std::optional<std::vector<LimbSeparation>> cuts;
  // A cage to use instead of the automatic one (already validated, e.g. by
  // readCage); it must enclose or meet the foreground as the caller intends.
  std::optional<TriMesh> userCage;
  bool envelope = true;
  EnvelopeOptions envelopeOptions;
  // The transfer mesh built on a thread of its own while the body parts
  // (bodyPartsMeanwhile), the cage and the envelope are built: the same
  // bytes, sooner on two cores or more, but both stages' grids held at once.
  // False: one after the other, for a run under a memory limit, whose
  // working grid is sized by kPreprocessBytesPerVoxel.
  bool concurrentTransferMesh = true;
  double sizingFraction = 0.05;  // initial F: this fraction of the working grid's diagonal
  TransferMeshOptions transferMesh;
  FrameDeformerOptions frame;
  // A pose to set at the end of the pre-processing (setPose); its selections
  // are checked against the cage as soon as the cage exists, so a pose that
  // selects nothing fails before the transfer mesh is built.
  std::optional<Pose> pose;
  std::string poseSource = "pose";
  // A saved rest state (prepared_state.h, `voxmorph prepare`): the cage,
  // envelope and transfer mesh are taken from it where it holds them for
  // this grid's label groups and these options (the same bytes the
  // pipeline would build), and a piece it lacks is refused (InputError
  // naming the file and what differs). With prepared->recording the
  // pipeline builds what it lacks and adds it instead.
  std::shared_ptr<PreparedState> prepared;
};

// Options that apply `pose` as `voxmorph deform` does: its separations for
// the cage and, within their cut regions, for the transfer mesh; its
// selections set once the cage exists (source names the pose in errors).
// `organs` names the label groups (required by separations and selections
// by group).
PipelineOptions poseOptions(const Pose& pose, const std::string& source, std::optional<OrganTable> organs);

// Sizes and checks of the pre-processing, for reports.
struct PipelineStats {
  bool automaticCage = true;
  CageReport cage;                        // of the automatic cage (check only, for a user cage)
  std::int64_t foregroundOutsideCage = 0;  // working-grid foreground voxels outside the cage
  std::int64_t uncoveredVoxels = 0;        // working-grid foreground voxels in no TM tet
  std::vector<CutReport> cuts;             // one per separation, of the current TM
  // Pre-processing, then the latest "embedding" (setPose), "deformation"
  // (deform) and "refinement" (refine). The stages follow one another on
  // the constructing thread, so their times add up to the whole; with
  // concurrentTransferMesh the transfer mesh is built meanwhile on its own
  // thread, its stage is the wait for it once the body parts, cage and
  // envelope are done, and their CPU seconds (the process's) count its work
  // in the meantime.
  std::vector<StageTime> stages;
};

class DeformationPipeline {
public:
  // Pre-processing of `grid` (copied). Throws InputError for a grid without
  // foreground, separations without an organ table, a separation naming a
  // group with no voxels; RuntimeFailure for an automatic cage that is not a
  // valid cage (self-intersecting, non-manifold).
  DeformationPipeline(const LabelGrid& grid, const PipelineOptions& options = {});

  // The pose's handles on the cage (selectHandles: InputError(source, ...)
  // for a selection that selects nothing) and the frame deformer's
  // precomputation. A connected part of the cage that no selection touches
  // (an inset cage can split off small pieces) is left out of the
  // deformation: ARAP has nothing to place it by, and the TM vertices inside
  // it are placed by the propagation like the other outliers. Positions are
  // reset to the rest pose.
  void setPose(const Pose& pose, const std::string& source);
  // One frame: the pose applied by `fraction` in [0, 1].
  void deform(double fraction = 1.0);
  // One frame from explicit handle targets (#handles by 3, in handles()
  // order), the interactive entry point: ARAP, Green coordinates and the
  // propagation run on what setPose precomputed; nothing is refactorized.
  // Returns the deformed TM (deformedTransferMesh) and envelope.
  void deformTo(const Eigen::MatrixX3d& handleTargets, int arapIterations);
  // Post-process: refines the TM under the current pose (eq. 4.5-4.6,
  // adaptive_refinement.h): the tets it splits gain midpoints placed by the
  // frame's Green coordinates, the rest of the TM keeps its embedding. The
  // deformer keeps its precomputation of the unrefined TM until the next
  // setPose, deform or deformTo, which embed the refined TM whole.
  RefinementResult refine(const RefinementOptions& options, const VertexFieldInterpolation& interpolate);

  const LabelGrid& groups() const { return groups_; }   // S (or B) on the working grid
  // The cage as built (or given), and the cage the deformation uses: its
  // parts that hold a handle (setPose). Handles index the latter.
  const TriMesh& builtCage() const { return builtCage_; }
  const TriMesh& cage() const { return cage_; }
  const TriMesh& envelope() const { return envelope_; }
  const ScalarGrid& sizingField() const { return sizing_; }
  const TetMesh& transferMesh() const { return transferMesh_; }  // rest TM (cut)
  const std::vector<Eigen::Vector3d>& deformedTransferMesh() const {
    return refined_ ? refinedPositions_ : deformer_.transferMeshPositions();
  }
  const std::vector<Eigen::Vector3d>& deformedCage() const { return deformer_.cagePositions(); }
  const std::vector<Eigen::Vector3d>& deformedEnvelope() const { return deformedEnvelope_; }
  // #TM vertices: 1 inside the cage (Green coordinates), 0 outside (propagation).
  const std::vector<std::uint8_t>& transferMeshInside() const { return refined_ ? refinedInside_ : deformer_.transferMeshInside(); }
  // The frame deformer (after refine: of the TM before the refinement).
  const FrameDeformer& deformer() const { return deformer_; }
  // Per cage() vertex: its vertex in builtCage().
  const std::vector<std::int32_t>& cageSource() const { return cageSource_; }
  // Per builtCage() vertex: the label group nearest it (empty without groups).
  const std::vector<Label>& cageGroups() const { return cageGroups_; }
  // Per builtCage() vertex: the body part nearest it (empty without body parts).
  const std::vector<Label>& cageBodyParts() const { return cageBodyParts_; }
  // The rigid bone groups of the current TM (empty without body parts and
  // bones); the deformer holds them rigid with options.rigidBones.
  const RigidBoneGroups& rigidBones() const { return rigidBones_; }
  // The body-part grid on the working grid (options.bodyParts).
  const std::optional<LabelGrid>& bodyParts() const { return options_.bodyParts; }
  const Pose& pose() const { return pose_; }
  const PoseHandles& handles() const { return handles_; }
  // Vertices of the built cage left out because their part has no handle.
  std::size_t droppedCageVertices() const { return builtCage_.vertexCount() - cage_.vertexCount(); }
  const PipelineStats& stats() const { return stats_; }

private:
  void precomputeFrame(bool withEnvelope);
  // One frame of the deformer at `fraction` of the pose (handles and rigid
  // bone motions).
  void updateFrame(double fraction);
  std::vector<std::uint8_t> acrossSeparation() const;
  std::size_t markTornVertices(std::vector<std::uint8_t>& propagate) const;
  void recordStage(StageTime time);
  // 1 per TM vertex that the frame's Green coordinates place (inside the
  // cage, not propagated, neither a rigid bone's nor in its band).
  std::vector<std::uint8_t> placedByGreenCoordinates() const;
  // The refinement's subject (adaptive_refinement.h): places a round's
  // midpoints in the current frame, and takes the TM the refinement keeps.
  void placeMidpoints(const TetMesh& refined, std::span<const TetEdge> parents, std::vector<Eigen::Vector3d>& deformed,
                      std::vector<std::uint8_t>& placed) const;
  void adoptRefinedMesh(TetMesh refined, std::vector<Eigen::Vector3d> deformed, std::vector<std::uint8_t> placed);
  // Embeds the refined TM whole when refine() left the deformer behind it.
  void embedRefinedMesh();

  PipelineOptions options_;
  std::vector<Label> cageGroups_;          // per built-cage vertex: nearest label group (selections by group)
  std::vector<Label> cageBodyParts_;       // per built-cage vertex: nearest body part (selections by body part)
  std::vector<std::int32_t> cageSource_;  // per cage_ vertex: its built-cage vertex
  LabelGrid boneKeys_;  // rigid_bones.h (empty without rigid bones)
  RigidBoneGroups rigidBones_;
  LabelGrid groups_, meshGroups_;  // meshGroups_: S reduced to the separated groups (empty without separations)
  std::string groupsDigest_, groupsWords_;  // groups_'s digest and how it was made (prepared state keys and messages)
  TriMesh builtCage_, cage_, envelope_;
  ScalarGrid sizing_;
  TetMesh transferMesh_;
  FrameDeformer deformer_;
  Pose pose_;
  PoseHandles handles_;
  double fraction_ = 0.0;
  bool posed_ = false;
  std::vector<Eigen::Vector3d> deformedEnvelope_;
  // After refine(): the refined TM's deformed positions and inside flags
  // (the deformer's describe the TM before it).
  bool refined_ = false;
  std::vector<Eigen::Vector3d> refinedPositions_;
  std::vector<std::uint8_t> refinedInside_;
  PipelineStats stats_;
};

// A description of the first fault of a surface that is not a valid cage
// ("12 boundary edges", "3 self-intersecting face pairs"...).
std::string cageFault(const SurfaceCheck& check);

// Working grid. The pre-processing's memory and time grow with the voxels it
// samples (distance transforms, the mesher's domain), not with the TM's
// size, so a source above the working budget runs it on a block-downsampled
// copy (out_of_core.h: downsampleLabels, downsampleFactor -- the smallest
// factor that brings the copy under the budget). In core the budget is
// kDefaultWorkingVoxels (the ICRP phantoms, 7 and 14 M voxels, run at full
// resolution); under a memory limit it is the limit's share for the
// pre-processing divided by kPreprocessBytesPerVoxel.
inline constexpr std::int64_t kDefaultWorkingVoxels = std::int64_t(1) << 24;
// Peak bytes the pre-processing holds per working-grid voxel (padded
// distance transform with nearest-seed indices, label, sizing and error
// grids), measured on the ICRP phantoms.
inline constexpr std::int64_t kPreprocessBytesPerVoxel = 48;

}  // namespace vox
