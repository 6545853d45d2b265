#include "geometry/deform/solve/adaptive_refinement.h"

#include "geometry/cancellation.h"
#include "geometry/deform/solve/deformation_metrics.h"
#include "geometry/error.h"
#include "geometry/progress.h"

#include <algorithm>
#include <chrono>
#include <compare>

namespace vox {

namespace {

// A marked tet is bisected this many times in a round: three bisections of
// a tet shrink it about as one regular 1-to-8 subdivision would.
constexpr int kBisectionsPerRound = 3;

// e_t of every tet and the grid error of the vertex errors.
struct MeasuredError {
  std::vector<double> tetError;
  GridError grid;
};

MeasuredError measureError(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed, const GridGeometry& geometry,
                           const VertexFieldInterpolation& interpolate) {
  MeasuredError out;
  out.tetError = tetDeformationError(rest, deformed);
  const std::vector<double> vertexError = vertexDeformationError(rest, out.tetError);
  GridError& grid = out.grid;
  grid.field = interpolate(rest, vertexError, geometry, -1.0f);
  double sum = 0.0;
  for (const float e : grid.field.values)
    if (e >= 0.0f) {
      sum += e;
      grid.max = std::max(grid.max, double(e));
      ++grid.coveredVoxels;
    }
  grid.mean = grid.coveredVoxels > 0 ? sum / double(grid.coveredVoxels) : 0.0;
  return out;
}

std::uint64_t edgeKey(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

// Rest edges ordered by length, ties by their vertex pair: a strict order,
// so that a walk to ever longer edges ends, and the same edge for every tet
// that holds it.
struct EdgeRank {
  double squaredLength;
  std::uint64_t key;
  auto operator<=>(const EdgeRank&) const = default;
};

EdgeRank edgeRank(const TetMesh& mesh, std::int32_t a, std::int32_t b) {
  return {(mesh.positions[std::size_t(a)] - mesh.positions[std::size_t(b)]).squaredNorm(), edgeKey(a, b)};
}

TetEdge longestEdge(const TetMesh& mesh, const Tet& tet) {
  TetEdge best{tet[0], tet[1]};
  EdgeRank bestRank = edgeRank(mesh, tet[0], tet[1]);
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      if (const EdgeRank r = edgeRank(mesh, tet[std::size_t(i)], tet[std::size_t(j)]); r > bestRank) {
        bestRank = r;
        best = {tet[std::size_t(i)], tet[std::size_t(j)]};
      }
  return best;
}

bool hasPlacedEdge(const Tet& tet, const std::vector<std::uint8_t>& placed) {
  int count = 0;
  for (const std::int32_t v : tet) count += placed[std::size_t(v)];
  return count >= 2;
}

// The terminal edge of the longest-edge propagation path from tet t
// (Rivara): t's longest edge if it is the longest edge of every tet around
// it, else the path from the tet around it with the longest edge. Bisecting
// the terminal edge splits every tet around it by its own longest edge,
// which keeps the children's shapes close to their ancestors' (on the Kuhn
// tets of a voxel mesh, in a few classes of similar tets). Splitting an edge
// that is not the longest of a tet around it makes slivers there within a
// round (children with a long edge across a short height), and on a sliver the basis change B_t of a smooth map is
// ill-conditioned: midpoints that Green coordinates put a few per cent of
// an edge off their tet's affine map stretch a sliver far beyond what the
// deformation does (on the stick figure's separated arm, to more than twice
// the unrefined TM's largest stretch).
TetEdge terminalEdge(const TetMesh& mesh, EdgeBisection& bisection, std::int32_t t) {
  TetEdge edge = longestEdge(mesh, mesh.tets[std::size_t(t)]);
  for (;;) {
    TetEdge next = edge;
    EdgeRank nextRank = edgeRank(mesh, edge[0], edge[1]);
    for (const std::int32_t u : bisection.tetsAround(edge)) {
      const TetEdge longest = longestEdge(mesh, mesh.tets[std::size_t(u)]);
      if (const EdgeRank r = edgeRank(mesh, longest[0], longest[1]); r > nextRank) {
        nextRank = r;
        next = longest;
      }
    }
    if (next == edge) return edge;
    edge = next;
  }
}

// One round's splits of `mesh`: the tets with e_t above `threshold` are
// bisected kBisectionsPerRound times, most distorted first, each by its
// longest edge after the longest-edge propagation path that keeps the
// shapes (terminalEdge). A tet with fewer than two vertices the deformation
// places is not marked: its midpoints could only lie on their edges'
// images, which changes no B_t. Returns the split edges in the order of
// their midpoints.
struct RoundSplits {
  std::vector<TetEdge> parents;
  bool budgetReached = false;
};

RoundSplits splitMarkedTets(TetMesh& mesh, std::vector<std::uint8_t> placed, std::span<const double> tetError,
                            double threshold, std::int64_t maxTets) {
  RoundSplits out;
  // Per tet: bisections still due. The marked tets, most distorted first,
  // then the children that still owe bisections, in the order they appear.
  std::vector<std::int8_t> due(mesh.tetCount(), 0);
  std::vector<std::int32_t> queue;
  for (std::size_t t = 0; t < mesh.tetCount(); ++t)
    if (tetError[t] > threshold && hasPlacedEdge(mesh.tets[t], placed)) {
      due[t] = kBisectionsPerRound;
      queue.push_back(std::int32_t(t));
    }
  std::stable_sort(queue.begin(), queue.end(), [&](std::int32_t a, std::int32_t b) { return tetError[std::size_t(a)] > tetError[std::size_t(b)]; });
  EdgeBisection bisection(mesh);
  std::vector<std::int32_t> around;
  for (std::size_t k = 0; k < queue.size(); ++k) {
    const std::int32_t t = queue[k];
    while (due[std::size_t(t)] > 0) {
      if (out.parents.size() % 1024 == 0) throwIfCancelled();
      // A child that lost its placed edge cannot gain from more splits.
      if (!hasPlacedEdge(mesh.tets[std::size_t(t)], placed)) {
        due[std::size_t(t)] = 0;
        break;
      }
      const TetEdge e = terminalEdge(mesh, bisection, t);
      around = bisection.tetsAround(e);
      if (std::int64_t(mesh.tetCount() + around.size()) > maxTets) {
        out.budgetReached = true;
        due[std::size_t(t)] = 0;
        break;
      }
      const std::size_t first = mesh.tetCount();
      bisection.bisect(e);
      for (std::size_t i = 0; i < around.size(); ++i) {
        // Both halves of a split tet owe what it still owed (read before
        // the push, which may move `due`).
        std::int8_t& parent = due[std::size_t(around[i])];
        if (parent > 0) --parent;
        const std::int8_t d = parent;
        due.push_back(d);
        if (d > 0) queue.push_back(std::int32_t(first + i));
      }
      placed.push_back(placed[std::size_t(e[0])] && placed[std::size_t(e[1])]);
      out.parents.push_back(e);
    }
  }
  return out;
}

}  // namespace

GridError gridDeformationError(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed, const GridGeometry& geometry,
                               const VertexFieldInterpolation& interpolate) {
  return measureError(rest, deformed, geometry, interpolate).grid;
}

EdgeBisection::EdgeBisection(TetMesh& mesh) : mesh_(mesh), incident_(mesh.vertexCount()) {
  for (std::size_t t = 0; t < mesh.tetCount(); ++t)
    for (const std::int32_t v : mesh.tets[t]) incident_[std::size_t(v)].push_back(std::int32_t(t));
}

const std::vector<std::int32_t>& EdgeBisection::tetsAround(TetEdge edge) {
  around_.clear();
  if (edge[0] < 0 || std::size_t(edge[0]) >= incident_.size() || edge[0] == edge[1]) return around_;
  for (const std::int32_t u : incident_[std::size_t(edge[0])]) {
    const Tet& tet = mesh_.tets[std::size_t(u)];
    if (std::find(tet.begin(), tet.end(), edge[1]) != tet.end()) around_.push_back(u);
  }
  std::sort(around_.begin(), around_.end());
  return around_;
}

std::size_t EdgeBisection::bisect(TetEdge edge) {
  const std::vector<std::int32_t> around = tetsAround(edge);
  if (around.empty())
    throw RuntimeFailure("EdgeBisection: vertices " + std::to_string(edge[0]) + " and " + std::to_string(edge[1]) + " are no edge of the mesh");
  const auto midpoint = std::int32_t(mesh_.vertexCount());
  mesh_.positions.push_back(0.5 * (mesh_.positions[std::size_t(edge[0])] + mesh_.positions[std::size_t(edge[1])]));
  incident_.emplace_back();
  for (const std::int32_t u : around) {
    Tet& first = mesh_.tets[std::size_t(u)];
    Tet second = first;
    for (std::size_t i = 0; i < 4; ++i) {
      if (first[i] == edge[1]) first[i] = midpoint;
      if (second[i] == edge[0]) second[i] = midpoint;
    }
    const auto appended = std::int32_t(mesh_.tetCount());
    mesh_.tets.push_back(second);
    mesh_.labels.push_back(mesh_.labels[std::size_t(u)]);
    // The first child holds a, the midpoint and the two others; the second
    // replaces the parent at b and joins the midpoint and the two others.
    std::vector<std::int32_t>& atB = incident_[std::size_t(edge[1])];
    *std::find(atB.begin(), atB.end(), u) = appended;
    incident_.back().push_back(u);
    incident_.back().push_back(appended);
    for (const std::int32_t v : second)
      if (v != midpoint && v != edge[1]) incident_[std::size_t(v)].push_back(appended);
  }
  return around.size();
}

RefinementResult refineTransferMesh(const RefinementSubject& subject, const GridGeometry& geometry,
                                    const VertexFieldInterpolation& interpolate, const RefinementOptions& options) {
  using Clock = std::chrono::steady_clock;
  RefinementResult result;
  // The TM of the current round, and the best one measured (the initial TM
  // stays the subject's until another is better).
  struct State {
    TetMesh mesh;
    std::vector<Eigen::Vector3d> deformed;
    std::vector<std::uint8_t> placed;
  };
  State current, best;
  bool refined = false;
  auto measure = [&](const TetMesh& rest, std::span<const Eigen::Vector3d> deformed, double seconds) {
    MeasuredError error = measureError(rest, deformed, geometry, interpolate);
    result.steps.push_back({.vertices = rest.vertexCount(),
                            .tets = rest.tetCount(),
                            .meanError = error.grid.mean,
                            .maxError = error.grid.max,
                            .seconds = seconds});
    return error;
  };
  reportProgress("refinement", 0.0);
  MeasuredError error = measure(subject.restMesh(), subject.deformedPositions(), 0.0);
  for (int iteration = 0;; ++iteration) {
    const RefinementStep& step = result.steps.back();
    if (step.maxError <= options.negligibleError) {
      result.stopReason = "negligible error";
      break;
    }
    if (step.maxError <= options.uniformRatio * step.meanError) {
      result.stopReason = "uniform error";
      break;
    }
    if (result.steps.size() >= 2 && step.maxError > (1.0 - options.minImprovement) * result.steps[result.steps.size() - 2].maxError) {
      result.stopReason = "stalled";
      break;
    }
    if (iteration >= options.maxIterations) {
      result.stopReason = "iterations";
      break;
    }
    const auto start = Clock::now();
    if (iteration == 0) current = {subject.restMesh(), subject.deformedPositions(), subject.placedByDeformation()};
    const RoundSplits splits = splitMarkedTets(current.mesh, current.placed, error.tetError, options.uniformRatio * step.meanError,
                                               options.maxTets);
    if (splits.parents.empty()) {
      result.stopReason = splits.budgetReached ? "tet budget" : "unsplittable";
      break;
    }
    result.steps.back().splitEdges = splits.parents.size();
    subject.placeMidpoints(current.mesh, splits.parents, current.deformed, current.placed);
    error = measure(current.mesh, current.deformed, std::chrono::duration<double>(Clock::now() - start).count());
    if (result.steps.back().maxError < result.steps[result.kept].maxError) {
      result.kept = result.steps.size() - 1;
      best = current;
      refined = true;
    }
    reportProgress("refinement", double(iteration + 1) / double(std::max(options.maxIterations, 1)));
  }
  if (refined) subject.adopt(std::move(best.mesh), std::move(best.deformed), std::move(best.placed));
  reportProgress("refinement", 1.0);
  return result;
}

}  // namespace vox
