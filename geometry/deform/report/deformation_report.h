#pragma once
// What `voxmorph deform --report` writes: stage times, the sizes of the cage,
// envelope and transfer mesh (TM) per refinement iteration, outliers (TM
// vertices and foreground voxels outside the cage), per-label voxel counts
// with volume and mass change, the whole body's change, the distortion
// histograms of the thesis' Figure 3.19 and the edge-length distortion of
// the propagated (outside) TM vertices against the inside ones, the body's
// projected areas and height at rest and posed (body_projection.h), and the
// run's provenance (provenance.h).

#include "geometry/deform/solve/adaptive_refinement.h"
#include "geometry/deform/report/collisions.h"
#include "geometry/deform/solve/deformation_metrics.h"
#include "geometry/deform/solve/label_volumes.h"
#include "geometry/deform/solve/skin_cover.h"
#include "geometry/deform/pipeline.h"
#include "geometry/body_projection.h"
#include "geometry/label_grid.h"
#include "geometry/organ_table.h"
#include "geometry/provenance.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace vox {

// Organs under this many voxels are exempt from the mass bound (a voxel or
// two of resampling is already a large fraction of them): listed apart.
inline constexpr std::uint64_t kSmallOrganVoxels = 1000;

struct LabelChange {
  Label label = 0;
  std::string name;                // organ name, or "" without a table
  bool unnamed = false;            // a table was given but does not name the label
  std::uint64_t before = 0, after = 0;
  double volumeChangePercent = 0;  // also the mass change: one density per label
  double massBeforeGrams = 0, massAfterGrams = 0;  // 0 without a table
  // With --preserve-volumes: the volume the deformation gives the label, in
  // output voxels (label_volumes.h), the count the correction aims at; else < 0.
  double deformedVolumeVoxels = -1;
};

struct WholeBodyChange {
  std::uint64_t before = 0, after = 0;  // foreground voxels
  double volumeChangePercent = 0;
  double massBeforeGrams = 0, massAfterGrams = 0, massChangePercent = 0;  // with a table
};

// Per label present before or after (label 0 excluded). counts: indexed by
// label (LabelStats::counts); the two may differ in length.
std::vector<LabelChange> labelChanges(std::span<const std::uint64_t> before, std::span<const std::uint64_t> after,
                                      double voxelVolumeMm3, const OrganTable* organs);
WholeBodyChange wholeBodyChange(std::span<const LabelChange> labels);

// Edge-length distortion |ln(|e'| / |e|)| of TM edges, split by whether an end
// lies outside the cage (placed by the propagation) or both inside (Green
// coordinates). The inside reference is restricted to the region the cage
// deforms: inside edges within `neighbourhoodRings` edge rings of an outside
// vertex, so that rigidly carried parts far away do not dilute it.
struct EdgeDistortion {
  std::size_t edges = 0;
  double mean = 0, median = 0, p95 = 0, max = 0;
};
struct OutlierDistortion {
  EdgeDistortion outside;       // edges with an end outside the cage
  EdgeDistortion insideNearby;  // edges with both ends inside, near an outside vertex
  EdgeDistortion inside;        // every edge with both ends inside
};
OutlierDistortion outlierEdgeDistortion(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed,
                                        std::span<const std::uint8_t> inside, int neighbourhoodRings = 3);

struct DeformationReport {
  std::string input, output, pose, engine;
  GridGeometry source, posed;    // input grid and G'
  int workingFactor = 1;         // working grid = source downsampled by this
  std::int64_t workingVoxels = 0;
  std::int64_t maxMemoryBytes = 0;  // 0: in core
  int samples = 1;
  std::vector<StageTime> stages;

  // Handles per pose selection (name, cage vertices it holds).
  std::vector<std::pair<std::string, std::size_t>> selections;
  bool automaticCage = true;
  std::size_t cageVertices = 0, cageFaces = 0;
  CageReport cage;
  std::int64_t foregroundOutsideCage = 0;  // working-grid voxels
  std::size_t envelopeVertices = 0, envelopeFaces = 0, envelopeOutside = 0;
  std::size_t tmVertices = 0, tmTets = 0, tmInside = 0, tmOutside = 0;
  // Deformed TM tets with volume <= 0 (the map folds there: output voxels in
  // the overlap take the tie rule's tet), and their share of the rest volume.
  std::size_t tmInverted = 0;
  double tmInvertedVolumeFraction = 0.0;
  std::int64_t uncoveredVoxels = 0;  // working-grid foreground voxels in no tet
  std::vector<CutReport> cuts;
  // Rigid bones (rigid_bones.h): groups, the TM vertices they place, the
  // vertices left free between two parts' bones, and per bone its rigidity.
  bool rigidBonesRequested = false;
  std::size_t rigidGroups = 0, rigidVertices = 0, sharedBoneVertices = 0;
  std::int64_t uncoveredBoneVoxels = 0;
  std::vector<BoneRigidity> bones;
  // With a joint pose: per body part (skeleton::Part order, part name), the
  // rigid motion of its bones from rest to posed by the joints' forward
  // kinematics, a 4 x 4 matrix in world mm (the posed bone of a part is its
  // rest bone moved by this; bones.per_bone measures how far it is from that).
  std::vector<std::pair<std::string, Eigen::Matrix4d>> partTransforms;
  // With body parts: tissue of two parts overlapping in the posed body.
  std::optional<Collisions> collisions;
  // With --articulated: the transfer mesh that resolves the skeleton
  // (articulated_mesh.h) and its posing (articulated_pose.h).
  struct Articulated {
    std::size_t vertices = 0, tets = 0, bodies = 0, bodyCutFaces = 0, limbCutFaces = 0, boneGapCutFaces = 0;
    std::size_t cutOffTissueVertices = 0;  // tissue the cuts closed off, rigid with the nearest bone (ArticulatedMesh)
    std::size_t rigidVertices = 0, slidingVertices = 0, solvedVertices = 0, solvedTets = 0;
    std::size_t stillVertices = 0, stillTets = 0;  // held at rest: far from every moved bone (ArticulatedPoseOptions::stillBeyondMm)
    int steps = 0, iterations = 0;
    double minRelativeVolume = 1.0;  // smallest det J over every step
    std::size_t invertedTets = 0;    // in the final positions
    bool reachedTargets = false;     // the bones sit on their parts' motions
    double maxSlidingGapMm = 0.0;
    // The untangling after the last step (ArticulatedPoseReport): the
    // inverted tets it found, the vertices it moved, its last radius (mm),
    // its seconds; the final positions' smallest det J.
    std::size_t invertedBeforeUntangling = 0, untangledVertices = 0;
    double untangleRadiusMm = 0.0, untangleSeconds = 0.0;
    // The contact after it: the boundary vertices through the tissue
    // across a crease before and after, the deepest of them (mm), its
    // rounds, the vertices the last round moved, its seconds.
    std::size_t penetratingBeforeContact = 0, penetratingAfterContact = 0, contactVertices = 0;
    double deepestPenetrationBeforeMm = 0.0, deepestPenetrationAfterMm = 0.0;
    int contactRounds = 0;
    double contactSeconds = 0.0;
    double finalMinRelativeVolume = 1.0;
  };
  std::optional<Articulated> articulated;
  RefinementResult refinement;
  DistortionHistograms distortion;
  OutlierDistortion outlierDistortion;

  std::vector<LabelChange> labels;
  WholeBodyChange wholeBody;
  // Projected areas and height of the source (rest) and of G' (posed).
  BodyProjection restProjection, posedProjection;
  Provenance provenance;
  bool withMasses = false;
  // A result beyond the run's bounds on bone and body change, written because
  // of --force (deform_run.h).
  bool forced = false;
  // --preserve-volumes: the label-volume correction of G' (label_volumes.h).
  std::optional<LabelVolumeCorrection> volumeCorrection;
  // --preserve-volumes with an organ table that names skin: the skin laid
  // over the tissue the pose bared (skin_cover.h).
  std::optional<SkinCover> skinCover;
};

// Fills the mesh sizes, outliers, cuts and distortion from a deformed
// pipeline.
void describePipeline(DeformationReport& report, const DeformationPipeline& pipeline);
// The transfer mesh's part of it: sizes, distortion histograms, inverted tets.
void describeTransferMesh(DeformationReport& report, const TetMesh& tm, const std::vector<Eigen::Vector3d>& deformed);

// The report as JSON text (indented) and as a short human summary.
std::string deformationReportJson(const DeformationReport& report);
std::string deformationSummary(const DeformationReport& report);

// Organs whose volume (and mass) changes by more than this are flagged in
// the printed table and the CSV.
inline constexpr double kDefaultFlagPercent = 2.0;
// Beyond these the deformation warns of large distortion: a dual edge
// stretched or shrunk by a factor of two or more, an angle off by 45 degrees.
inline constexpr double kLargeStretch = 2.0;
inline constexpr double kLargeAngleDeviationDeg = 45.0;

// The per-organ table a person reads: label, name, voxels before and after,
// mass before and after (with a table), change in %, and a flag column:
// "*" beyond flagPercent (organs of kSmallOrganVoxels or more), "small"
// beyond it under that size, "unnamed" for labels the organ table lacks.
std::string labelChangeTable(const DeformationReport& report, double flagPercent = kDefaultFlagPercent);
// The same rows as CSV (header line; names quoted).
std::string labelChangeCsv(const DeformationReport& report, double flagPercent = kDefaultFlagPercent);
// One line per thing a user must know: inverted TM tets, large distortion,
// labels without a name in the organ table. Empty when all is well.
std::vector<std::string> deformationWarnings(const DeformationReport& report);

}  // namespace vox
