#include "geometry/deform/pipeline.h"
#include "geometry/disjoint_sets.h"

#include "geometry/deform/prepared_state.h"
#include "geometry/deform/solve/green_coordinates.h"
#include "geometry/skeleton/label_groups.h"
#include "geometry/raster/out_of_core.h"
#include "geometry/deform/cage/surface_checks.h"
#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/label_stats.h"
#include "geometry/parallel.h"
#include "geometry/skeleton/body_parts.h"
#include "geometry/skeleton/bones.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <limits>
#include <numeric>
#include <set>

namespace vox {

namespace {

// Label of the groups that no separation names, in the TM's group grid: one
// material, so the mesher does not resolve interfaces nobody cuts.
constexpr Label kOtherGroups = Label(kLabelGroupCount + 1);

// The pre-processing's transfer mesh as built: cut, its cut reports and the
// working-grid voxels it leaves uncovered.
struct BuiltTransferMesh {
  TetMesh mesh;
  std::vector<CutReport> cuts;
  std::int64_t uncoveredVoxels = 0;
};

// The transfer mesh built on a thread of its own while the constructing
// thread builds the cage and the envelope: it depends on the label groups
// and F alone, and CGAL's mesher refines it on one core, so the cage's
// parallel loops have the other cores meanwhile. The thread counts its
// loops' threads as the constructing thread does (the same bytes either
// way), and stops when the pipeline fails (the destructor) or the process
// is cancelled while the pipeline waits for it.
class TransferMeshThread {
public:
  explicit TransferMeshThread(std::function<BuiltTransferMesh()> build) {
    result_ = std::async(std::launch::async, [this, threads = workerThreads(0), build = std::move(build)] {
      const ScopedWorkerThreads scope(threads);
      const ScopedCancellation cancel(stop_);
      return build();
    });
  }
  ~TransferMeshThread() {
    stop_ = true;
    if (result_.valid()) result_.wait();
  }
  TransferMeshThread(const TransferMeshThread&) = delete;
  TransferMeshThread& operator=(const TransferMeshThread&) = delete;

  // Waits for the mesh (rethrows the thread's exception), passing the
  // process's cancellation on to the thread's flag.
  BuiltTransferMesh get() {
    while (result_.wait_for(std::chrono::milliseconds(20)) != std::future_status::ready)
      if (cancellationRequested()) stop_ = true;
    return result_.get();
  }

private:
  std::atomic<bool> stop_{false};
  std::future<BuiltTransferMesh> result_;
};

}  // namespace

PipelineOptions poseOptions(const Pose& pose, const std::string& source, std::optional<OrganTable> organs) {
  PipelineOptions options;
  options.organs = std::move(organs);
  std::vector<LimbSeparation> cuts;
  for (const PoseSeparation& s : pose.separations) {
    options.cage.separations.push_back(s.cage);
    cuts.push_back(s.cut());
  }
  options.cuts = std::move(cuts);
  options.pose = pose;
  options.poseSource = source;
  return options;
}

std::string cageFault(const SurfaceCheck& c) {
  if (c.boundaryEdges) return std::to_string(c.boundaryEdges) + " boundary edges";
  if (c.nonManifoldEdges) return std::to_string(c.nonManifoldEdges) + " non-manifold edges";
  if (c.nonManifoldVertices) return std::to_string(c.nonManifoldVertices) + " non-manifold vertices";
  if (c.misorientedEdges) return std::to_string(c.misorientedEdges) + " inconsistently oriented edges";
  if (c.selfIntersections) return std::to_string(c.selfIntersections) + " self-intersecting face pairs";
  if (c.degenerateFaces) return std::to_string(c.degenerateFaces) + " degenerate faces";
  if (c.isolatedVertices) return std::to_string(c.isolatedVertices) + " unused vertices";
  return "non-positive volume";
}

DeformationPipeline::DeformationPipeline(const LabelGrid& grid, const PipelineOptions& options) : options_(options) {
  const std::vector<LimbSeparation>& separations = options_.cage.separations;
  const bool groupSelections = options_.pose && usesLabelGroups(*options_.pose);
  const bool withGroups = options_.organs || options_.bodyParts;
  const auto checkBodyParts = [&] {
    if (options_.bodyParts && options_.bodyParts->dims() != grid.dims())
      throw InputError("body parts", "the body-part grid's dims differ from the grid's");
  };
  checkBodyParts();
  if (options_.bodyPartsMeanwhile && (options_.bodyParts || !options_.organs || options_.groupsFromParts))
    throw RuntimeFailure("DeformationPipeline: bodyPartsMeanwhile goes with an organ table, groupsFromParts false and no bodyParts");
  if (options_.pose && !options_.pose->joints.empty())
    throw InputError(options_.poseSource, "a pose with joints is compiled against the grid's skeleton first (voxmorph deform, render and view do)");
  // S from the body parts when given, else from the organ names.
  const auto labelGroups = [&] {
    return options_.bodyParts && (options_.groupsFromParts || !options_.organs) ? skeleton::labelGroupsOfParts(*options_.bodyParts)
                                                                                : labelGroupGrid(grid, *options_.organs);
  };
  LabelGrid selectionGroups;  // S, for selections by label group
  {
    StageTimer timer("label groups");
    if (groupSelections) requireOrganTable(withGroups, OrganTableNeed::LabelGroup, options_.poseSource);
    if (separations.empty()) {
      groups_ = binaryGroupGrid(grid);
      if (withGroups) selectionGroups = labelGroups();
    } else {
      requireOrganTable(withGroups, OrganTableNeed::Separation, "separation");
      groups_ = labelGroups();
      std::vector<std::int64_t> count(kLabelGroupCount + 1, 0);
      for (const Label l : groups_.labels()) ++count[l];
      std::set<Label> named;
      for (const LimbSeparation& s : separations)
        for (const Label g : {s.groupA, s.groupB}) {
          if (g < 1 || g > kLabelGroupCount || count[g] == 0)
            throw InputError("separation", std::string("label group '") +
                                               (g >= 1 && g <= kLabelGroupCount ? labelGroupName(LabelGroup(g)) : "?") +
                                               "' has no voxels in this grid");
          named.insert(g);
        }
      meshGroups_ = groups_;
      for (Label& l : meshGroups_.labels())
        if (l != 0 && !named.count(l)) l = kOtherGroups;
    }
    if (options_.prepared) {
      groupsDigest_ = gridDigest(groups_);
      groupsWords_ = separations.empty() ? "the foreground"
                     : options_.bodyParts && (options_.groupsFromParts || !options_.organs) ? "the label groups of the body parts"
                                                                                              : "the label groups of the organ names";
    }
    stats_.stages.push_back(timer.stop());
  }
  // The transfer mesh first, on its own thread (TransferMeshThread), from
  // options_.prepared where it holds it; refused, where it lacks it, only
  // once the cage and envelope have been taken, so the message names the
  // first piece missing.
  sizing_ = defaultSizingField(groups_.geometry(), options_.sizingFraction);
  const bool separated = !separations.empty();
  const std::vector<LimbSeparation>& cuts = options_.cuts ? *options_.cuts : separations;
  PreparedMeshQuery meshQuery;
  if (options_.prepared)
    meshQuery = {(separated ? gridDigest(meshGroups_) : groupsDigest_) + " " + groupsDigest_ + " " + gridDigest(sizing_) + " " +
                     transferMeshOptionsKey(options_.transferMesh) + " cuts " + separationsKey(cuts),
                 separationsText(cuts, groups_.geometry())};
  const PreparedTransferMesh* storedMesh = options_.prepared ? options_.prepared->findMesh(meshQuery.key) : nullptr;
  std::function<BuiltTransferMesh()> buildMesh;
  if (!storedMesh && (!options_.prepared || options_.prepared->recording))
    buildMesh = [this, separated, &cuts] {
      BuiltTransferMesh built;
      // The mesh's group grid has the foreground of groups_: its uncovered
      // voxels are groups_'s.
      built.mesh = vox::buildTransferMesh(separated ? meshGroups_ : groups_, sizing_, options_.transferMesh, {}, &built.uncoveredVoxels);
      for (const LimbSeparation& s : cuts) built.cuts.push_back(cutTransferMesh(built.mesh, s.groupA, s.groupB, s.region));
      return built;
    };
  std::optional<TransferMeshThread> meshThread;
  if (buildMesh && options_.concurrentTransferMesh) meshThread.emplace(buildMesh);
  if (options_.bodyPartsMeanwhile) {
    StageTimer timer("skeleton");
    options_.bodyParts = options_.bodyPartsMeanwhile();
    checkBodyParts();
    stats_.stages.push_back(timer.stop());
  }
  {
    StageTimer timer("cage");
    if (options_.userCage) {
      builtCage_ = *options_.userCage;
      stats_.automaticCage = false;
      stats_.cage.check = checkSurface(builtCage_);
      stats_.cage.foregroundOutside = countForegroundOutside(builtCage_, groups_);
    } else {
      PreparedState* prepared = options_.prepared.get();
      PreparedCageQuery query;
      if (prepared)
        query = {groupsDigest_ + " " + cageOptionsKey(options_.cage), groupsWords_, separationsText(separations, grid.geometry()),
                 cageOptionsText(options_.cage)};
      if (const PreparedCage* stored = prepared ? prepared->findCage(query.key) : nullptr) {
        builtCage_ = stored->cage;
        stats_.cage = stored->report;
      } else {
        if (prepared && !prepared->recording) prepared->refuseCage(query);
        CageResult r = buildCage(groups_, options_.cage);
        if (!r.report.check.validCage())
          throw RuntimeFailure("the automatic cage is not a valid cage (" + cageFault(r.report.check) +
                               "); try another --vertices or --dilation");
        builtCage_ = std::move(r.cage);
        stats_.cage = r.report;
        if (prepared) prepared->cages.push_back({query.key, query.groups, query.separations, query.options, builtCage_, stats_.cage});
      }
    }
    stats_.foregroundOutsideCage = stats_.cage.foregroundOutside;
    stats_.stages.push_back(timer.stop());
  }
  cage_ = builtCage_;
  // With an organ table every cage vertex knows its nearest label group, so
  // any later pose may select by group.
  if (withGroups) cageGroups_ = nearestGroups(builtCage_.positions, separations.empty() ? selectionGroups : groups_);
  if (options_.bodyParts) cageBodyParts_ = nearestGroups(builtCage_.positions, *options_.bodyParts);
  if (options_.pose) selectHandles(*options_.pose, builtCage_, options_.poseSource, cageGroups_, cageBodyParts_);
  if (options_.envelope) {
    StageTimer timer("envelope");
    PreparedState* prepared = options_.prepared.get();
    const std::string key = prepared ? groupsDigest_ + " " + envelopeOptionsKey(options_.envelopeOptions) : "";
    if (const PreparedEnvelope* stored = prepared ? prepared->findEnvelope(key) : nullptr) {
      envelope_ = stored->envelope;
    } else {
      if (prepared && !prepared->recording) prepared->refuseEnvelope();
      envelope_ = extractEnvelope(groups_, options_.envelopeOptions);
      if (prepared) prepared->envelopes.push_back({key, envelope_});
    }
    stats_.stages.push_back(timer.stop());
  }
  if (options_.bodyParts && options_.organs && skeleton::namesBones(*options_.organs))
    boneKeys_ = boneKeyGrid(grid, *options_.organs, *options_.bodyParts);
  StageTimer meshTimer("transfer mesh");
  if (storedMesh) {
    transferMesh_ = storedMesh->mesh;
    stats_.cuts = storedMesh->cutReports;
    stats_.uncoveredVoxels = storedMesh->uncoveredVoxels;
  } else {
    if (!buildMesh) options_.prepared->refuseMesh(meshQuery);
    BuiltTransferMesh built = meshThread ? meshThread->get() : buildMesh();
    transferMesh_ = std::move(built.mesh);
    stats_.cuts = std::move(built.cuts);
    stats_.uncoveredVoxels = built.uncoveredVoxels;
    if (options_.prepared) options_.prepared->meshes.push_back({meshQuery.key, meshQuery.cuts, transferMesh_, stats_.cuts, stats_.uncoveredVoxels});
  }
  stats_.stages.push_back(meshTimer.stop());
  // The bone groups depend on the TM alone: once per TM, not per pose.
  rigidBones_ = boneKeys_.voxelCount() > 0 ? rigidBoneGroups(transferMesh_, boneKeys_, options_.rigidJointRings) : RigidBoneGroups{};
  if (options_.pose) setPose(*options_.pose, options_.poseSource);
}

void DeformationPipeline::recordStage(StageTime time) {
  for (StageTime& s : stats_.stages)
    if (s.name == time.name) {
      s = std::move(time);
      return;
    }
  stats_.stages.push_back(std::move(time));
}

void DeformationPipeline::precomputeFrame(bool withEnvelope) {
  const std::span<const Eigen::Vector3d> envelope =
      withEnvelope ? std::span<const Eigen::Vector3d>(envelope_.positions) : std::span<const Eigen::Vector3d>();
  FrameDeformerOptions frame = options_.frame;
  frame.propagateAnyway = acrossSeparation();
  if (options_.rigidBones) frame.rigidGroups = rigidBones_.vertexGroup;
  deformer_.precompute(cage_, envelope, transferMesh_, handles_.vertices, frame);
  if (frame.propagateAnyway.empty() || handles_.vertices.empty()) return;
  // Tears: a limb vertex that Green coordinates leave with the body beside
  // it (or the reverse) while its own group's neighbours follow the limb
  // shows, in the full pose, as edges to those neighbours stretched by more
  // than e. Such vertices are propagated from their group too, and the
  // embedding redone, a few rounds at most.
  for (int round = 0; round < 3; ++round) {
    updateFrame(1.0);
    if (markTornVertices(frame.propagateAnyway) == 0) break;
    deformer_.precompute(cage_, envelope, transferMesh_, handles_.vertices, frame);
  }
  updateFrame(0.0);
}

void DeformationPipeline::updateFrame(double fraction) {
  std::vector<Eigen::Isometry3d> motions;
  if (!options_.partMotions.empty()) {
    for (const Label part : rigidBones_.groupPart) {
      Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
      if (part < options_.partMotions.size()) {
        const PoseTransform& t = options_.partMotions[part];
        const Eigen::Vector3d o = t.apply(Eigen::Vector3d::Zero(), fraction);
        for (int k = 0; k < 3; ++k) m.linear().col(k) = t.apply(Eigen::Vector3d::Unit(k), fraction) - o;
        m.translation() = o;
      }
      motions.push_back(m);
    }
  }
  deformer_.update(handleTargets(pose_, handles_, cage_, fraction), pose_.arapIterations, motions);
}

std::size_t DeformationPipeline::markTornVertices(std::vector<std::uint8_t>& propagate) const {
  const std::vector<Eigen::Vector3d>& posed = deformer_.transferMeshPositions();
  const std::vector<std::uint8_t>& inside = deformer_.transferMeshInside();
  const std::size_t nv = transferMesh_.vertexCount();
  std::vector<std::int32_t> edges(nv, 0), torn(nv, 0);
  for (std::size_t t = 0; t < transferMesh_.tetCount(); ++t) {
    const Tet& tet = transferMesh_.tets[t];
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const auto u = std::size_t(tet[a]), v = std::size_t(tet[b]);
        const double rest = (transferMesh_.positions[u] - transferMesh_.positions[v]).norm();
        const double now = (posed[u] - posed[v]).norm();
        const bool stretched = rest > 0.0 && std::abs(std::log(std::max(now, 1e-12) / rest)) > 1.0;
        for (const std::size_t w : {u, v}) {
          ++edges[w];
          torn[w] += stretched;
        }
      }
  }
  std::size_t added = 0;
  for (std::size_t v = 0; v < nv; ++v)
    if (inside[v] && !propagate[v] && 2 * torn[v] > edges[v]) {
      propagate[v] = 1;
      ++added;
    }
  return added;
}

std::vector<std::uint8_t> DeformationPipeline::acrossSeparation() const {
  // With separations the inset cage follows the groups' interface only as
  // closely as its few hundred vertices allow: a hand vertex may lie in the
  // part of the cage around the thigh it touches, and Green coordinates
  // would move it with the thigh while its tets move with the hand. A TM
  // vertex whose tets all belong to one separated group, and whose nearest
  // cage vertex lies nearest the group it is separated from, is placed by
  // the propagation instead, from its own group's tets.
  const std::vector<LimbSeparation>& cuts = options_.cuts ? *options_.cuts : options_.cage.separations;
  std::vector<std::uint8_t> out;
  if (cuts.empty() || cageGroups_.size() != builtCage_.vertexCount() || cage_.vertexCount() == 0) return out;
  // Groups of the cage the deformation uses (the built cage's parts with handles).
  if (cageSource_.size() != cage_.vertexCount()) return out;
  std::vector<Label> groups(cage_.vertexCount());
  for (std::size_t c = 0; c < groups.size(); ++c) groups[c] = cageGroups_[std::size_t(cageSource_[c])];
  const std::size_t nv = transferMesh_.vertexCount();
  constexpr Label kMixed = Label(0xffff);
  std::vector<Label> vertexGroup(nv, 0);
  for (std::size_t t = 0; t < transferMesh_.tetCount(); ++t)
    for (const std::int32_t v : transferMesh_.tets[t]) {
      Label& g = vertexGroup[std::size_t(v)];
      const Label l = Label(transferMesh_.labels[t]);
      g = g == 0 ? l : (g == l ? g : kMixed);
    }
  out.assign(nv, 0);
  parallelFor(std::int64_t(nv), 0, [&](std::int64_t v) {
    const Label g = vertexGroup[std::size_t(v)];
    if (g == 0 || g == kMixed) return;
    const Eigen::Vector3d& p = transferMesh_.positions[std::size_t(v)];
    double best = std::numeric_limits<double>::infinity();
    Label nearest = 0;
    for (std::size_t c = 0; c < cage_.vertexCount(); ++c)
      if (const double d = (cage_.positions[c] - p).squaredNorm(); d < best) {
        best = d;
        nearest = groups[c];
      }
    for (const LimbSeparation& s : cuts)
      if ((g == s.groupA && nearest == s.groupB) || (g == s.groupB && nearest == s.groupA)) {
        if (s.region && !s.region->contains(p)) continue;
        out[std::size_t(v)] = 1;
      }
  });

  // The cut surface: the groups' interface inside the region, which the
  // inset cage follows least well (its erosion leaves the interface in a
  // shallow crease where Green coordinates blend both sides). Its vertices,
  // on either side, are placed from their own side's tets.
  for (const CutReport& cut : stats_.cuts)
    for (const std::int32_t v : cut.splitVertices) out[std::size_t(v)] = 1;

  // Islands: inside vertices of a separated group joined (through edges of
  // their group's tets) to less than 5 % of the group's largest inside
  // region, e.g. fingertips inside the part of the cage around the thigh
  // they touch, whose neighbours all lie outside. They are propagated too.
  std::vector<std::uint8_t> separated(kLabelGroupCount + 2, 0);
  for (const LimbSeparation& s : cuts)
    for (const Label g : {s.groupA, s.groupB})
      if (g < separated.size()) separated[g] = 1;
  // Only the vertices of a separated group that are not placed otherwise
  // need the cage's winding number.
  const auto ofSeparatedGroup = [&](std::size_t v) {
    const Label g = vertexGroup[v];
    return !out[v] && g != kMixed && g < separated.size() && separated[g];
  };
  std::vector<std::size_t> classified;
  std::vector<Eigen::Vector3d> points;
  for (std::size_t v = 0; v < nv; ++v)
    if (ofSeparatedGroup(v)) {
      classified.push_back(v);
      points.push_back(transferMesh_.positions[v]);
    }
  const std::vector<std::uint8_t> pointInside = insideCage(cage_, points);
  std::vector<std::uint8_t> inside(nv, 0);
  for (std::size_t k = 0; k < classified.size(); ++k) inside[classified[k]] = pointInside[k];
  auto candidate = [&](std::size_t v) { return inside[v] && ofSeparatedGroup(v); };
  DisjointSets islands(nv);
  const auto find = [&](std::int32_t v) { return islands.find(v); };
  for (std::size_t t = 0; t < transferMesh_.tetCount(); ++t) {
    const Tet& tet = transferMesh_.tets[t];
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        if (candidate(std::size_t(tet[a])) && candidate(std::size_t(tet[b]))) islands.unite(tet[a], tet[b]);
  }
  std::vector<std::int64_t> size(nv, 0);
  std::vector<std::int64_t> largest(separated.size(), 0);
  for (std::size_t v = 0; v < nv; ++v)
    if (candidate(v)) ++size[std::size_t(find(std::int32_t(v)))];
  for (std::size_t v = 0; v < nv; ++v)
    if (candidate(v)) largest[vertexGroup[v]] = std::max(largest[vertexGroup[v]], size[std::size_t(find(std::int32_t(v)))]);
  for (std::size_t v = 0; v < nv; ++v)
    if (candidate(v) && 20 * size[std::size_t(find(std::int32_t(v)))] < largest[vertexGroup[v]]) out[v] = 1;
  return out;
}

void DeformationPipeline::setPose(const Pose& pose, const std::string& source) {
  StageTimer timer("embedding");
  if (usesLabelGroups(pose)) requireOrganTable(options_.organs || options_.bodyParts, OrganTableNeed::LabelGroup, source);
  if (!pose.joints.empty())
    throw InputError(source, "a pose with joints is compiled against the grid's skeleton first (voxmorph deform, render and view do)");
  PoseHandles handles = selectHandles(pose, builtCage_, source, cageGroups_, cageBodyParts_);
  // Only the parts of the cage that hold a handle take part.
  const std::vector<std::int32_t> parts = cageParts(builtCage_);
  std::vector<std::uint8_t> held(builtCage_.vertexCount(), 0);
  for (const std::int32_t v : handles.vertices) held[std::size_t(parts[std::size_t(v)])] = 1;
  std::vector<std::int32_t> index(builtCage_.vertexCount(), -1);
  cage_ = {};
  cageSource_.clear();
  for (std::size_t v = 0; v < builtCage_.vertexCount(); ++v)
    if (held[std::size_t(parts[v])]) {
      index[v] = std::int32_t(cage_.positions.size());
      cage_.positions.push_back(builtCage_.positions[v]);
      cageSource_.push_back(std::int32_t(v));
    }
  for (const Tri& t : builtCage_.triangles)
    if (index[std::size_t(t[0])] >= 0) cage_.triangles.push_back({index[std::size_t(t[0])], index[std::size_t(t[1])], index[std::size_t(t[2])]});
  for (std::int32_t& v : handles.vertices) v = index[std::size_t(v)];
  handles_ = std::move(handles);
  pose_ = pose;
  refined_ = false;
  precomputeFrame(options_.envelope);
  fraction_ = 0.0;
  deformedEnvelope_ = envelope_.positions;
  recordStage(timer.stop());
}

void DeformationPipeline::deform(double fraction) {
  if (handles_.vertices.empty()) throw RuntimeFailure("DeformationPipeline::deform: no pose set");
  StageTimer timer("deformation");
  embedRefinedMesh();
  fraction_ = fraction;
  updateFrame(fraction);
  if (deformer_.envelopePositions().size() == envelope_.vertexCount()) deformedEnvelope_ = deformer_.envelopePositions();
  recordStage(timer.stop());
}

void DeformationPipeline::deformTo(const Eigen::MatrixX3d& handleTargets, int arapIterations) {
  if (handles_.vertices.empty()) throw RuntimeFailure("DeformationPipeline::deformTo: no pose set");
  if (std::size_t(handleTargets.rows()) != handles_.vertices.size())
    throw RuntimeFailure("DeformationPipeline::deformTo: " + std::to_string(handleTargets.rows()) + " targets for " +
                         std::to_string(handles_.vertices.size()) + " handles");
  embedRefinedMesh();
  deformer_.update(handleTargets, arapIterations);
  if (deformer_.envelopePositions().size() == envelope_.vertexCount()) deformedEnvelope_ = deformer_.envelopePositions();
}

RefinementResult DeformationPipeline::refine(const RefinementOptions& options, const VertexFieldInterpolation& interpolate) {
  if (handles_.vertices.empty()) throw RuntimeFailure("DeformationPipeline::refine: no pose set");
  StageTimer timer("refinement");
  const RefinementSubject subject{
      .restMesh = [this]() -> const TetMesh& { return transferMesh_; },
      .deformedPositions = [this]() -> const std::vector<Eigen::Vector3d>& { return deformedTransferMesh(); },
      .placedByDeformation = [this] { return placedByGreenCoordinates(); },
      .placeMidpoints = [this](const TetMesh& refined, std::span<const TetEdge> parents, std::vector<Eigen::Vector3d>& deformed,
                               std::vector<std::uint8_t>& placed) { placeMidpoints(refined, parents, deformed, placed); },
      .adopt = [this](TetMesh refined, std::vector<Eigen::Vector3d> deformed, std::vector<std::uint8_t> placed) {
        adoptRefinedMesh(std::move(refined), std::move(deformed), std::move(placed));
      },
  };
  RefinementResult result = refineTransferMesh(subject, sizing_.geometry, interpolate, options);
  recordStage(timer.stop());
  return result;
}

std::vector<std::uint8_t> DeformationPipeline::placedByGreenCoordinates() const {
  std::vector<std::uint8_t> placed = transferMeshInside();
  if (!options_.rigidBones || rigidBones_.vertexGroup.size() != placed.size()) return placed;
  // A rigid bone's vertices move with its fit, the band around them by the
  // propagation (FrameDeformerOptions::rigidBandRings).
  std::vector<std::uint8_t> held(placed.size(), 0);
  for (std::size_t v = 0; v < held.size(); ++v) held[v] = rigidBones_.vertexGroup[v] >= 0;
  for (int ring = 0; ring < options_.frame.rigidBandRings; ++ring) {
    std::vector<std::uint8_t> next = held;
    for (const Tet& t : transferMesh_.tets)
      if (held[std::size_t(t[0])] || held[std::size_t(t[1])] || held[std::size_t(t[2])] || held[std::size_t(t[3])])
        for (const std::int32_t v : t) next[std::size_t(v)] = 1;
    held = std::move(next);
  }
  for (std::size_t v = 0; v < placed.size(); ++v)
    if (held[v]) placed[v] = 0;
  return placed;
}

void DeformationPipeline::placeMidpoints(const TetMesh& refined, std::span<const TetEdge> parents,
                                         std::vector<Eigen::Vector3d>& deformed, std::vector<std::uint8_t>& placed) const {
  const std::size_t old = deformed.size(), nv = refined.vertexCount();
  // A midpoint between two vertices the Green coordinates place, inside the
  // cage, is placed by them too: the deformation itself, which the split
  // tets now follow more closely. Any other midpoint stays on its edge's
  // deformed image (the propagation and a rigid motion are affine on a tet).
  const std::span<const Eigen::Vector3d> added(refined.positions.data() + old, nv - old);
  const std::vector<std::uint8_t> inCage = insideCage(cage_, added);
  placed.resize(nv, 0);
  std::vector<Eigen::Vector3d> points;
  std::vector<std::size_t> ids;
  for (std::size_t v = old; v < nv; ++v) {
    const TetEdge& e = parents[v - old];
    placed[v] = placed[std::size_t(e[0])] && placed[std::size_t(e[1])] && inCage[v - old];
    if (!placed[v]) continue;
    ids.push_back(v);
    points.push_back(refined.positions[v]);
  }
  deformed.resize(nv);
  if (!points.empty()) {
    const GreenCoordinates coordinates = greenCoordinates(cage_, points, options_.frame.precision);
    const GreenCageFrame frame = greenCageDisplacement(cage_, deformer_.cagePositions(), coordinates.stride());
    std::vector<Eigen::Vector3d> out(points.size());
    applyGreenCoordinates(coordinates, frame, out, points);
    for (std::size_t k = 0; k < ids.size(); ++k) deformed[ids[k]] = out[k];
  }
  for (std::size_t v = old; v < nv; ++v)
    if (!placed[v]) deformed[v] = 0.5 * (deformed[std::size_t(parents[v - old][0])] + deformed[std::size_t(parents[v - old][1])]);
}

void DeformationPipeline::adoptRefinedMesh(TetMesh refined, std::vector<Eigen::Vector3d> deformed, std::vector<std::uint8_t> placed) {
  // Inside: the initial vertices keep theirs; a midpoint is inside when the
  // Green coordinates placed it.
  std::vector<std::uint8_t> inside = transferMeshInside();
  const std::size_t old = inside.size();
  inside.resize(refined.vertexCount(), 0);
  for (std::size_t v = old; v < inside.size(); ++v) inside[v] = placed[v];
  transferMesh_ = std::move(refined);
  refinedPositions_ = std::move(deformed);
  refinedInside_ = std::move(inside);
  refined_ = true;
  // The bone groups of the refined TM, for the report (its midpoints took
  // their parents' motion).
  rigidBones_ = boneKeys_.voxelCount() > 0 ? rigidBoneGroups(transferMesh_, boneKeys_, options_.rigidJointRings) : RigidBoneGroups{};
}

void DeformationPipeline::embedRefinedMesh() {
  if (!refined_) return;
  refined_ = false;
  precomputeFrame(options_.envelope);
}

}  // namespace vox
