#include "geometry/deform/articulated_pose.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <queue>

namespace vox {

ArticulatedPoser::ArticulatedPoser(const ArticulatedMesh& mesh, const ArticulatedPoseOptions& options)
    : mesh_(mesh), options_(options), positions_(mesh.mesh.positions) {
  const TetMesh& m = mesh.mesh;
  std::vector<std::int32_t> index(m.vertexCount(), -1);
  std::vector<Tet> tets;
  for (const Tet& t : m.tets) {
    bool oneRigidPart = true, allRigid = true;
    for (const std::int32_t v : t) {
      allRigid = allRigid && mesh.role[std::size_t(v)] == VertexRole::Rigid;
      oneRigidPart = oneRigidPart && mesh.role[std::size_t(v)] == VertexRole::Rigid && mesh.vertexPart[std::size_t(v)] == mesh.vertexPart[std::size_t(t[0])];
    }
    if (oneRigidPart) continue;
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
  std::vector<Eigen::Vector3d> rest;
  std::vector<double> weights;
  for (std::size_t i = 0; i < solved_.size(); ++i) {
    const auto v = std::size_t(solved_[i]);
    rest.push_back(m.positions[v]);
    if (mesh.role[v] == VertexRole::Rigid) constrained_.push_back(std::int32_t(i));
    if (mesh.role[v] == VertexRole::Sliding) {
      sliding_.push_back(std::int32_t(i));
      weights.push_back(options.slidingWeight);
    }
  }
  constrainedTargets_.resize(constrained_.size());
  slidingTargets_.resize(sliding_.size());
  if (!tets.empty()) {
    solver_.precompute(rest, tets, constrained_, sliding_, weights, options.solve, "articulated transfer mesh");
    // The approach: the bones as stiff soft targets beside the sliding ones.
    std::vector<std::int32_t> soft = sliding_;
    soft.insert(soft.end(), constrained_.begin(), constrained_.end());
    weights.resize(soft.size(), options.boneWeight);
    approach_.precompute(rest, tets, {}, soft, weights, options.solve, "articulated transfer mesh");
  }
  nearestParts();
}

void ArticulatedPoser::nearestParts() {
  // Dijkstra along the mesh's edges from each part's rigid vertices: per
  // vertex the two nearest parts.
  const TetMesh& m = mesh_.mesh;
  const std::size_t nv = m.vertexCount();
  std::vector<std::vector<std::pair<std::int32_t, double>>> edges(nv);
  for (const Tet& t : m.tets)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const std::int32_t a = t[std::size_t(i)], b = t[std::size_t(j)];
        const double l = (m.positions[std::size_t(a)] - m.positions[std::size_t(b)]).norm();
        edges[std::size_t(a)].emplace_back(b, l);
        edges[std::size_t(b)].emplace_back(a, l);
      }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<std::array<std::pair<double, skeleton::Part>, 2>> best(nv, {{{kInf, skeleton::Part::None}, {kInf, skeleton::Part::None}}});
  std::vector<double> dist(nv);
  using Item = std::pair<double, std::int32_t>;
  for (int p = 1; p <= skeleton::kPartCount; ++p) {
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    std::fill(dist.begin(), dist.end(), kInf);
    for (std::size_t v = 0; v < nv; ++v)
      if (mesh_.role[v] == VertexRole::Rigid && int(mesh_.vertexPart[v]) == p) {
        dist[v] = 0.0;
        queue.emplace(0.0, std::int32_t(v));
      }
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
    for (std::size_t v = 0; v < nv; ++v) {
      auto& b = best[v];
      const std::pair<double, skeleton::Part> c{dist[v], skeleton::Part(p)};
      if (c.first < b[0].first) {
        b[1] = b[0];
        b[0] = c;
      } else if (c.first < b[1].first) {
        b[1] = c;
      }
    }
  }
  nearPart_.resize(solved_.size());
  nearWeight_.resize(solved_.size());
  for (std::size_t i = 0; i < solved_.size(); ++i) {
    const auto& b = best[std::size_t(solved_[i])];
    nearPart_[i] = {b[0].second, b[1].second};
    const double d0 = b[0].first, d1 = b[1].first;
    // Full weight to the nearest part unless the second is within blendMm
    // of it too; half and half where both are equally near.
    nearWeight_[i] = !std::isfinite(d1) || d1 - d0 >= options_.blendMm ? 1.0 : 0.5 + 0.5 * (d1 - d0) / options_.blendMm;
  }
}

void ArticulatedPoser::predict(InjectiveSolver& solver, std::span<const Eigen::Isometry3d> motions, double from, double to) {
  std::array<Eigen::Isometry3d, skeleton::kPartCount + 1> step;
  for (int p = 0; p <= skeleton::kPartCount; ++p) {
    const Eigen::Isometry3d m = std::size_t(p) < motions.size() ? motions[std::size_t(p)] : Eigen::Isometry3d::Identity();
    step[std::size_t(p)] = screwInterpolate(m, to) * screwInterpolate(m, from).inverse();
  }
  const std::vector<Eigen::Vector3d>& current = solver.positions();
  std::vector<Eigen::Vector3d> predicted(current.size());
  for (std::size_t i = 0; i < current.size(); ++i) {
    const double w = nearWeight_[i];
    const Eigen::Vector3d a = step[std::size_t(nearPart_[i][0])] * current[i];
    predicted[i] = w >= 1.0 ? a : Eigen::Vector3d(w * a + (1.0 - w) * (step[std::size_t(nearPart_[i][1])] * current[i]));
  }
  // As far along as no tet inverts (halving from the whole way).
  std::vector<Eigen::Vector3d> trial(current.size());
  for (double t = 1.0; t > 1.0 / 64.0; t *= 0.5) {
    for (std::size_t i = 0; i < current.size(); ++i) trial[i] = current[i] + t * (predicted[i] - current[i]);
    const std::vector<double> volumes = solver.relativeVolumes(trial);
    if (*std::min_element(volumes.begin(), volumes.end()) > 0.05) {
      solver.setPositions(trial);
      return;
    }
  }
}

void ArticulatedPoser::targets(const InjectiveSolver& solver, std::span<const Eigen::Isometry3d> motions, double fraction) {
  placeRigidVertices(mesh_, motions, fraction, positions_);
  for (std::size_t c = 0; c < constrained_.size(); ++c) constrainedTargets_[c] = positions_[std::size_t(solved_[std::size_t(constrained_[c])])];
  // Sliding targets: where the current positions project onto the bodies
  // moved by this step.
  const std::vector<Eigen::Vector3d>& current = solver.positions();
  for (std::size_t s = 0; s < sliding_.size(); ++s) positions_[std::size_t(solved_[std::size_t(sliding_[s])])] = current[std::size_t(sliding_[s])];
  projectSlidingVertices(mesh_, motions, fraction, positions_);
  for (std::size_t s = 0; s < sliding_.size(); ++s) slidingTargets_[s] = positions_[std::size_t(solved_[std::size_t(sliding_[s])])];
}

void ArticulatedPoser::gather(const InjectiveSolver& solver) {
  const std::vector<Eigen::Vector3d>& current = solver.positions();
  for (std::size_t i = 0; i < solved_.size(); ++i) positions_[std::size_t(solved_[i])] = current[i];
}

ArticulatedPoseReport ArticulatedPoser::pose(std::span<const Eigen::Isometry3d> motions) {
  const auto start = std::chrono::steady_clock::now();
  ArticulatedPoseReport report;
  report.solvedVertices = solved_.size();
  report.solvedTets = solvedTets_;
  report.constrainedVertices = constrained_.size();
  report.slidingVertices = sliding_.size();
  report.bridgingTets = bridgingTets_;
  positions_ = mesh_.mesh.positions;
  if (solvedTets_ > 0) {
    // The approach: the pose in steps with the bones as stiff soft targets,
    // so that one squeezed tet slows the bones near it, not every bone.
    approach_.resetToRest();
    const int steps = std::max(1, options_.steps);
    for (int s = 1; s <= steps; ++s) {
      const double fraction = double(s) / double(steps);
      predict(approach_, motions, double(s - 1) / double(steps), fraction);
      targets(approach_, motions, fraction);
      std::vector<Eigen::Vector3d> soft = slidingTargets_;
      soft.insert(soft.end(), constrainedTargets_.begin(), constrainedTargets_.end());
      const InjectiveStepReport r = approach_.solveStep({}, soft);
      report.iterations += r.iterations;
      report.minRelativeVolume = std::min(report.minRelativeVolume, r.minRelativeVolume);
      report.stepMinRelativeVolume.push_back(r.minRelativeVolume);
      ++report.steps;
    }
    // The bones onto their motions exactly: put there when no tet inverts,
    // else chased from where the approach left them (hard constraints); then
    // the tissue relaxes around them.
    targets(approach_, motions, 1.0);
    std::vector<Eigen::Vector3d> placed = approach_.positions();
    for (std::size_t c = 0; c < constrained_.size(); ++c) placed[std::size_t(constrained_[c])] = constrainedTargets_[c];
    const std::vector<double> volumes = solver_.relativeVolumes(placed);
    solver_.setPositions(*std::min_element(volumes.begin(), volumes.end()) > 0.0 ? placed : approach_.positions());
    const InjectiveStepReport r = solver_.solveStep(constrainedTargets_, slidingTargets_);
    report.iterations += r.iterations;
    report.minRelativeVolume = std::min(report.minRelativeVolume, r.minRelativeVolume);
    report.stepMinRelativeVolume.push_back(r.minRelativeVolume);
    report.reachedTargets = r.reachedTargets;
    ++report.steps;
    gather(solver_);
  }
  placeRigidVertices(mesh_, motions, 1.0, positions_);
  const TetMesh& m = mesh_.mesh;
  for (const Tet& t : m.tets) report.invertedTets += signedVolume(positions_, t) <= 0.0;
  std::vector<Eigen::Vector3d> projected = positions_;
  projectSlidingVertices(mesh_, motions, 1.0, projected);
  for (std::size_t v = 0; v < projected.size(); ++v)
    if (mesh_.role[v] == VertexRole::Sliding) report.maxSlidingGapMm = std::max(report.maxSlidingGapMm, (projected[v] - positions_[v]).norm());
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace vox
