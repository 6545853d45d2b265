#include "geometry/deform/solve/propagation.h"

#include "geometry/deform/solve/deformation_metrics.h"
#include "geometry/error.h"

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>

namespace vox {

namespace {

constexpr int kTetEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

Eigen::Vector3d tetCentroid(const std::vector<Eigen::Vector3d>& p, const Tet& t) {
  return 0.25 * (p[std::size_t(t[0])] + p[std::size_t(t[1])] + p[std::size_t(t[2])] + p[std::size_t(t[3])]);
}

// Index of the point of `candidates` (by position) nearest to q.
template <class PositionOf>
std::int32_t nearestOf(const std::vector<std::int32_t>& candidates, const Eigen::Vector3d& q, PositionOf&& position) {
  std::int32_t best = -1;
  double bestDistance = std::numeric_limits<double>::infinity();
  for (std::int32_t c : candidates) {
    const double d = (position(c) - q).squaredNorm();
    if (d < bestDistance) {
      bestDistance = d;
      best = c;
    }
  }
  return best;
}

// Splits `members` (a flag per element) into connected groups through
// `neighbours(e, visit)`. Calls group(list) for each group.
template <class Neighbours, class Group>
void connectedGroups(std::size_t count, const std::vector<std::uint8_t>& member, Neighbours&& neighbours, Group&& group) {
  std::vector<std::uint8_t> seen(count, 0);
  std::vector<std::int32_t> list, stack;
  for (std::size_t s = 0; s < count; ++s) {
    if (!member[s] || seen[s]) continue;
    list.clear();
    seen[s] = 1;
    stack.push_back(std::int32_t(s));
    while (!stack.empty()) {
      const std::int32_t e = stack.back();
      stack.pop_back();
      list.push_back(e);
      neighbours(e, [&](std::int32_t n) {
        if (member[std::size_t(n)] && !seen[std::size_t(n)]) {
          seen[std::size_t(n)] = 1;
          stack.push_back(n);
        }
      });
    }
    group(list);
  }
}

}  // namespace

void RigidityPropagation::precompute(const TetMesh& rest, std::span<const std::uint8_t> inside, const std::string& source) {
  rest.validate(source);
  if (inside.size() != rest.vertexCount())
    throw InputError(source, "inside-cage mask has " + std::to_string(inside.size()) + " entries for " +
                                 std::to_string(rest.vertexCount()) + " vertices");
  vertexCount_ = rest.vertexCount();
  rest_ = rest.positions;
  tets_ = rest.tets;
  diagnostics_ = {};
  const std::size_t nt = tets_.size();
  const std::vector<double> volume = tetVolumes(rest);

  std::vector<std::uint8_t> inTc(nt, 0), inTu(nt, 0);
  std::vector<std::int32_t> tcTets;
  for (std::size_t t = 0; t < nt; ++t) {
    if (!(signedVolume(rest_, tets_[t]) > 0))
      throw InputError(source, "tet " + std::to_string(t) + " is inverted or degenerate (volume " +
                                   std::to_string(signedVolume(rest_, tets_[t])) + ")");
    bool all = true;
    for (std::int32_t v : tets_[t]) all = all && inside[std::size_t(v)];
    (all ? inTc : inTu)[t] = 1;
    if (all) tcTets.push_back(std::int32_t(t));
  }
  for (std::size_t v = 0; v < vertexCount_; ++v) (inside[v] ? diagnostics_.insideVertexCount : diagnostics_.outsideVertexCount)++;
  diagnostics_.constrainedTetCount = tcTets.size();

  tuTets_.clear();
  tuSlot_.clear();
  knownSource_.clear();
  knownEdgeInv_.clear();
  unknownVertices_.clear();
  pinnedVertices_.clear();
  edgeTerms_.clear();
  couplings_.clear();
  tuBasis_.clear();
  vertexSlot_.assign(vertexCount_, -1);
  if (diagnostics_.outsideVertexCount == 0) return;
  if (tcTets.empty())
    throw InputError(source, "no tet lies entirely inside the cage: the " + std::to_string(diagnostics_.outsideVertexCount) +
                                 " vertices outside it have nothing to follow");

  auto centroidOfTet = [&](std::int32_t t) { return tetCentroid(rest_, tets_[std::size_t(t)]); };
  const auto neighbors = faceNeighbors(rest, source);

  // Tets around each vertex, for the neighbourhoods of unconstrained groups.
  const VertexTets around = vertexTets(tets_, vertexCount_);

  // ---- Step 1 (eq. 4.3): unknown B_t of T_u tets.
  std::vector<std::int32_t> tuIndex(nt, -1);
  for (std::size_t t = 0; t < nt; ++t)
    if (inTu[t]) {
      tuIndex[t] = std::int32_t(tuTets_.size());
      tuTets_.push_back(std::int32_t(t));
    }
  tuSlot_.assign(tuTets_.size(), 0);
  // T_u groups through faces; pin one tet of each group with no T_c neighbour.
  std::vector<std::int32_t> knownSlotOfTet(nt, -1);
  auto knownSlot = [&](std::int32_t tet, std::int32_t sourceTet) {
    const auto s = std::int32_t(knownSource_.size());
    knownSource_.push_back(sourceTet);
    knownSlotOfTet[std::size_t(tet)] = s;
    return s;
  };
  connectedGroups(
      nt, inTu,
      [&](std::int32_t t, auto&& visit) {
        for (std::int32_t n : neighbors[std::size_t(t)])
          if (n >= 0) visit(n);
      },
      [&](const std::vector<std::int32_t>& group) {
        for (std::int32_t t : group)
          for (std::int32_t n : neighbors[std::size_t(t)])
            if (n >= 0 && inTc[std::size_t(n)]) return;
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        for (std::int32_t t : group) c += centroidOfTet(t);
        c /= double(group.size());
        const std::int32_t representative = nearestOf(group, c, centroidOfTet);
        // The T_c tets that share a vertex with the group are its
        // neighbourhood; the nearest T_c tet in space may lie across a cut
        // (another limb).
        std::vector<std::int32_t> adjacent;
        for (std::int32_t t : group)
          for (std::int32_t v : tets_[std::size_t(t)])
            for (const std::int32_t n : around.of(v))
              if (inTc[std::size_t(n)]) adjacent.push_back(n);
        const std::int32_t sourceTet =
            nearestOf(adjacent.empty() ? tcTets : adjacent, centroidOfTet(representative), centroidOfTet);
        tuSlot_[std::size_t(tuIndex[std::size_t(representative)])] = -1 - knownSlot(representative, sourceTet);
        ++diagnostics_.unconstrainedTetGroups;
      });
  std::int32_t unknownTets = 0;
  for (std::size_t k = 0; k < tuTets_.size(); ++k)
    if (tuSlot_[k] >= 0) tuSlot_[k] = unknownTets++;
  diagnostics_.unknownTetCount = std::size_t(unknownTets);

  // With the T_c transforms eliminated, eq. 4.3 has one row per unknown and
  // a zero-residual solution (Delta B_t = 0 on all of T_u), so its
  // least-squares minimizer is the solution of the square system. Row t
  // multiplied by sqrt|t| sum_n |n| reads
  //   sum_{n in T1(t)} |t| |n| (B_t - B_n) = 0:
  // a graph Laplacian on face adjacency with symmetric weights |t||n|, SPD
  // once every group touches a constraint. Its Cholesky factor keeps the
  // 1-ring sparsity of the tet graph, where the normal equations A^T A would
  // couple 2-rings (measured: several times the fill and solve time).
  // Volumes are scaled by their mean to keep the entries near 1.
  double meanVolume = 0;
  for (double v : volume) meanVolume += v / double(nt);
  std::vector<Eigen::Triplet<double>> a, c;
  for (std::size_t k = 0; k < tuTets_.size(); ++k) {
    const std::int32_t row = tuSlot_[k];
    if (row < 0) continue;
    const auto t = std::size_t(tuTets_[k]);
    double diagonal = 0;
    for (std::int32_t n : neighbors[t]) {
      if (n < 0) continue;
      const double w = (volume[t] / meanVolume) * (volume[std::size_t(n)] / meanVolume);
      diagonal += w;
      if (inTc[std::size_t(n)]) {
        std::int32_t slot = knownSlotOfTet[std::size_t(n)];
        if (slot < 0) slot = knownSlot(n, n);
        c.emplace_back(row, slot, w);
      } else {
        const std::int32_t col = tuSlot_[std::size_t(tuIndex[std::size_t(n)])];
        if (col >= 0)
          a.emplace_back(row, col, -w);
        else
          c.emplace_back(row, -1 - col, w);
      }
    }
    a.emplace_back(row, row, diagonal);
  }
  {
    Eigen::SparseMatrix<double> laplacian(unknownTets, unknownTets);
    laplacian.setFromTriplets(a.begin(), a.end());
    step1Rhs_.resize(unknownTets, Eigen::Index(knownSource_.size()));
    step1Rhs_.setFromTriplets(c.begin(), c.end());
    step1_.factorize(laplacian);
  }

  // ---- Step 2 (eq. 4.4): unknown positions of the outside vertices.
  std::vector<std::uint8_t> outside(vertexCount_, 0);
  for (std::size_t v = 0; v < vertexCount_; ++v) outside[v] = inside[v] ? 0 : 1;
  // Vertex adjacency through the edges of T_u tets (every edge with an
  // outside end belongs only to T_u tets).
  std::vector<std::vector<std::int32_t>> adjacent(vertexCount_);
  for (std::int32_t t : tuTets_)
    for (const auto& e : kTetEdges) {
      const std::int32_t i = tets_[std::size_t(t)][std::size_t(e[0])], j = tets_[std::size_t(t)][std::size_t(e[1])];
      adjacent[std::size_t(i)].push_back(j);
      adjacent[std::size_t(j)].push_back(i);
    }
  std::vector<std::uint8_t> pinned(vertexCount_, 0);
  auto positionOfVertex = [&](std::int32_t v) -> const Eigen::Vector3d& { return rest_[std::size_t(v)]; };
  connectedGroups(
      vertexCount_, outside,
      [&](std::int32_t v, auto&& visit) {
        for (std::int32_t u : adjacent[std::size_t(v)]) visit(u);
      },
      [&](const std::vector<std::int32_t>& group) {
        for (std::int32_t v : group)
          for (std::int32_t u : adjacent[std::size_t(v)])
            if (inside[std::size_t(u)]) return;
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        for (std::int32_t v : group) c += rest_[std::size_t(v)];
        c /= double(group.size());
        const std::int32_t representative = nearestOf(group, c, positionOfVertex);
        const std::int32_t sourceTet = nearestOf(tcTets, rest_[std::size_t(representative)], centroidOfTet);
        pinnedVertices_.push_back({representative, sourceTet, Eigen::Matrix3d::Zero()});
        pinned[std::size_t(representative)] = 1;
        ++diagnostics_.unconstrainedVertexGroups;
      });
  for (std::size_t v = 0; v < vertexCount_; ++v)
    if (outside[v] && !pinned[v]) {
      vertexSlot_[v] = std::int32_t(unknownVertices_.size());
      unknownVertices_.push_back(std::int32_t(v));
    }
  const auto nu = Eigen::Index(unknownVertices_.size());
  std::vector<Eigen::Triplet<double>> l;
  for (std::size_t k = 0; k < tuTets_.size(); ++k) {
    const Tet& t = tets_[std::size_t(tuTets_[k])];
    const double w = volume[std::size_t(tuTets_[k])];
    for (const auto& e : kTetEdges) {
      const std::int32_t vi = t[std::size_t(e[0])], vj = t[std::size_t(e[1])];
      const std::int32_t i = vertexSlot_[std::size_t(vi)], j = vertexSlot_[std::size_t(vj)];
      if (i < 0 && j < 0) continue;
      edgeTerms_.push_back({std::int32_t(k), i, j, rest_[std::size_t(vi)] - rest_[std::size_t(vj)], w});
      if (i >= 0) l.emplace_back(i, i, w);
      if (j >= 0) l.emplace_back(j, j, w);
      if (i >= 0 && j >= 0) {
        l.emplace_back(i, j, -w);
        l.emplace_back(j, i, -w);
      } else if (i >= 0) {
        couplings_.push_back({i, vj, w});
      } else {
        couplings_.push_back({j, vi, w});
      }
    }
  }
  // Rest edge inverses of the tets whose B_t is read every frame.
  for (std::int32_t t : knownSource_) knownEdgeInv_.push_back(restEdgeInverse(rest_, tets_[std::size_t(t)]));
  for (PinnedVertex& p : pinnedVertices_) p.sourceEdgeInv = restEdgeInverse(rest_, tets_[std::size_t(p.sourceTet)]);
  Eigen::SparseMatrix<double> lm(nu, nu);
  lm.setFromTriplets(l.begin(), l.end());
  step2_.factorize(lm);
  tuBasis_.assign(tuTets_.size(), Eigen::Matrix3d::Identity());
}

void RigidityPropagation::propagate(std::span<Eigen::Vector3d> positions) {
  if (positions.size() != vertexCount_) throw RuntimeFailure("propagation: positions do not match the precomputed mesh");
  if (tuTets_.empty() && pinnedVertices_.empty()) return;

  // Step 1: known transforms, then the unknown ones (9 right-hand sides).
  Eigen::MatrixXd known(Eigen::Index(knownSource_.size()), 9);
  for (std::size_t k = 0; k < knownSource_.size(); ++k) {
    const auto t = std::size_t(knownSource_[k]);
    const Eigen::Matrix3d b = basisChange(knownEdgeInv_[k], positions, tets_[t]);
    known.row(Eigen::Index(k)) = Eigen::Map<const Eigen::Matrix<double, 1, 9>>(b.data());
  }
  const Eigen::MatrixXd x = step1_.solve(step1Rhs_ * known);
  for (std::size_t k = 0; k < tuTets_.size(); ++k) {
    const std::int32_t slot = tuSlot_[k];
    Eigen::Matrix<double, 1, 9> entries;
    if (slot >= 0)
      entries = x.row(slot);
    else
      entries = known.row(-1 - slot);
    tuBasis_[k] = Eigen::Map<const Eigen::Matrix3d>(entries.data());
    // The smooth blend of the constraints, made rigid (see the header).
    if (slot >= 0) tuBasis_[k] = polarRotation(tuBasis_[k]);
  }

  // Pinned representatives follow the affine map of their source tet.
  for (const PinnedVertex& p : pinnedVertices_) {
    const Tet& t = tets_[std::size_t(p.sourceTet)];
    const Eigen::Matrix3d b = basisChange(p.sourceEdgeInv, positions, t);
    positions[std::size_t(p.vertex)] =
        positions[std::size_t(t[0])] + b * (rest_[std::size_t(p.vertex)] - rest_[std::size_t(t[0])]);
  }

  // Step 2: edges target |t| B_t (v_i^0 - v_j^0) summed over their tets.
  // Accumulated per vertex (contiguous), then handed over as 3 columns.
  std::vector<Eigen::Vector3d> sums(unknownVertices_.size(), Eigen::Vector3d::Zero());
  for (const EdgeTerm& e : edgeTerms_) {
    const Eigen::Vector3d target = e.volume * (tuBasis_[std::size_t(e.tuIndex)] * e.restEdge);
    if (e.i >= 0) sums[std::size_t(e.i)] += target;
    if (e.j >= 0) sums[std::size_t(e.j)] -= target;
  }
  for (const Coupling& c : couplings_) sums[std::size_t(c.row)] += c.weight * positions[std::size_t(c.vertex)];
  const Eigen::MatrixXd rhs =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(sums.data()->data(), Eigen::Index(sums.size()), 3);
  const Eigen::MatrixXd placed = step2_.solve(rhs);
  for (std::size_t k = 0; k < unknownVertices_.size(); ++k)
    positions[std::size_t(unknownVertices_[k])] = placed.row(Eigen::Index(k)).transpose();
}

void propagateOutsideCage(const TetMesh& rest, std::span<const std::uint8_t> inside, std::span<Eigen::Vector3d> positions) {
  RigidityPropagation propagation;
  propagation.precompute(rest, inside);
  propagation.propagate(positions);
}

}  // namespace vox
