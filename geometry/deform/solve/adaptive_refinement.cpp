#include "geometry/deform/solve/adaptive_refinement.h"

#include "geometry/cancellation.h"
#include "geometry/deform/solve/deformation_metrics.h"
#include "geometry/error.h"
#include "geometry/progress.h"

#include <algorithm>
#include <chrono>
#include <compare>
#include <numeric>

namespace vox {

namespace {

// A marked tet is bisected this many times in a round: three bisections of
// a tet shrink it about as one regular 1-to-8 subdivision would.
constexpr int kBisectionsPerRound = 3;
// A round bisects in at most this many conflict-free passes (in one pass no
// tet holds two split edges; a marked tet whose longest edge is not the
// longest of a tet around it waits for that tet's split, a pass each);
// tets still due after them are measured again in the next round.
constexpr int kPassesPerRound = 16 * kBisectionsPerRound;

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

// The tets of each vertex, ascending (compressed rows).
struct VertexTets {
  std::vector<std::int64_t> offsets;  // #V + 1
  std::vector<std::int32_t> tets;
};

VertexTets vertexTets(const TetMesh& mesh) {
  VertexTets out;
  out.offsets.assign(mesh.vertexCount() + 1, 0);
  for (const Tet& t : mesh.tets)
    for (const std::int32_t v : t) ++out.offsets[std::size_t(v) + 1];
  std::partial_sum(out.offsets.begin(), out.offsets.end(), out.offsets.begin());
  out.tets.resize(std::size_t(out.offsets.back()));
  std::vector<std::int64_t> fill(out.offsets.begin(), out.offsets.end() - 1);
  for (std::size_t t = 0; t < mesh.tetCount(); ++t)
    for (const std::int32_t v : mesh.tets[t]) out.tets[std::size_t(fill[std::size_t(v)]++)] = std::int32_t(t);
  return out;
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
// which bounds how far the children's shapes fall from their ancestors'.
// Splitting an edge that is not the longest of a tet around it makes
// slivers there over a few rounds (children with a long edge across a short
// height), and on a sliver the basis change B_t of a smooth map is
// ill-conditioned: midpoints that Green coordinates put a few per cent of
// an edge off their tet's affine map stretch a sliver far beyond what the
// deformation does (on the stick figure's separated arm, to more than twice
// the unrefined TM's largest stretch). `around` receives the tets on the
// terminal edge.
TetEdge terminalEdge(const TetMesh& mesh, const VertexTets& incident, std::int32_t t, std::vector<std::int32_t>& around) {
  TetEdge edge = longestEdge(mesh, mesh.tets[std::size_t(t)]);
  for (;;) {
    around.clear();
    TetEdge next = edge;
    EdgeRank nextRank = edgeRank(mesh, edge[0], edge[1]);
    for (std::int64_t k = incident.offsets[std::size_t(edge[0])]; k < incident.offsets[std::size_t(edge[0]) + 1]; ++k) {
      const std::int32_t u = incident.tets[std::size_t(k)];
      const Tet& tet = mesh.tets[std::size_t(u)];
      if (std::find(tet.begin(), tet.end(), edge[1]) == tet.end()) continue;
      around.push_back(u);
      const TetEdge longest = longestEdge(mesh, tet);
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
  // Per tet: bisections still due, and the e_t of the marked tet it comes from.
  std::vector<std::int8_t> due(mesh.tetCount(), 0);
  std::vector<double> priority(mesh.tetCount(), 0.0);
  for (std::size_t t = 0; t < mesh.tetCount(); ++t)
    if (tetError[t] > threshold && hasPlacedEdge(mesh.tets[t], placed)) {
      due[t] = kBisectionsPerRound;
      priority[t] = tetError[t];
    }
  std::vector<std::int32_t> order, around;
  for (int pass = 0; pass < kPassesPerRound; ++pass) {
    throwIfCancelled();
    order.clear();
    for (std::size_t t = 0; t < mesh.tetCount(); ++t)
      if (due[t] > 0) order.push_back(std::int32_t(t));
    if (order.empty()) break;
    std::stable_sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) { return priority[std::size_t(a)] > priority[std::size_t(b)]; });
    const VertexTets incident = vertexTets(mesh);
    std::vector<std::uint8_t> claimed(mesh.tetCount(), 0);
    std::vector<TetEdge> edges;
    std::int64_t tets = std::int64_t(mesh.tetCount());
    for (const std::int32_t t : order) {
      if (claimed[std::size_t(t)]) continue;
      const TetEdge e = terminalEdge(mesh, incident, t, around);
      if (std::any_of(around.begin(), around.end(), [&](std::int32_t u) { return claimed[std::size_t(u)] != 0; })) continue;
      if (tets + std::int64_t(around.size()) > maxTets) {
        out.budgetReached = true;
        due[std::size_t(t)] = 0;
        continue;
      }
      for (const std::int32_t u : around) claimed[std::size_t(u)] = 1;
      tets += std::int64_t(around.size());
      edges.push_back(e);
    }
    if (edges.empty()) break;
    const std::vector<std::int32_t> splitFrom = bisectEdges(mesh, edges);
    for (std::size_t t = 0; t < claimed.size(); ++t)
      if (claimed[t] && due[t] > 0) --due[t];
    for (const std::int32_t t : splitFrom) {
      due.push_back(due[std::size_t(t)]);
      priority.push_back(priority[std::size_t(t)]);
    }
    for (const TetEdge& e : edges) {
      placed.push_back(placed[std::size_t(e[0])] && placed[std::size_t(e[1])]);
      out.parents.push_back(e);
    }
    // A child that lost its placed edge cannot gain from more splits.
    for (std::size_t t = 0; t < mesh.tetCount(); ++t)
      if (due[t] > 0 && !hasPlacedEdge(mesh.tets[t], placed)) due[t] = 0;
  }
  return out;
}

}  // namespace

GridError gridDeformationError(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed, const GridGeometry& geometry,
                               const VertexFieldInterpolation& interpolate) {
  return measureError(rest, deformed, geometry, interpolate).grid;
}

std::vector<std::int32_t> bisectEdges(TetMesh& mesh, std::span<const TetEdge> edges) {
  const std::size_t nv = mesh.vertexCount(), nt = mesh.tetCount();
  std::vector<std::int32_t> splitFrom;
  std::vector<std::pair<std::uint64_t, std::int32_t>> keys;
  keys.reserve(edges.size());
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const TetEdge& e = edges[k];
    if (e[0] < 0 || e[1] < 0 || std::size_t(e[0]) >= nv || std::size_t(e[1]) >= nv || e[0] == e[1])
      throw RuntimeFailure("bisectEdges: edge " + std::to_string(k) + " is not an edge of the mesh's vertices");
    keys.emplace_back(edgeKey(e[0], e[1]), std::int32_t(k));
  }
  std::sort(keys.begin(), keys.end());
  // Only a tet with two ends of split edges can hold one: the rest are
  // passed over without a search.
  std::vector<std::uint8_t> end(nv, 0);
  for (const TetEdge& e : edges) end[std::size_t(e[0])] = end[std::size_t(e[1])] = 1;
  for (const TetEdge& e : edges) mesh.positions.push_back(0.5 * (mesh.positions[std::size_t(e[0])] + mesh.positions[std::size_t(e[1])]));
  for (std::size_t t = 0; t < nt; ++t) {
    Tet tet = mesh.tets[t];
    if (end[std::size_t(tet[0])] + end[std::size_t(tet[1])] + end[std::size_t(tet[2])] + end[std::size_t(tet[3])] < 2) continue;
    int split = -1, at = -1, other = -1;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const std::uint64_t key = edgeKey(tet[std::size_t(i)], tet[std::size_t(j)]);
        const auto it = std::lower_bound(keys.begin(), keys.end(), std::make_pair(key, std::int32_t(0)));
        if (it == keys.end() || it->first != key) continue;
        if (split >= 0) throw RuntimeFailure("bisectEdges: tet " + std::to_string(t) + " holds two of the edges");
        split = it->second;
        at = i;
        other = j;
      }
    if (split < 0) continue;
    const std::int32_t midpoint = std::int32_t(nv) + split;
    Tet second = tet;
    second[std::size_t(at)] = midpoint;
    tet[std::size_t(other)] = midpoint;
    mesh.tets[t] = tet;
    mesh.tets.push_back(second);
    mesh.labels.push_back(mesh.labels[t]);
    splitFrom.push_back(std::int32_t(t));
  }
  return splitFrom;
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
