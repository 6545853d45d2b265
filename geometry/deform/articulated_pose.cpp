#include "geometry/deform/articulated_pose.h"

#include "geometry/cancellation.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <queue>

namespace vox {

namespace {

// The rigid motion that best takes from(k) to to(k) over the solve indices
// `ids` (at least three).
template <class From, class To>
Eigen::Isometry3d rigidFit(std::span<const std::int32_t> ids, From&& from, To&& to) {
  Eigen::Matrix3Xd a(3, Eigen::Index(ids.size())), b(3, Eigen::Index(ids.size()));
  for (std::size_t k = 0; k < ids.size(); ++k) {
    a.col(Eigen::Index(k)) = from(ids[k]);
    b.col(Eigen::Index(k)) = to(ids[k]);
  }
  Eigen::Isometry3d fit;
  fit.matrix() = Eigen::umeyama(a, b, false);
  return fit;
}

}  // namespace

ArticulatedPoser::ArticulatedPoser(const ArticulatedMesh& mesh, const ArticulatedPoseOptions& options)
    : mesh_(mesh), options_(options), positions_(mesh.mesh.positions) {
  const TetMesh& m = mesh.mesh;
  edges_.resize(m.vertexCount());
  for (const Tet& t : m.tets)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const std::int32_t a = t[std::size_t(i)], b = t[std::size_t(j)];
        const double l = (m.positions[std::size_t(a)] - m.positions[std::size_t(b)]).norm();
        edges_[std::size_t(a)].emplace_back(b, l);
        edges_[std::size_t(b)].emplace_back(a, l);
      }
  nearestParts();
}

namespace {

// Dijkstra along `edges` from the vertices where dist is 0: dist filled in.
void edgeDistances(const std::vector<std::vector<std::pair<std::int32_t, double>>>& edges, std::vector<double>& dist) {
  using Item = std::pair<double, std::int32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (std::size_t v = 0; v < dist.size(); ++v)
    if (dist[v] == 0.0) queue.emplace(0.0, std::int32_t(v));
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[std::size_t(v)]) continue;
    for (const auto& [w, l] : edges[std::size_t(v)])
      if (d + l < dist[std::size_t(w)]) {
        dist[std::size_t(w)] = d + l;
        queue.emplace(d + l, w);
      }
  }
}

}  // namespace

void ArticulatedPoser::prepare(std::span<const Eigen::Isometry3d> motions) {
  const TetMesh& m = mesh_.mesh;
  const std::size_t nv = m.vertexCount();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  solved_.clear();
  constrained_.clear();
  sliding_.clear();
  still_.clear();
  approachSoftBones_.clear();
  for (std::vector<std::int32_t>& owned : partConstrained_) owned.clear();
  bridgingTets_ = stillTets_ = 0;
  // Still vertices: the bones of segments the pose does not move, the
  // tissue farther than stillBeyondMm from every moved segment's bone, and
  // the tissue that carries the bones of an unmoved part (tissueBoneParts).
  const bool stillOn = options_.stillBeyondMm > 0.0;
  std::array<bool, kSegmentCount + 1> turned{}, moving{};
  for (int p = 1; p <= kSegmentCount; ++p) {
    const Eigen::Isometry3d mp = partMotionAt(motions, skeleton::Part(p), 1.0);
    turned[std::size_t(p)] = (mp.linear() - Eigen::Matrix3d::Identity()).norm() > 1e-12 || mp.translation().norm() > 1e-9;
    moving[std::size_t(p)] = !stillOn || turned[std::size_t(p)];
  }
  std::vector<std::uint8_t> still(nv, 0);
  if (stillOn) {
    std::vector<double> dist(nv, kInf);
    for (std::size_t v = 0; v < nv; ++v)
      if (mesh_.role[v] == VertexRole::Rigid && moving[std::size_t(mesh_.vertexPart[v])]) dist[v] = 0.0;
    edgeDistances(edges_, dist);
    for (std::size_t v = 0; v < nv; ++v)
      still[v] = mesh_.role[v] == VertexRole::Rigid ? !moving[std::size_t(mesh_.vertexPart[v])] : dist[v] > options_.stillBeyondMm;
  }
  // The bones left to the tissue, of the parts the pose does not move.
  const std::vector<skeleton::Part>& carried = options_.tissueBoneParts;
  for (std::size_t v = 0; v < std::min(nv, carried.size()); ++v)
    if (mesh_.role[v] == VertexRole::Free && carried[v] != skeleton::Part::None && !turned[std::size_t(carried[v])]) still[v] = 1;

  std::vector<std::int32_t> index(nv, -1);
  std::vector<Tet> tets;
  for (const Tet& t : m.tets) {
    if (rigidWithOneSegment(mesh_, t)) continue;
    bool allRigid = true, allStill = true;
    for (const std::int32_t v : t) {
      allRigid = allRigid && mesh_.role[std::size_t(v)] == VertexRole::Rigid;
      allStill = allStill && still[std::size_t(v)];
    }
    if (allStill) {
      ++stillTets_;
      continue;
    }
    if (allRigid) ++bridgingTets_;
    Tet local;
    for (int k = 0; k < 4; ++k) {
      std::int32_t& i = index[std::size_t(t[std::size_t(k)])];
      if (i < 0) {
        i = std::int32_t(solved_.size());
        solved_.push_back(t[std::size_t(k)]);
      }
      local[std::size_t(k)] = i;
    }
    tets.push_back(local);
  }
  solvedTets_ = tets.size();
  solveTets_ = tets;
  std::vector<Eigen::Vector3d> rest;
  std::vector<double> weights;
  stillSolve_.assign(solved_.size(), 0);
  for (std::size_t i = 0; i < solved_.size(); ++i) {
    const auto v = std::size_t(solved_[i]);
    rest.push_back(m.positions[v]);
    stillSolve_[i] = still[v];
    if (mesh_.role[v] == VertexRole::Rigid) {
      constrained_.push_back(std::int32_t(i));
      partConstrained_[std::size_t(mesh_.vertexPart[v])].push_back(std::int32_t(i));
    } else if (still[v]) {
      still_.push_back(std::int32_t(i));
    } else if (mesh_.role[v] == VertexRole::Sliding) {
      sliding_.push_back(std::int32_t(i));
      weights.push_back(options_.slidingWeight);
    }
  }
  constrainedTargets_.resize(constrained_.size());
  slidingTargets_.resize(sliding_.size());
  approachHard_ = still_;
  for (std::size_t c = 0; c < constrained_.size(); ++c)
    if (stillSolve_[std::size_t(constrained_[c])] && options_.holdUnmovedBones) approachHard_.push_back(constrained_[c]);
    else approachSoftBones_.push_back(c);
  if (!tets.empty()) {
    std::vector<std::int32_t> hard = constrained_;
    hard.insert(hard.end(), still_.begin(), still_.end());
    solver_.precompute(rest, tets, hard, sliding_, weights, options_.solve, "articulated transfer mesh");
    // The approach: the moved bones as stiff soft targets beside the
    // sliding ones; the still vertices hard at rest.
    std::vector<std::int32_t> soft = sliding_;
    for (const std::size_t c : approachSoftBones_) soft.push_back(constrained_[c]);
    weights.resize(soft.size(), options_.boneWeight);
    approach_.precompute(rest, tets, approachHard_, soft, weights, options_.solve, "articulated transfer mesh");
  }
  nearPart_.resize(solved_.size());
  nearWeight_.resize(solved_.size());
  for (std::size_t i = 0; i < solved_.size(); ++i) {
    const auto& b = nearest_[std::size_t(solved_[i])];
    nearPart_[i] = {b[0].second, b[1].second};
    const double d0 = b[0].first, d1 = b[1].first;
    // Full weight to the nearest part unless the second is within blendMm
    // of it too; half and half where both are equally near.
    nearWeight_[i] = !std::isfinite(d1) || d1 - d0 >= options_.blendMm ? 1.0 : 0.5 + 0.5 * (d1 - d0) / options_.blendMm;
    // A bone's vertex moves with its own part only.
    if (mesh_.role[std::size_t(solved_[i])] == VertexRole::Rigid) {
      nearPart_[i][0] = mesh_.vertexPart[std::size_t(solved_[i])];
      nearWeight_[i] = 1.0;
    }
  }
}

void ArticulatedPoser::nearestParts() {
  // Dijkstra along the mesh's edges from each part's rigid vertices: per
  // vertex the two nearest parts.
  const std::size_t nv = mesh_.mesh.vertexCount();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  nearest_.assign(nv, {{{kInf, skeleton::Part::None}, {kInf, skeleton::Part::None}}});
  std::vector<double> dist(nv);
  for (int p = 1; p <= kSegmentCount; ++p) {
    std::fill(dist.begin(), dist.end(), kInf);
    for (std::size_t v = 0; v < nv; ++v)
      if (mesh_.role[v] == VertexRole::Rigid && int(mesh_.vertexPart[v]) == p) dist[v] = 0.0;
    edgeDistances(edges_, dist);
    for (std::size_t v = 0; v < nv; ++v) {
      auto& b = nearest_[v];
      const std::pair<double, skeleton::Part> c{dist[v], skeleton::Part(p)};
      if (c.first < b[0].first) {
        b[1] = b[0];
        b[0] = c;
      } else if (c.first < b[1].first) {
        b[1] = c;
      }
    }
  }
}

void ArticulatedPoser::predict(InjectiveSolver& solver, std::span<const Eigen::Isometry3d> from, std::span<const Eigen::Isometry3d> to) {
  PartTransforms step;
  for (int p = 0; p <= kSegmentCount; ++p)
    step[std::size_t(p)] = partMotionAt(to, skeleton::Part(p), 1.0) * partMotionAt(from, skeleton::Part(p), 1.0).inverse();
  const std::vector<Eigen::Vector3d>& current = solver.positions();
  std::vector<Eigen::Vector3d> predicted(current.size());
  for (std::size_t i = 0; i < current.size(); ++i) predicted[i] = blended(i, step, current[i]);
  // As far along as no tet inverts, vertex by vertex: the vertices of a tet
  // the prediction would squeeze go half as far, again until none is (a
  // squeezed tet at the shoulder does not hold back the hand).
  std::vector<double> share(current.size(), 1.0);
  for (std::size_t i = 0; i < current.size(); ++i)
    if (stillSolve_[i]) share[i] = 0.0;
  std::vector<Eigen::Vector3d> trial(current.size());
  std::vector<double> floor = solver.relativeVolumes(current);
  for (double& f : floor) f = std::min(0.05, 0.5 * f);
  // After six halvings such vertices stay where they are (every vertex
  // staying is the current, valid configuration: the rounds end).
  for (int round = 0;; ++round) {
    for (std::size_t i = 0; i < current.size(); ++i) trial[i] = current[i] + share[i] * (predicted[i] - current[i]);
    const std::vector<double> volumes = solver.relativeVolumes(trial);
    bool squeezed = false;
    for (std::size_t t = 0; t < volumes.size(); ++t)
      if (volumes[t] <= floor[t]) {
        squeezed = true;
        for (const std::int32_t v : solveTets_[t]) share[std::size_t(v)] = round < 6 ? 0.5 * share[std::size_t(v)] : 0.0;
      }
    if (!squeezed) {
      solver.setPositions(trial);
      return;
    }
  }
}

std::vector<Eigen::Vector3d> ArticulatedPoser::corrected(const std::vector<Eigen::Vector3d>& current,
                                                        std::span<const Eigen::Isometry3d> motions) const {
  // Per part: the rigid motion that takes its bones from where they are
  // (the best fit of its vertices of the solve) onto its motion.
  PartTransforms correction;
  correction.fill(Eigen::Isometry3d::Identity());
  for (int p = 1; p <= kSegmentCount; ++p) {
    const std::vector<std::int32_t>& owned = partConstrained_[std::size_t(p)];
    if (owned.size() < 3) continue;
    const Eigen::Isometry3d m = std::size_t(p) < motions.size() ? motions[std::size_t(p)] : Eigen::Isometry3d::Identity();
    correction[std::size_t(p)] = rigidFit(
        owned, [&](std::int32_t c) { return current[std::size_t(c)]; },
        [&](std::int32_t c) -> Eigen::Vector3d { return m * mesh_.mesh.positions[std::size_t(solved_[std::size_t(c)])]; });
  }
  std::vector<Eigen::Vector3d> out(current.size());
  for (std::size_t i = 0; i < current.size(); ++i) out[i] = blended(i, correction, current[i]);
  return out;
}

Eigen::Vector3d ArticulatedPoser::blended(std::size_t i, const PartTransforms& transforms, const Eigen::Vector3d& p) const {
  const double w = nearWeight_[i];
  const Eigen::Vector3d a = transforms[std::size_t(nearPart_[i][0])] * p;
  return w >= 1.0 ? a : Eigen::Vector3d(w * a + (1.0 - w) * (transforms[std::size_t(nearPart_[i][1])] * p));
}

void ArticulatedPoser::targets(const InjectiveSolver& solver, std::span<const Eigen::Isometry3d> motions) {
  placeRigidVertices(mesh_, motions, 1.0, positions_);
  for (std::size_t c = 0; c < constrained_.size(); ++c) constrainedTargets_[c] = positions_[std::size_t(solved_[std::size_t(constrained_[c])])];
  // Sliding targets in their bodies' frames: each vertex taken into its
  // body's rest frame by where the owner's bone is now (the rigid motion
  // that best fits the owner's vertices of the solve), put on the body's
  // surface there, and carried to the step's pose by the owner's motion.
  // Along the surface the vertex keeps where the solve put it (it slides);
  // only its distance from the surface is corrected, whether the bones are
  // ahead of the tissue or behind it.
  const std::vector<Eigen::Vector3d>& current = solver.positions();
  const std::vector<Eigen::Vector3d>& rest = mesh_.mesh.positions;
  const PartTransforms now = partFits(solver);
  for (const std::int32_t i : sliding_) {
    const auto v = std::size_t(solved_[std::size_t(i)]);
    const auto b = std::size_t(mesh_.vertexBody[v]);
    const skeleton::Part owner = mesh_.bodies[b].owner;
    positions_[v] = partMotionAt(motions, owner, 1.0) * slideOnBody(mesh_, b, now[std::size_t(owner)].inverse() * current[std::size_t(i)], rest[v]);
  }
  for (std::size_t s = 0; s < sliding_.size(); ++s) slidingTargets_[s] = positions_[std::size_t(solved_[std::size_t(sliding_[s])])];
}

ArticulatedPoser::PartTransforms ArticulatedPoser::partFits(const InjectiveSolver& solver) const {
  const std::vector<Eigen::Vector3d>& current = solver.positions();
  const std::vector<Eigen::Vector3d>& rest = mesh_.mesh.positions;
  PartTransforms fit;
  fit.fill(Eigen::Isometry3d::Identity());
  for (int p = 1; p <= kSegmentCount; ++p) {
    const std::vector<std::int32_t>& owned = partConstrained_[std::size_t(p)];
    if (owned.size() < 3) continue;
    fit[std::size_t(p)] = rigidFit(
        owned, [&](std::int32_t c) { return rest[std::size_t(solved_[std::size_t(c)])]; },
        [&](std::int32_t c) { return current[std::size_t(c)]; });
  }
  return fit;
}

void ArticulatedPoser::placeUnsolved(const InjectiveSolver& solver) {
  const std::vector<Eigen::Vector3d>& rest = mesh_.mesh.positions;
  const PartTransforms fit = partFits(solver);
  std::vector<bool> solved(rest.size(), false);
  for (const std::int32_t v : solved_) solved[std::size_t(v)] = true;
  for (std::size_t v = 0; v < rest.size(); ++v)
    if (!solved[v] && mesh_.role[v] == VertexRole::Rigid) positions_[v] = fit[std::size_t(mesh_.vertexPart[v])] * rest[v];
}

void ArticulatedPoser::gather(const InjectiveSolver& solver) {
  const std::vector<Eigen::Vector3d>& current = solver.positions();
  for (std::size_t i = 0; i < solved_.size(); ++i) positions_[std::size_t(solved_[i])] = current[i];
}

std::vector<double> ArticulatedPoser::boneLag(const InjectiveSolver& solver) const {
  std::vector<double> lag(kSegmentCount + 1, 0.0);
  const std::vector<Eigen::Vector3d>& current = solver.positions();
  for (std::size_t c = 0; c < constrained_.size(); ++c) {
    const auto i = std::size_t(constrained_[c]);
    double& l = lag[std::size_t(mesh_.vertexPart[std::size_t(solved_[i])])];
    l = std::max(l, (current[i] - constrainedTargets_[c]).norm());
  }
  return lag;
}

ArticulatedPoseReport ArticulatedPoser::pose(std::span<const Eigen::Isometry3d> motions) {
  const std::vector<Eigen::Isometry3d> given(motions.begin(), motions.end());
  return pose([&given](double fraction) {
    std::vector<Eigen::Isometry3d> out(given.size());
    for (std::size_t p = 0; p < given.size(); ++p) out[p] = partMotionAt(given, skeleton::Part(p), fraction);
    return out;
  });
}

ArticulatedPoseReport ArticulatedPoser::pose(const MotionPath& path) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Eigen::Isometry3d> motions = path(1.0);
  prepare(motions);
  ArticulatedPoseReport report;
  report.stillVertices = still_.size();
  report.stillTets = stillTets_;
  report.solvedVertices = solved_.size();
  report.solvedTets = solvedTets_;
  report.constrainedVertices = constrained_.size();
  report.slidingVertices = sliding_.size();
  report.bridgingTets = bridgingTets_;
  positions_ = mesh_.mesh.positions;
  // Where the still vertices stay: the approach's hard ones, the last
  // step's after the bones.
  std::vector<Eigen::Vector3d> approachHeld, stillHeld;
  for (const std::int32_t i : approachHard_) approachHeld.push_back(mesh_.mesh.positions[std::size_t(solved_[std::size_t(i)])]);
  for (const std::int32_t i : still_) stillHeld.push_back(mesh_.mesh.positions[std::size_t(solved_[std::size_t(i)])]);
  const auto approachSoft = [&] {
    std::vector<Eigen::Vector3d> soft = slidingTargets_;
    for (const std::size_t c : approachSoftBones_) soft.push_back(constrainedTargets_[c]);
    return soft;
  };
  if (solvedTets_ > 0) {
    // The approach: the pose in steps with the bones as stiff soft targets,
    // so that one squeezed tet slows the bones near it, not every bone.
    approach_.resetToRest();
    const int steps = std::max(1, options_.steps);
    std::vector<Eigen::Isometry3d> previous = path(0.0);
    for (int s = 1; s <= steps; ++s) {
      throwIfCancelled();
      const std::vector<Eigen::Isometry3d> step = s == steps ? motions : path(double(s) / double(steps));
      predict(approach_, previous, step);
      targets(approach_, step);
      previous = step;
      const InjectiveStepReport r = approach_.solveStep(approachHeld, approachSoft());
      report.iterations += r.iterations;
      report.minRelativeVolume = std::min(report.minRelativeVolume, r.minRelativeVolume);
      report.stepMinRelativeVolume.push_back(r.minRelativeVolume);
      const std::vector<double> lag = boneLag(approach_);
      report.stepBoneLagMm.push_back(*std::max_element(lag.begin(), lag.end()));
      ++report.steps;
      if (options_.onStep) {
        gather(approach_);
        placeUnsolved(approach_);
        options_.onStep(s, positions_);
      }
    }
    // At the full pose the bones stiffen (their weight times 10, 100,
    // 1000): they close on their motions as far as the tissue lets them.
    {
      targets(approach_, motions);
      const std::vector<Eigen::Vector3d> soft = approachSoft();
      std::vector<double> scale(soft.size(), 1.0);
      for (int round = 1; round <= options_.stiffeningRounds; ++round) {
        std::fill(scale.begin() + std::ptrdiff_t(slidingTargets_.size()), scale.end(), std::pow(10.0, round));
        approach_.scaleSoftWeights(scale);
        const InjectiveStepReport r = approach_.solveStep(approachHeld, soft);
        report.iterations += r.iterations;
        report.minRelativeVolume = std::min(report.minRelativeVolume, r.minRelativeVolume);
      }
      std::fill(scale.begin(), scale.end(), 1.0);
      approach_.scaleSoftWeights(scale);
    }
    // The bones onto their motions exactly: put there when no tet inverts,
    // else chased from where the approach left them (hard constraints); then
    // the tissue relaxes around them.
    targets(approach_, motions);
    report.segmentLagMm = boneLag(approach_);
    std::vector<Eigen::Vector3d> placed = corrected(approach_.positions(), motions);
    for (std::size_t c = 0; c < constrained_.size(); ++c) placed[std::size_t(constrained_[c])] = constrainedTargets_[c];
    for (std::size_t k = 0; k < still_.size(); ++k) placed[std::size_t(still_[k])] = stillHeld[k];
    const std::vector<double> volumes = solver_.relativeVolumes(placed);
    solver_.setPositions(*std::min_element(volumes.begin(), volumes.end()) > 0.0 ? placed : approach_.positions());
    std::vector<Eigen::Vector3d> hard = constrainedTargets_;
    hard.insert(hard.end(), stillHeld.begin(), stillHeld.end());
    const InjectiveStepReport r = solver_.solveStep(hard, slidingTargets_);
    report.iterations += r.iterations;
    report.minRelativeVolume = std::min(report.minRelativeVolume, r.minRelativeVolume);
    report.stepMinRelativeVolume.push_back(r.minRelativeVolume);
    report.reachedTargets = r.reachedTargets;
    ++report.steps;
    gather(solver_);
  } else {
    report.reachedTargets = true;  // nothing to solve: the bones are placed on their motions below
  }
  placeRigidVertices(mesh_, motions, 1.0, positions_);
  const TetMesh& m = mesh_.mesh;
  for (const Tet& t : m.tets) report.invertedBeforeUntangling += signedVolume(positions_, t) <= 0.0;
  if (report.invertedBeforeUntangling > 0 && solvedTets_ > 0) untangle(motions, report);
  if (options_.contactRounds > 0 && solvedTets_ > 0) resolveContacts(motions, report);
  if (options_.onStep) options_.onStep(report.steps, positions_);
  for (const Tet& t : m.tets) {
    const double volume = signedVolume(positions_, t);
    report.invertedTets += volume <= 0.0;
    if (!rigidWithOneSegment(mesh_, t)) report.finalMinRelativeVolume = std::min(report.finalMinRelativeVolume, volume / signedVolume(m.positions, t));
  }
  std::vector<Eigen::Vector3d> projected = positions_;
  projectSlidingVertices(mesh_, motions, 1.0, projected);
  for (std::size_t v = 0; v < projected.size(); ++v)
    if (mesh_.role[v] == VertexRole::Sliding) report.maxSlidingGapMm = std::max(report.maxSlidingGapMm, (projected[v] - positions_[v]).norm());
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

std::vector<std::uint8_t> ArticulatedPoser::movableVertices() const {
  std::vector<std::uint8_t> movable(mesh_.mesh.vertexCount(), 0);
  for (std::size_t i = 0; i < solved_.size(); ++i) {
    const auto v = std::size_t(solved_[i]);
    movable[v] = mesh_.role[v] != VertexRole::Rigid && !stillSolve_[i];
  }
  return movable;
}

std::vector<double> ArticulatedPoser::distanceToInverted(std::size_t& inverted) const {
  std::vector<double> dist(mesh_.mesh.vertexCount(), std::numeric_limits<double>::infinity());
  inverted = 0;
  for (const Tet& t : mesh_.mesh.tets)
    if (signedVolume(positions_, t) <= 0.0) {
      ++inverted;
      for (const std::int32_t v : t) dist[std::size_t(v)] = 0.0;
    }
  if (inverted > 0) edgeDistances(edges_, dist);
  return dist;
}

std::size_t ArticulatedPoser::freeWithin(std::span<const double> dist, double radius, std::span<const std::uint8_t> movable,
                                         std::span<const Eigen::Vector3d> onBodies, std::vector<std::uint8_t>& free,
                                         std::vector<UntangleAnchor>& anchors) const {
  free.assign(mesh_.mesh.vertexCount(), 0);
  std::size_t moved = 0;
  for (std::size_t v = 0; v < free.size(); ++v) {
    if (!movable[v] || dist[v] > radius) continue;
    free[v] = 1;
    ++moved;
    if (mesh_.role[v] == VertexRole::Sliding) anchors.push_back({std::int32_t(v), onBodies[v], options_.slidingWeight});
  }
  return moved;
}

void ArticulatedPoser::untangle(std::span<const Eigen::Isometry3d> motions, ArticulatedPoseReport& report) {
  const TetMesh& m = mesh_.mesh;
  const std::vector<std::uint8_t> movable = movableVertices();
  std::vector<Eigen::Vector3d> onBodies = positions_;
  projectSlidingVertices(mesh_, motions, 1.0, onBodies);
  const auto start = std::chrono::steady_clock::now();
  for (const double radius : options_.untangleRadiiMm) {
    std::size_t inverted = 0;
    const std::vector<double> dist = distanceToInverted(inverted);
    if (inverted == 0) break;
    std::vector<std::uint8_t> free;
    std::vector<UntangleAnchor> anchors;
    const std::size_t moved = freeWithin(dist, radius, movable, onBodies, free, anchors);
    if (moved == 0) continue;
    untangleTets(m.positions, m.tets, free, anchors, positions_, options_.untangle);
    report.untangleRadiusMm = radius;
    report.untangledVertices = moved;
  }
  report.untangleSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void ArticulatedPoser::resolveContacts(std::span<const Eigen::Isometry3d> motions, ArticulatedPoseReport& report) {
  const TetMesh& m = mesh_.mesh;
  const std::size_t nv = m.vertexCount();
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::uint8_t> movable = movableVertices();
  // Not about a tangle the untangling left: a vertex there lies inside the
  // tissue across because the tets fold, and a pull on it folds them more.
  {
    std::size_t inverted = 0;
    const std::vector<double> toFold = distanceToInverted(inverted);
    for (std::size_t v = 0; v < nv && inverted > 0; ++v) movable[v] = movable[v] && toFold[v] > options_.contactRadiusMm;
  }
  // Candidates: the free tissue (a sliding vertex stays on its body, whose
  // two sides overlap by design where the bones' staircases cross).
  std::vector<std::uint8_t> candidate(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) candidate[v] = movable[v] && mesh_.role[v] == VertexRole::Free;
  // Penetrable: every tet, the articular bodies' too (the tissue across a
  // sliding cut that the turn pressed into the owner's bone end).
  const std::vector<std::uint8_t> penetrable(m.tetCount(), 1);
  std::vector<Eigen::Vector3d> onBodies = positions_;
  projectSlidingVertices(mesh_, motions, 1.0, onBodies);
  UntangleOptions solve = options_.untangle;
  solve.lowestEnergy = true;
  // Per vertex found in some round: where it is held. A vertex drawn out
  // of the tissue across stays held where it got, or the tissue's
  // elasticity presses it back in the next round.
  std::vector<std::pair<std::int32_t, Eigen::Vector3d>> held;
  std::vector<std::int32_t> heldIndex(nv, -1);
  for (int round = 0; round <= options_.contactRounds; ++round) {
    throwIfCancelled();
    const std::vector<Penetration> found = findPenetrations(m.positions, m.tets, positions_, candidate, penetrable, options_.contact);
    // The report counts the vertices through the tissue across; a face's
    // centroid there (ContactOptions::faceCentroids) moves its vertices.
    std::size_t vertices = 0;
    double deepest = 0.0;
    for (const Penetration& p : found)
      if (p.vertex >= 0) {
        ++vertices;
        deepest = std::max(deepest, p.depth);
      }
    if (round == 0) {
      report.penetratingBeforeContact = vertices;
      report.deepestPenetrationBeforeMm = deepest;
    }
    report.penetratingAfterContact = vertices;
    report.deepestPenetrationAfterMm = deepest;
    if (found.empty() || round == options_.contactRounds) break;
    for (auto& [v, target] : held) target = positions_[std::size_t(v)];
    std::vector<double> dist(nv, std::numeric_limits<double>::infinity());
    for (const Penetration& p : found)
      for (const std::int32_t u : p.of)
        if (u >= 0) dist[std::size_t(u)] = 0.0;
    for (const auto& h : held) dist[std::size_t(h.first)] = 0.0;
    edgeDistances(edges_, dist);
    // Per vertex this round: the depth of what moves it (its own
    // penetration before any face's, else the deepest face's).
    std::vector<double> moveDepth(nv, -1.0);
    for (const Penetration& p : found) {
      // Halfway where the crossed boundary moves too: its own vertices,
      // inside this side, are drawn back the other half.
      bool across = true;
      for (const std::int32_t u : p.face) across = across && movable[std::size_t(u)] && dist[std::size_t(u)] <= options_.contactRadiusMm;
      const Eigen::Vector3d shift = ((across ? 0.5 : 1.0) * p.depth + options_.contactMarginMm) * (p.surface - p.at) / p.depth;
      for (const std::int32_t u : p.of) {
        if (u < 0) continue;
        double& depth = moveDepth[std::size_t(u)];
        const double own = p.vertex >= 0 ? std::numeric_limits<double>::infinity() : p.depth;
        if (depth >= own) continue;
        depth = own;
        const Eigen::Vector3d target = positions_[std::size_t(u)] + shift;
        std::int32_t& k = heldIndex[std::size_t(u)];
        if (k < 0) {
          k = std::int32_t(held.size());
          held.emplace_back(u, target);
        } else {
          held[std::size_t(k)].second = target;
        }
      }
    }
    std::vector<std::uint8_t> free;
    std::vector<UntangleAnchor> anchors;
    const std::size_t moved = freeWithin(dist, options_.contactRadiusMm, movable, onBodies, free, anchors);
    for (const auto& [v, target] : held) anchors.push_back({v, target, options_.contactWeight});
    untangleTets(m.positions, m.tets, free, anchors, positions_, solve);
    report.contactVertices = moved;
    ++report.contactRounds;
  }
  report.contactSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int articulatedPoseSteps(std::span<const PoseJoint> angles, const ArticulatedPoseOptions& options) {
  double largest = 0.0;
  for (const PoseJoint& j : angles)
    for (const double d : j.degrees) largest = std::max(largest, std::abs(d));
  const double perTurn = std::ceil(double(std::max(0, options.stepsPerQuarterTurn)) * largest / 90.0 - 1e-9);
  return std::max(options.steps, int(std::min(perTurn, 1000.0)));
}

ArticulatedPoser::MotionPath jointMotionPath(const skeleton::Skeleton& skeleton, const std::vector<skeleton::Joint>& joints,
                                             const std::vector<PoseJoint>& angles, const ArticulatedMesh& mesh) {
  return [&skeleton, joints, angles, &mesh](double fraction) {
    std::vector<PoseJoint> scaled = angles;
    for (PoseJoint& j : scaled)
      for (double& d : j.degrees) d *= fraction;
    return segmentMotions(skeleton::partMotions(joints, scaled), skeleton, mesh);
  };
}

}  // namespace vox
