#include "geometry/deform/run/deform_run.h"

#include "geometry/ascii_text.h"
#include "geometry/deform/articulated_pose.h"
#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/deform/pose/posed_extent.h"
#include "geometry/deform/prepared_state.h"
#include "geometry/deform/solve/label_volumes.h"
#include "geometry/deform/solve/skin_cover.h"
#include "geometry/deform/solve/rigid_bones.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/mesh_io.h"
#include "geometry/label_stats.h"
#include "geometry/parallel.h"
#include "geometry/raster/out_of_core.h"
#include "geometry/raster/rasterize.h"
#include "geometry/skeleton/body_parts.h"
#include "geometry/skeleton/bones.h"
#include "geometry/world_frame.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <future>
#include <memory>
#include <numbers>
#include <optional>

namespace vox {

namespace {

// Memory the driver, the Vulkan device and the allocator keep beside the
// rasterization buffers under --max-memory.
constexpr std::int64_t kRasterOverheadBytes = std::int64_t(256) << 20;

// The source: whole in memory (read, or a view of the caller's grid), or
// opened out of core.
struct Source {
  std::optional<LabelGrid> grid;
  std::unique_ptr<OutOfCoreSource> outOfCore;
  // The pipeline's grid when downsampled, or a borrowing caller's grid
  // copied for the pipeline, which reads labels as a vector (empty otherwise).
  LabelGrid working;
  const LabelGrid* caller = nullptr;  // request.inputGrid
  int factor = 1;

  const GridGeometry& geometry() const { return grid ? grid->geometry() : outOfCore->geometry(); }
  const LabelGrid& workingGrid() const {
    if (outOfCore) return outOfCore->downsampled();
    if (working.voxelCount() > 0) return working;
    return caller ? *caller : *grid;
  }
};

Source openSource(const DeformGridRequest& o) {
  Source s;
  if (o.maxMemoryMb > 0) {
    // Half the budget for the pre-processing's peak, the rest for the mesher,
    // the transfer mesh and its coordinates.
    const std::int64_t budget = o.maxMemoryMb << 20;
    const std::int64_t maxWorking = std::min(kDefaultWorkingVoxels, budget / 2 / kPreprocessBytesPerVoxel);
    // A compressed file is spooled to an unlinked temporary beside the
    // output, or without one in the system's temporary folder.
    const bool seekable = o.inputGrid || gridSlicesSeekable(o.input);
    const std::string temp = seekable             ? std::string()
                             : o.output.empty() ? std::filesystem::temp_directory_path().string()
                                                : std::filesystem::path(o.output).parent_path().string();
    std::unique_ptr<GridSliceReader> reader = o.inputGrid ? std::make_unique<LabelGridSlices>(*o.inputGrid) : openGridSlices(o.input);
    s.outOfCore = std::make_unique<OutOfCoreSource>(std::move(reader), o.input, seekable, maxWorking, temp);
    s.factor = s.outOfCore->downsampleFactor();
    return s;
  }
  if (o.inputGrid) {
    s.grid = LabelGrid(o.inputGrid->geometry(), o.inputGrid->data(), nullptr);
    s.caller = o.inputGrid;
  } else {
    s.grid = readGrid(o.input);
  }
  s.factor = downsampleFactor(s.grid->geometry(), kDefaultWorkingVoxels);
  if (s.factor > 1) {
    s.working = downsampleLabels(*s.grid, s.factor);
  } else if (o.inputGrid && o.inputGrid->borrowed()) {
    s.working = *o.inputGrid;
  }
  return s;
}

// G' held in memory, handed to writePosedGrid slab by slab.
class HeldGrid : public SlabRasterizer {
public:
  explicit HeldGrid(const LabelGrid& grid) : grid_(grid) {}
  const GridGeometry& outputGeometry() const override { return grid_.geometry(); }
  std::int64_t slabSlices() const override { return 64; }
  void rasterizeSlab(std::int64_t z0, std::int64_t z1, Label* out) override {
    const std::int64_t slice = grid_.geometry().sliceVoxels();
    std::copy(grid_.data() + z0 * slice, grid_.data() + z1 * slice, out);
  }

private:
  const LabelGrid& grid_;
};

// G' where the request wants it: its file and, with request.posedGrid, in
// memory, handed over on commit. G' held whole (`whole`, the volume
// correction's) is handed over as it is, not copied from the slices.
class PosedGridSink : public GridSliceWriter {
public:
  PosedGridSink(const DeformGridRequest& o, const GridGeometry& g, Label maxLabel, LabelGrid* whole)
      : keep_(o.posedGrid), whole_(whole) {
    if (!o.output.empty()) file_ = createGridSlices(o.output, g, maxLabel);
    if (keep_ && !whole_) grid_ = LabelGrid(g);
  }
  void writeSlices(const Label* in, std::int64_t count) override {
    if (keep_ && !whole_) {
      const std::int64_t n = count * grid_.geometry().sliceVoxels();
      std::copy(in, in + n, grid_.data() + written_);
      written_ += n;
    }
    if (file_) file_->writeSlices(in, count);
  }
  void commit() override {
    if (file_) file_->commit();
    if (keep_) *keep_ = whole_ ? std::move(*whole_) : std::move(grid_);
  }

private:
  LabelGrid* keep_;
  LabelGrid* whole_;
  std::unique_ptr<GridSliceWriter> file_;
  LabelGrid grid_;
  std::int64_t written_ = 0;
};

// What the report and the writer take from the source grid alone: its
// projection, its label counts and its largest label (the output's datatype).
struct SourceMeasures {
  BodyProjection projection;
  std::vector<std::uint64_t> counts;
  Label maxLabel = 0;
};

// The source's measures; held whole, they are taken on a thread of their own
// while the pipeline poses the mesh (its transfer mesh keeps one core while
// the cage's loops leave the other waiting), out of core they come with the
// working grid.
std::future<SourceMeasures> measureSource(const Source& source) {
  if (!source.grid) {
    std::promise<SourceMeasures> ready;
    ready.set_value({source.outOfCore->bodyProjection(), source.outOfCore->labelCounts(), source.outOfCore->maxLabel()});
    return ready.get_future();
  }
  return std::async(std::launch::async, [&grid = *source.grid] {
    SourceMeasures m;
    m.counts = computeLabelStats(grid).counts;
    m.maxLabel = Label(m.counts.size() - 1);
    m.projection = bodyProjection(grid);
    return m;
  });
}

void warn(const DeformGridRequest& o, const std::string& message) {
  if (o.warn) o.warn(message);
}

// The bone whose volume the pose changes most, when by more than
// `maxPercent` (report.bones: the volume through the transfer mesh).
std::optional<std::string> boneChangeFault(const DeformationReport& report, double maxPercent) {
  const BoneRigidity* worst = nullptr;
  for (const BoneRigidity& b : report.bones)
    if (!worst || std::abs(b.volumeChangePercent()) > std::abs(worst->volumeChangePercent())) worst = &b;
  if (!worst || !(std::abs(worst->volumeChangePercent()) > maxPercent)) return std::nullopt;
  return "the pose changes the volume of the " + std::string(skeleton::partName(skeleton::Part(worst->key / kBoneKeyStride))) + " " +
         skeleton::boneName(skeleton::Bone(worst->key % kBoneKeyStride)) + " by " + formatNumber("%+.1f", worst->volumeChangePercent()) +
         " % (more than --max-bone-change " + formatNumber("%g", maxPercent) + " %)";
}

// Two parts' tissue pressed through each other over more than `maxPercent`
// of the body (report.collisions): more than contact holds. Named by the
// pair that overlaps most and, where one hangs from the other, their joint.
std::optional<std::string> tissueOverlapFault(const Collisions& c, double maxPercent) {
  const double percent = 100.0 * c.bodyFraction();
  if (!(percent > maxPercent) || c.pairs.empty()) return std::nullopt;
  const auto a = skeleton::Part(c.pairs.front().partA), b = skeleton::Part(c.pairs.front().partB);
  const std::optional<skeleton::JointId> between = skeleton::jointBetween(a, b);
  const std::string joint = between ? std::string(" at the ") + skeleton::jointKind(*between).name : std::string();
  return "the pose presses the tissue of the " + std::string(skeleton::partName(a)) + " and the " + skeleton::partName(b) +
         " through each other" + joint + " (" + formatNumber("%.2f", percent) + " % of the body overlaps, more than --max-tissue-overlap " +
         formatNumber("%g", maxPercent) + " %)";
}

// A physically wrong result: refused (nothing written) unless forced, then
// written with a warning and "forced" in the report.
void refuseOrForce(const DeformGridRequest& o, DeformationReport& report, const std::string& fault) {
  if (!o.force) throw InputError(o.poseSource, fault + "; nothing written (--force writes it)");
  report.forced = true;
  warn(o, fault + "; written because of --force");
}

}  // namespace

// The pipeline's options on the working grid: a pose with joints (or
// selections by body part, or a user's parts grid) compiled against the
// skeleton, the cage options and the extra separations.
PipelineOptions deformPipelineOptions(const DeformGridRequest& o, const LabelGrid& working, int factor, const PreparedState* prepared,
                                      std::optional<std::string>* bonesFault) {
  if (bonesFault) bonesFault->reset();
  const skeleton::Skeleton* stored = prepared && prepared->skeleton ? &*prepared->skeleton : nullptr;
  std::optional<LabelGrid> userParts;
  if (!o.parts.empty() && !stored) {
    LabelGrid parts = readGrid(o.parts);  // its dims checked with the request
    if (factor > 1) parts = downsampleLabels(parts, factor);
    userParts = std::move(parts);
  }
  // Bones held rigid turn about their joint: the cage near the joint turns
  // with the moving part too (unless the pose says otherwise), so that the
  // tissue around the bone follows it.
  skeleton::JointPoseOptions joints;
  if (o.rigidBones) joints.jointZone = skeleton::JointZone::Child;
  // The prepared skeleton (built from the same grid, organ table and parts
  // grid: PreparedState::check) stands in for the one built here.
  const bool skeletal = !o.pose.joints.empty() || usesBodyParts(o.pose) || !o.parts.empty();
  std::optional<skeleton::Skeleton> built;
  if (skeletal && !stored) {
    requireOrganTable(o.organs.has_value(), OrganTableNeed::Bones, o.poseSource);
    built = skeleton::buildSkeleton(working, *o.organs, {o.input, o.organsSource, o.parts}, std::move(userParts));
  }
  // A skeletal pose has its skeleton here (stored or built); any other pose
  // compiles without one.
  const skeleton::Skeleton* sk = stored ? stored : built ? &*built : nullptr;
  PipelineOptions options = skeletal ? skeleton::skeletalPoseOptions(o.pose, o.poseSource, *sk, o.organs, joints)
                                     : skeleton::skeletalPoseOptions(o.pose, o.poseSource, working, o.organs,
                                                                     {o.input, o.organsSource, o.parts}, std::nullopt, joints);
  if (bonesFault && !o.pose.joints.empty())
    *bonesFault = skeleton::bonesThroughEachOther(*sk, skeleton::posedJoints(*sk, o.pose.joints, o.poseSource), o.pose.joints,
                                                  o.maxBoneOverlapPercent);
  // Any pose on a grid whose organ table names bones: the body parts too, for
  // the collision count and the bone measures (the label groups of a pose
  // without joints stay those of the organ names).
  // Built, they are computed while the pipeline builds the transfer mesh.
  if (!options.bodyParts && o.organs && skeleton::namesBones(*o.organs)) {
    options.groupsFromParts = false;
    if (stored) {
      options.bodyParts = stored->parts.parts;
    } else {
      options.bodyPartsMeanwhile = [&working, organs = *o.organs, input = o.input, organsSource = o.organsSource]() -> std::optional<LabelGrid> {
        try {
          return skeleton::bodyParts(working, organs, input, organsSource).parts;
        } catch (const InputError&) {
          return std::nullopt;  // a table that names bones the grid does not hold: no body parts
        }
      };
    }
  }
  options.rigidBones = o.rigidBones;
  // Under a memory limit the working grid is sized for one stage's grids at a time.
  options.concurrentTransferMesh = o.maxMemoryMb <= 0;
  options.cage.dilationMm = o.dilationMm;
  options.cage.targetVertices = o.vertices;
  for (const LimbSeparation& s : o.extraSeparations) {
    options.cage.separations.push_back(s);
    options.cuts->push_back(s);
  }
  if (o.cage) options.userCage = *o.cage;
  return options;
}

namespace {

// Each part's forward-kinematics motion (grid frame) as a 4 x 4 matrix in
// the world frame (world = direction * grid).
std::vector<std::pair<std::string, Eigen::Matrix4d>> partTransformsInWorld(std::span<const Eigen::Isometry3d> motions,
                                                                             const GridGeometry& g) {
  std::vector<std::pair<std::string, Eigen::Matrix4d>> out;
  for (std::size_t p = 1; p < motions.size(); ++p) {
    // Segments beyond the body parts (the scapulae) only where they moved.
    if (p > std::size_t(skeleton::kPartCount) && motions[p].isApprox(Eigen::Isometry3d::Identity(), 0.0)) continue;
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = g.direction * motions[p].linear() * g.direction.transpose();
    m.topRightCorner<3, 1>() = g.direction * motions[p].translation();
    out.emplace_back(segmentName(int(p)), m);
  }
  return out;
}
std::vector<std::pair<std::string, Eigen::Matrix4d>> partTransformsInWorld(const std::vector<PoseTransform>& motions,
                                                                             const GridGeometry& g) {
  std::vector<Eigen::Isometry3d> m(motions.size(), Eigen::Isometry3d::Identity());
  for (std::size_t p = 0; p < motions.size(); ++p) {
    const PoseTransform& t = motions[p];
    m[p].linear() = Eigen::AngleAxisd(t.angleDeg * std::numbers::pi / 180.0, t.axis).toRotationMatrix();
    m[p].translation() = t.center - m[p].linear() * t.center + t.translation;
  }
  return partTransformsInWorld(m, g);
}

// The rest transfer mesh, its posed positions and what the posing adds to
// the outputs.
struct PosedMesh {
  TetMesh rest;
  std::vector<Eigen::Vector3d> deformed;
  LabelGrid collisionMask;
  std::optional<TriMesh> posedCage;
  std::optional<LabelGrid> parts;  // the body parts on the working grid, when the run has them
  bool rigidBones = false;         // the bones moved rigidly (the articulated transfer mesh)
};

// Collisions of the posed body parts on the working grid's spacing.
Collisions collisionsOf(const DeformGridRequest& o, const Source& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed,
                        const LabelGrid& parts, LabelGrid& mask) {
  GridGeometry lattice = deformedGridGeometry(source.geometry(), deformed);
  if (source.factor > 1) {
    for (int a = 0; a < 3; ++a) lattice.dims[std::size_t(a)] = (lattice.dims[std::size_t(a)] + source.factor - 1) / source.factor;
    lattice.spacing *= double(source.factor);
  }
  Collisions collisions = findCollisions(rest, deformed, parts, lattice, !o.collisionMask.empty());
  if (!o.collisionMask.empty()) mask = std::move(collisions.mask);
  collisions.mask = {};
  return collisions;
}

// The cage pipeline: cage, transfer mesh, embedding, deformation,
// refinement, collisions.
PosedMesh poseByCage(const DeformGridRequest& o, const Source& source, RasterEngines& engines, DeformationReport& report,
                     const std::shared_ptr<PreparedState>& prepared) {
  PosedMesh out;
  StageTimer skeletonTimer("skeleton");
  std::optional<std::string> bonesFault;
  PipelineOptions options = deformPipelineOptions(o, source.workingGrid(), source.factor, prepared.get(), &bonesFault);
  options.prepared = prepared;
  // The posed grid comes from the transfer mesh alone: the envelope (its
  // build, and the Green coordinates of its vertices in the embedding) is
  // for the interactive display, and leaving it out changes no output byte.
  options.envelope = false;
  if (options.bodyParts) report.stages.push_back(skeletonTimer.stop());
  if (bonesFault) refuseOrForce(o, report, *bonesFault);
  const bool separated = !options.cage.separations.empty();
  auto pipeline = std::make_unique<DeformationPipeline>(source.workingGrid(), options);
  if (pipeline->stats().foregroundOutsideCage > 0 && !separated)
    warn(o, std::to_string(pipeline->stats().foregroundOutsideCage) +
                " foreground voxels lie outside the cage without limb separation; the propagation solve places them, but a "
                "larger --dilation (or --separate where limbs touch) keeps them inside");
  pipeline->deform();
  checkPosedGrowth(source.geometry(), pipeline->deformedTransferMesh(), o.poseSource,
                   selectionMovingFarthest(pipeline->pose(), pipeline->handles(), pipeline->deformedCage(), source.geometry()),
                   o.allowGrowth);

  report.refinement = pipeline->refine({.maxIterations = o.refineIterations, .maxTets = o.maxTets}, engines.interpolation());
  describePipeline(report, *pipeline);
  report.rigidBonesRequested = o.rigidBones;
  report.partTransforms = partTransformsInWorld(options.partMotions, source.geometry());
  // A bone the pose crushes or swells is refused before anything is written.
  if (const std::optional<std::string> fault = boneChangeFault(report, o.maxBoneChangePercent)) refuseOrForce(o, report, *fault);
  std::optional<StageTime> collisionTime;
  if (const std::optional<LabelGrid>& parts = pipeline->bodyParts()) {
    StageTimer collisionTimer("collisions");
    report.collisions = collisionsOf(o, source, pipeline->transferMesh(), pipeline->deformedTransferMesh(), *parts, out.collisionMask);
    collisionTime = collisionTimer.stop();
    if (const std::optional<std::string> fault = tissueOverlapFault(*report.collisions, o.maxTissueOverlapPercent)) refuseOrForce(o, report, *fault);
  }
  // The extra outputs are written with G', once the whole body is measured
  // (the posed mesh from `rest` and `deformed` below).
  if (!o.posedCage.empty()) {
    out.posedCage = pipeline->cage();
    out.posedCage->positions = pipeline->deformedCage();
    surfaceGridToWorld(*out.posedCage, source.geometry());
  }
  for (const StageTime& t : pipeline->stats().stages) report.stages.push_back(t);
  if (collisionTime) report.stages.push_back(*collisionTime);

  // The pipeline's grids and coordinates go before the rasterization buffers.
  out.rest = pipeline->transferMesh();
  out.deformed = pipeline->deformedTransferMesh();
  if (o.preserveVolumes) out.parts = pipeline->bodyParts();
  pipeline.reset();
  engines.releaseInterpolation();
  return out;
}

// The articulated transfer mesh of `grid` with `options`: the prepared
// state's when it holds one, else built (with a warning when the state
// holds none).
ArticulatedMesh articulatedMeshOf(const LabelGrid& grid, const OrganTable& organs, const skeleton::Skeleton& sk,
                                  const ArticulatedMeshOptions& options, const PreparedState* prepared,
                                  const std::function<void(const std::string&)>& warn) {
  const PreparedArticulatedMesh* stored = prepared ? prepared->findArticulatedMesh(articulatedMeshOptionsKey(options)) : nullptr;
  if (prepared && !stored && warn)
    warn(prepared->source + ": holds no articulated transfer mesh (voxmorph prepare --articulated adds it); building it");
  return stored ? stored->mesh : buildArticulatedMesh(grid, organs, sk, options);
}

// The posing of a joint pose on `mesh`: its steps, the limb cuts' sides for
// the contact, the pelvis' bones left to the tissue.
ArticulatedPoseOptions articulatedPoseOptionsFor(const Pose& pose, const ArticulatedMesh& mesh, const LabelGrid& grid, const OrganTable& organs,
                                                 const skeleton::Skeleton& sk, const ArticulatedMeshOptions& meshOptions) {
  ArticulatedPoseOptions options;
  options.steps = articulatedPoseSteps(pose.joints, options);
  options.contact.side = limbGroupSides(mesh, sk);
  options.tissueBoneParts = tissueBoneParts(mesh, grid, organs, sk, meshOptions);
  return options;
}

// The joint pose on the transfer mesh that resolves the skeleton.
PosedMesh poseArticulated(const DeformGridRequest& o, const Source& source, DeformationReport& report, const PreparedState* prepared) {
  PosedMesh out;
  const LabelGrid& grid = source.workingGrid();
  StageTimer skeletonTimer("skeleton");
  const skeleton::Skeleton sk = prepared && prepared->skeleton ? *prepared->skeleton
                                                               : skeleton::buildSkeleton(grid, *o.organs, {o.input, o.organsSource, o.parts});
  const std::vector<skeleton::Joint> joints = skeleton::posedJoints(sk, o.pose.joints, o.poseSource);
  const skeleton::PartMotions partMotions = skeleton::partMotions(joints, o.pose.joints);
  report.stages.push_back(skeletonTimer.stop());
  if (const auto fault = skeleton::bonesThroughEachOther(sk, joints, o.pose.joints, o.maxBoneOverlapPercent)) refuseOrForce(o, report, *fault);
  StageTimer meshTimer("articulated transfer mesh");
  ArticulatedMeshOptions meshOptions;
  meshOptions.boneGapMm = o.boneGapMm;
  ArticulatedMesh mesh = articulatedMeshOf(grid, *o.organs, sk, meshOptions, prepared, [&](const std::string& w) { warn(o, w); });
  const std::vector<Eigen::Isometry3d> motions = segmentMotions(partMotions, sk, mesh);
  report.stages.push_back(meshTimer.stop());
  StageTimer poseTimer("articulated pose");
  ArticulatedPoser poser(mesh, articulatedPoseOptionsFor(o.pose, mesh, grid, *o.organs, sk, meshOptions));
  const ArticulatedPoseReport r = poser.pose(jointMotionPath(sk, joints, o.pose.joints, mesh));
  report.stages.push_back(poseTimer.stop());
  DeformationReport::Articulated a;
  a.vertices = mesh.mesh.vertexCount();
  a.tets = mesh.mesh.tetCount();
  a.bodies = mesh.bodies.size();
  for (const CutReport& c : mesh.cuts) a.bodyCutFaces += c.cutFaces;
  a.limbCutFaces = mesh.limbCut.cutFaces;
  a.boneGapCutFaces = mesh.boneGapCut.cutFaces;
  a.cutOffTissueVertices = mesh.cutOffTissueVertices;
  for (const std::size_t n : mesh.rigidVertices) a.rigidVertices += n;
  a.slidingVertices = r.slidingVertices;
  a.solvedVertices = r.solvedVertices;
  a.solvedTets = r.solvedTets;
  a.stillVertices = r.stillVertices;
  a.stillTets = r.stillTets;
  a.steps = r.steps;
  a.iterations = r.iterations;
  a.minRelativeVolume = r.minRelativeVolume;
  a.invertedTets = r.invertedTets;
  a.reachedTargets = r.reachedTargets;
  a.maxSlidingGapMm = r.maxSlidingGapMm;
  a.invertedBeforeUntangling = r.invertedBeforeUntangling;
  a.untangledVertices = r.untangledVertices;
  a.untangleRadiusMm = r.untangleRadiusMm;
  a.untangleSeconds = r.untangleSeconds;
  a.penetratingBeforeContact = r.penetratingBeforeContact;
  a.penetratingAfterContact = r.penetratingAfterContact;
  a.deepestPenetrationBeforeMm = r.deepestPenetrationBeforeMm;
  a.deepestPenetrationAfterMm = r.deepestPenetrationAfterMm;
  a.contactRounds = r.contactRounds;
  a.contactVertices = r.contactVertices;
  a.contactSeconds = r.contactSeconds;
  a.finalMinRelativeVolume = r.finalMinRelativeVolume;
  report.articulated = a;
  out.rest = std::move(mesh.mesh);
  out.deformed = poser.positions();
  describeTransferMesh(report, out.rest, out.deformed);
  report.partTransforms = partTransformsInWorld(motions, source.geometry());
  const RigidBoneGroups groups = rigidBoneGroups(out.rest, boneKeyGrid(grid, *o.organs, sk.parts.parts));
  report.rigidVertices = a.rigidVertices;
  report.uncoveredBoneVoxels = groups.uncoveredVoxels;
  report.bones = measureBoneRigidity(groups, out.rest, out.deformed);
  if (r.invertedTets > 0) {
    // Named by the joint nearest most of them (rest centroids).
    std::vector<std::size_t> near(sk.joints.size(), 0);
    for (const Tet& t : out.rest.tets) {
      if (signedVolume(out.deformed, t) > 0.0) continue;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const std::int32_t v : t) c += 0.25 * out.rest.positions[std::size_t(v)];
      if (const skeleton::Joint* joint = sk.nearestJoint(c)) ++near[std::size_t(joint - sk.joints.data())];
    }
    const auto most = std::size_t(std::max_element(near.begin(), near.end()) - near.begin());
    refuseOrForce(o, report,
                  "the pose inverts " + std::to_string(r.invertedTets) + " tets of the articulated transfer mesh" +
                      (near.empty() ? std::string() : " (" + std::to_string(near[most]) + " nearest " + sk.joints[most].kind().name + ")"));
  }
  if (const std::optional<std::string> fault = boneChangeFault(report, o.maxBoneChangePercent)) refuseOrForce(o, report, *fault);
  StageTimer collisionTimer("collisions");
  report.collisions = collisionsOf(o, source, out.rest, out.deformed, sk.parts.parts, out.collisionMask);
  report.stages.push_back(collisionTimer.stop());
  if (const std::optional<std::string> fault = tissueOverlapFault(*report.collisions, o.maxTissueOverlapPercent)) refuseOrForce(o, report, *fault);
  if (o.preserveVolumes) out.parts = sk.parts.parts;
  out.rigidBones = true;
  return out;
}

}  // namespace

void checkDeformGridRequest(const DeformGridRequest& o) {
  if (!(o.posedGrid && o.output.empty()) && !hasGridExtension(o.output)) throw InputError(o.output, "unknown grid format for the output");
  if (o.inputGrid && !o.prepared.empty())
    throw UsageError("--prepared", "is checked against the grid file it was made from; a grid in memory has none");
  if (!o.posedCage.empty() && !hasSurfaceExtension(o.posedCage))
    throw InputError(o.posedCage, "unknown surface format for --posed-cage (use .obj, .off or .ply)");
  if (o.preserveVolumes && o.maxMemoryMb > 0)
    throw UsageError("--preserve-volumes", "needs the posed grid in memory; it cannot be combined with --max-memory");
  if (!o.prepared.empty() && o.maxMemoryMb > 0)
    throw UsageError("--prepared", "holds the rest state of an in-core run; it cannot be combined with --max-memory");
  if (!o.collisionMask.empty() && !hasGridExtension(o.collisionMask))
    throw InputError(o.collisionMask, "unknown grid format for --collision-mask");
  if (!o.posedMesh.empty() && !hasTetMeshExtension(o.posedMesh))
    throw InputError(o.posedMesh, "unknown tet mesh format for --posed-mesh (use .mesh, .meshb, .vtu or .msh)");
  if (!o.pose.separations.empty() || !o.extraSeparations.empty())
    requireOrganTable(o.organs.has_value(), OrganTableNeed::Separation, o.poseSource);
  if (usesLabelGroups(o.pose)) requireOrganTable(o.organs.has_value(), OrganTableNeed::LabelGroup, o.poseSource);
  if (posesArticulated(o)) {
    if (o.pose.joints.empty()) throw InputError(o.poseSource, "--articulated poses joints: the pose has no \"joints\"");
    if (!o.pose.selections.empty() || !o.pose.separations.empty())
      throw InputError(o.poseSource, "--articulated poses joints only: the pose's selections and separations have no place there");
    if (o.maxMemoryMb > 0)
      throw UsageError(o.articulated ? "--articulated" : o.poseSource + " (\"articulated\")", "cannot be combined with --max-memory");
    if (o.cage || !o.posedCage.empty() || !o.extraSeparations.empty() || o.rigidBones || !o.parts.empty())
      throw UsageError(o.articulated ? "--articulated" : o.poseSource + " (\"articulated\")",
                       "has no cage: it cannot be combined with --cage, --posed-cage, --separate, --rigid-bones or --parts");
  }
  const bool skeletal = !o.pose.joints.empty() || usesBodyParts(o.pose) || !o.parts.empty();
  if (skeletal) {
    requireOrganTable(o.organs.has_value(), OrganTableNeed::Bones, o.poseSource);
    skeleton::requireBones(*o.organs, o.organsSource);
  }
  if (!o.parts.empty() &&
      openGridSlices(o.parts)->geometry().dims != (o.inputGrid ? o.inputGrid->dims() : openGridSlices(o.input)->geometry().dims))
    throw InputError(o.parts, "has other dims than the grid " + o.input);
  if (!o.collisionMask.empty() && !skeletal && !(o.organs && skeleton::namesBones(*o.organs)))
    throw InputError(o.collisionMask, "collisions are between body parts: they need an organ table that names the bones (--organs) or --parts");
}

DeformationReport deformGrid(const DeformGridRequest& o, RasterEngines& engines) {
  checkDeformGridRequest(o);

  DeformationReport report;
  report.input = o.input;
  report.output = o.output;
  report.pose = o.poseSource;
  report.samples = o.samples;
  report.maxMemoryBytes = o.maxMemoryMb << 20;
  report.withMasses = o.organs.has_value();
  report.provenance = o.provenance;

  StageTimer readTimer("read source");
  Source source = openSource(o);
  report.stages.push_back(readTimer.stop());
  report.source = source.geometry();
  std::future<SourceMeasures> measuring = measureSource(source);
  report.workingFactor = source.factor;
  report.workingVoxels = source.workingGrid().voxelCount();

  std::shared_ptr<PreparedState> prepared;
  if (!o.prepared.empty()) {
    StageTimer preparedTimer("prepared state");
    prepared = std::make_shared<PreparedState>(PreparedState::read(o.prepared));
    const std::string note =
        prepared->check(preparedInputs(o.input, o.organs, o.organsSource, o.parts, source.factor, source.workingGrid().dims()));
    if (!note.empty()) warn(o, note);
    report.stages.push_back(preparedTimer.stop());
  }
  PosedMesh posedMesh = posesArticulated(o) ? poseArticulated(o, source, report, prepared.get()) : poseByCage(o, source, engines, report, prepared);
  const TetMesh& rest = posedMesh.rest;
  const std::vector<Eigen::Vector3d>& deformed = posedMesh.deformed;
  LabelGrid& collisionMask = posedMesh.collisionMask;
  std::optional<TriMesh>& posedCage = posedMesh.posedCage;
  source.working = LabelGrid();  // the pipeline's grid goes before G'

  StageTimer rasterTimer("rasterization");
  std::int64_t rasterBudget = 0;
  if (source.outOfCore) {
    const std::int64_t resident = (source.outOfCore->downsampled().voxelCount() + collisionMask.voxelCount()) * std::int64_t(sizeof(Label)) +
                                  std::int64_t(rest.vertexCount()) * 48 + std::int64_t(rest.tetCount()) * 32;
    rasterBudget = std::max<std::int64_t>(std::int64_t(64) << 20, report.maxMemoryBytes - resident - kRasterOverheadBytes);
  }
  // With the volume correction and the body parts, each side's bone is
  // rasterized and corrected under a key of its own (splitLabels), so that
  // one humerus does not make up for the other.
  const SourceMeasures measures = measuring.get();
  report.restProjection = measures.projection;
  const Label maxLabel = measures.maxLabel;
  std::vector<std::uint8_t> bones;
  SplitLabels split;
  if (o.preserveVolumes && source.grid && o.organs) {
    for (const skeleton::Bone b : skeleton::boneOfLabels(*o.organs, maxLabel)) bones.push_back(b != skeleton::Bone::None);
    if (posedMesh.parts) split = splitLabels(*source.grid, bones, *posedMesh.parts, source.factor);
  }
  posedMesh.parts.reset();
  const LabelGrid* keyed = !split.labelOf.empty() ? &split.grid : source.grid ? &*source.grid : nullptr;
  const RasterSource raster = keyed ? RasterSource{.grid = keyed} : RasterSource{.slices = &source.outOfCore->slices()};
  const std::unique_ptr<SlabRasterizer> engine = makeRasterizer(engines, raster, rest, deformed, o.samples, rasterBudget);
  PosedGridMeasures after;
  std::unique_ptr<GridSliceWriter> output;  // G', committed once the whole body is measured
  std::vector<double> deformedVolumes;
  LabelGrid posed;  // G' held whole for the volume correction
  if (o.preserveVolumes) {
    posed = rasterizeAllSlabs(*engine);
    report.stages.push_back(rasterTimer.stop());
    StageTimer correctionTimer("volume correction");
    // The voids the pose opened inside the body first, the bones' labels
    // last. Bones moved rigidly keep their rest volume: where their voxels
    // lie in tissue tets beside the bone's own, the Jacobians of those tets
    // would count them squeezed or stretched with the tissue.
    std::vector<std::uint8_t> behind = bones;
    for (std::size_t k = bones.size(); k < split.labelOf.size(); ++k) behind.push_back(bones[split.labelOf[k]]);
    const std::vector<double> keyedVolumes = deformedLabelVolumes(*keyed, rest, deformed);
    const bool toRest = o.volumeTarget == DeformGridRequest::VolumeTarget::Rest;
    std::vector<double> targets = keyedVolumes;
    if (toRest || posedMesh.rigidBones) {
      const std::vector<double> restVolumes = deformedLabelVolumes(*keyed, rest, rest.positions);
      for (std::size_t k = 0; k < targets.size(); ++k)
        if (toRest || (k < behind.size() && behind[k])) targets[k] = restVolumes[k];
    }
    report.volumeCorrection = preserveLabelVolumes(posed, *keyed, rest, deformed, targets, 0, true, behind);
    report.volumeCorrection->toRestVolumes = toRest;
    deformedVolumes = keyedVolumes;
    if (!split.labelOf.empty()) {
      // The keys back to their labels.
      std::vector<Label>& labels = posed.labels();
      parallelRanges(std::int64_t(labels.size()), workerThreads(0), [&](std::int64_t v0, std::int64_t v1) {
        for (std::int64_t v = v0; v < v1; ++v) {
          Label& l = labels[std::size_t(v)];
          if (l < split.labelOf.size()) l = split.labelOf[l];
        }
      });
      deformedVolumes.assign(bones.size(), 0.0);
      for (std::size_t k = 0; k < keyedVolumes.size(); ++k)
        deformedVolumes[k < split.labelOf.size() ? split.labelOf[k] : k] += keyedVolumes[k];
      split = {};
    }
    report.stages.push_back(correctionTimer.stop());
    if (o.coverSkin && o.organs) {
      StageTimer coverTimer("skin cover");
      const std::vector<std::uint8_t> skin = skeleton::skinOfLabels(*o.organs, maxLabel);
      if (std::find(skin.begin(), skin.end(), std::uint8_t(1)) != skin.end()) {
        // bones: flagged above (the correction runs in core with the organ table)
        report.skinCover = coverBareTissue(posed, *source.grid, rest, deformed, skin, bones);
        report.stages.push_back(coverTimer.stop());
      }
    }
    StageTimer writeTimer("write");
    HeldGrid held(posed);
    output = std::make_unique<PosedGridSink>(o, held.outputGeometry(), maxLabel, &posed);
    after = writePosedGrid(held, *output, false);
    report.posed = held.outputGeometry();
    report.stages.push_back(writeTimer.stop());
  } else {
    output = std::make_unique<PosedGridSink>(o, engine->outputGeometry(), maxLabel, nullptr);
    after = writePosedGrid(*engine, *output, false);
    report.posed = engine->outputGeometry();
    report.stages.push_back(rasterTimer.stop());
  }
  report.engine = engines.name();

  const std::vector<std::uint64_t>& before = measures.counts;
  const OrganTable* organs = o.organs ? &*o.organs : nullptr;
  report.labels = labelChanges(before, after.counts, source.geometry().voxelVolume(), organs);
  report.posedProjection = after.projection;
  for (LabelChange& c : report.labels)
    if (c.label < deformedVolumes.size()) c.deformedVolumeVoxels = deformedVolumes[c.label];
  report.wholeBody = wholeBodyChange(report.labels);
  if (std::abs(report.wholeBody.volumeChangePercent) > o.maxBodyChangePercent)
    refuseOrForce(o, report,
                  "the pose changes the whole body's volume by " + formatNumber("%+.2f", report.wholeBody.volumeChangePercent) +
                      " % (more than --max-body-change " + formatNumber("%g", o.maxBodyChangePercent) + " %)");
  if (!o.collisionMask.empty()) writeGrid(o.collisionMask, collisionMask);
  if (posedCage) writeSurface(o.posedCage, *posedCage);
  if (!o.posedMesh.empty()) {
    TetMesh posed = rest;
    posed.positions = deformed;
    tetMeshGridToWorld(posed, source.geometry());
    writeTetMesh(o.posedMesh, posed);
  }
  output->commit();
  return report;
}

ArticulatedSteps poseArticulatedSteps(const ArticulatedStepsRequest& o) {
  const skeleton::Skeleton sk = o.prepared && o.prepared->skeleton
                                    ? *o.prepared->skeleton
                                    : skeleton::buildSkeleton(o.grid, o.organs, {o.gridSource, o.organsSource, ""});
  const std::vector<skeleton::Joint> joints = skeleton::posedJoints(sk, o.pose.joints, o.poseSource);
  ArticulatedMeshOptions meshOptions;
  meshOptions.boneGapMm = o.boneGapMm;
  ArticulatedMesh mesh = articulatedMeshOf(o.grid, o.organs, sk, meshOptions, o.prepared, o.warn);
  ArticulatedPoseOptions poseOptions = articulatedPoseOptionsFor(o.pose, mesh, o.grid, o.organs, sk, meshOptions);
  ArticulatedSteps out;
  poseOptions.onStep = [&](int, std::span<const Eigen::Vector3d> positions) {
    out.steps.emplace_back(positions.begin(), positions.end());
    if (o.onStep) o.onStep(int(out.steps.size()));
  };
  ArticulatedPoser poser(mesh, poseOptions);
  out.report = poser.pose(jointMotionPath(sk, joints, o.pose.joints, mesh));
  out.rest = std::move(mesh.mesh);
  return out;
}

int articulatedStepCount(const Pose& pose) { return articulatedPoseSteps(pose.joints, ArticulatedPoseOptions{}) + 1; }

}  // namespace vox
