#include "geometry/deform/solve/cage_arap.h"
#include "geometry/disjoint_sets.h"

#include "geometry/deform/solve/deformation_metrics.h"
#include "geometry/error.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <string>

namespace vox {

namespace {

// Rotation for the covariance S = sum w e e'^T (Procrustes): R = V U^T from
// S = U Sigma V^T, the transpose of the rotation nearest S.
Eigen::Matrix3d closestRotation(const Eigen::Matrix3d& s) { return svdRotation(s).transpose(); }

double cotangent(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double cross = a.cross(b).norm();
  // A degenerate corner says nothing about the edge: no contribution.
  return cross > 0 ? a.dot(b) / cross : 0.0;
}

}  // namespace

void CageArap::precompute(const TriMesh& restCage, std::span<const std::int32_t> handles) {
  restCage.validate("cage");
  const auto nv = std::int32_t(restCage.vertexCount());
  rest_ = restCage.positions;

  // Cotangent weight of each undirected edge: half the sum of the cotangents
  // of the angles opposite to it.
  std::map<std::pair<std::int32_t, std::int32_t>, double> cot;
  for (const Tri& t : restCage.triangles) {
    for (int k = 0; k < 3; ++k) {
      const std::int32_t o = t[std::size_t(k)], a = t[std::size_t((k + 1) % 3)], b = t[std::size_t((k + 2) % 3)];
      const Eigen::Vector3d& po = rest_[std::size_t(o)];
      cot[std::minmax(a, b)] += 0.5 * cotangent(rest_[std::size_t(a)] - po, rest_[std::size_t(b)] - po);
    }
  }
  edges_.clear();
  weights_.clear();
  double positiveSum = 0;
  std::size_t positiveCount = 0;
  for (const auto& [edge, w] : cot) {
    edges_.push_back({edge.first, edge.second});
    weights_.push_back(w);
    if (w > 0) {
      positiveSum += w;
      ++positiveCount;
    }
  }
  const double floor = kMinWeightFraction * (positiveCount > 0 ? positiveSum / double(positiveCount) : 1.0);
  clamped_ = 0;
  for (double& w : weights_)
    if (w < floor) {
      w = floor;
      ++clamped_;
    }

  offsets_.assign(std::size_t(nv) + 1, 0);
  for (const auto& e : edges_) {
    ++offsets_[std::size_t(e[0]) + 1];
    ++offsets_[std::size_t(e[1]) + 1];
  }
  for (std::size_t i = 0; i < std::size_t(nv); ++i) offsets_[i + 1] += offsets_[i];
  adjacency_.assign(std::size_t(offsets_.back()), 0);
  adjacencyWeight_.assign(std::size_t(offsets_.back()), 0.0);
  {
    std::vector<std::int32_t> fill(offsets_.begin(), offsets_.end() - 1);
    for (std::size_t e = 0; e < edges_.size(); ++e) {
      const auto [a, b] = edges_[e];
      adjacency_[std::size_t(fill[std::size_t(a)])] = b;
      adjacencyWeight_[std::size_t(fill[std::size_t(a)]++)] = weights_[e];
      adjacency_[std::size_t(fill[std::size_t(b)])] = a;
      adjacencyWeight_[std::size_t(fill[std::size_t(b)]++)] = weights_[e];
    }
  }

  handles_.assign(handles.begin(), handles.end());
  freeIndex_.assign(std::size_t(nv), 0);
  for (std::size_t k = 0; k < handles_.size(); ++k) {
    const std::int32_t h = handles_[k];
    if (h < 0 || h >= nv) throw InputError("cage", "handle vertex " + std::to_string(h) + " is not a cage vertex");
    if (freeIndex_[std::size_t(h)] < 0) throw InputError("cage", "handle vertex " + std::to_string(h) + " is given twice");
    freeIndex_[std::size_t(h)] = -1;
  }

  // Every connected component needs a handle, or the global step is singular.
  {
    DisjointSets parts{std::size_t(nv)};
    for (std::int32_t v = 0; v < nv; ++v)
      for (std::int32_t k = offsets_[std::size_t(v)]; k < offsets_[std::size_t(v) + 1]; ++k) parts.unite(v, adjacency_[std::size_t(k)]);
    std::vector<std::size_t> size(std::size_t(nv), 0);
    std::vector<std::uint8_t> anchored(std::size_t(nv), 0);
    for (std::int32_t v = 0; v < nv; ++v) {
      const std::int32_t r = parts.find(v);
      ++size[std::size_t(r)];
      if (freeIndex_[std::size_t(v)] < 0) anchored[std::size_t(r)] = 1;
    }
    for (std::int32_t s = 0; s < nv; ++s)
      if (parts.find(s) == s && !anchored[std::size_t(s)])
        throw InputError("cage", "a connected part of the cage (" + std::to_string(size[std::size_t(s)]) + " vertices, including vertex " +
                                     std::to_string(s) + ") holds no handle vertex");
  }

  freeVertices_.clear();
  for (std::int32_t v = 0; v < nv; ++v)
    if (freeIndex_[std::size_t(v)] >= 0) {
      freeIndex_[std::size_t(v)] = std::int32_t(freeVertices_.size());
      freeVertices_.push_back(v);
    }
  // The global step reads R_i of the free vertices and of their neighbours
  // only; a handle whose neighbours are all handles needs no rotation.
  std::vector<std::uint8_t> needsRotation(std::size_t(nv), 0);
  for (const std::int32_t v : freeVertices_) {
    needsRotation[std::size_t(v)] = 1;
    for (std::int32_t k = offsets_[std::size_t(v)]; k < offsets_[std::size_t(v) + 1]; ++k)
      needsRotation[std::size_t(adjacency_[std::size_t(k)])] = 1;
  }
  rotationVertices_.clear();
  for (std::int32_t v = 0; v < nv; ++v)
    if (needsRotation[std::size_t(v)]) rotationVertices_.push_back(v);
  std::vector<std::int32_t> handleSlot(std::size_t(nv), -1);
  for (std::size_t k = 0; k < handles_.size(); ++k) handleSlot[std::size_t(handles_[k])] = std::int32_t(k);

  // L_ff (lower triangle) and the couplings L_fc.
  const auto nf = Eigen::Index(freeVertices_.size());
  std::vector<Eigen::Triplet<double>> triplets;
  couplings_.clear();
  for (Eigen::Index r = 0; r < nf; ++r) {
    const std::int32_t v = freeVertices_[std::size_t(r)];
    double diagonal = 0;
    for (std::int32_t k = offsets_[std::size_t(v)]; k < offsets_[std::size_t(v) + 1]; ++k) {
      const std::int32_t u = adjacency_[std::size_t(k)];
      const double w = adjacencyWeight_[std::size_t(k)];
      diagonal += w;
      const std::int32_t c = freeIndex_[std::size_t(u)];
      if (c >= 0) {
        if (c < r) triplets.emplace_back(r, c, -w);
      } else {
        couplings_.push_back({std::int32_t(r), handleSlot[std::size_t(u)], w});
      }
    }
    triplets.emplace_back(r, r, diagonal);
  }
  Eigen::SparseMatrix<double> lff(nf, nf);
  lff.setFromTriplets(triplets.begin(), triplets.end());
  solver_.factorize(lff);

  rotations_.assign(std::size_t(nv), Eigen::Matrix3d::Identity());
  current_ = rest_;
}

void CageArap::resetWarmStart() {
  current_ = rest_;
  std::fill(rotations_.begin(), rotations_.end(), Eigen::Matrix3d::Identity());
}

void CageArap::fitRotations(std::span<const Eigen::Vector3d> positions) {
  for (const std::int32_t v : rotationVertices_) {
    const auto i = std::size_t(v);
    Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
    for (std::int32_t k = offsets_[i]; k < offsets_[i + 1]; ++k) {
      const auto j = std::size_t(adjacency_[std::size_t(k)]);
      s += adjacencyWeight_[std::size_t(k)] * (rest_[i] - rest_[j]) * (positions[i] - positions[j]).transpose();
    }
    rotations_[i] = closestRotation(s);
  }
}

const std::vector<Eigen::Vector3d>& CageArap::solve(const Eigen::MatrixX3d& handleTargets, int iterations) {
  if (handleTargets.rows() != Eigen::Index(handles_.size()))
    throw InputError("cage", "got " + std::to_string(handleTargets.rows()) + " handle targets for " +
                                 std::to_string(handles_.size()) + " handles");
  if (!handleTargets.allFinite()) throw InputError("cage", "a handle target has a non-finite coordinate");
  // Every handle at rest: the rest cage is the minimum (zero energy), taken
  // as is rather than through iterations that would only add rounding.
  bool atRest = true;
  for (std::size_t k = 0; k < handles_.size() && atRest; ++k)
    atRest = handleTargets.row(Eigen::Index(k)).transpose() == rest_[std::size_t(handles_[k])];
  if (atRest) {
    current_ = rest_;
    return current_;
  }
  for (std::size_t k = 0; k < handles_.size(); ++k) current_[std::size_t(handles_[k])] = handleTargets.row(Eigen::Index(k)).transpose();

  const auto nf = Eigen::Index(freeVertices_.size());
  Eigen::MatrixXd rhs(nf, 3);
  for (int it = 0; it < iterations && nf > 0; ++it) {
    fitRotations(current_);
    // Eq. 3.2: b_i = sum_j w_ij / 2 (R_i + R_j)(v_i - v_j), minus the handle
    // columns of L times the handle positions.
    for (Eigen::Index r = 0; r < nf; ++r) {
      const auto i = std::size_t(freeVertices_[std::size_t(r)]);
      Eigen::Vector3d b = Eigen::Vector3d::Zero();
      for (std::int32_t k = offsets_[i]; k < offsets_[i + 1]; ++k) {
        const auto j = std::size_t(adjacency_[std::size_t(k)]);
        b += 0.5 * adjacencyWeight_[std::size_t(k)] * (rotations_[i] + rotations_[j]) * (rest_[i] - rest_[j]);
      }
      rhs.row(r) = b.transpose();
    }
    for (const Coupling& c : couplings_) rhs.row(c.freeRow) += c.weight * handleTargets.row(c.handleSlot);
    const Eigen::MatrixXd x = solver_.solve(rhs);
    for (Eigen::Index r = 0; r < nf; ++r) current_[std::size_t(freeVertices_[std::size_t(r)])] = x.row(r).transpose();
  }
  return current_;
}

double CageArap::energy(std::span<const Eigen::Vector3d> positions) const {
  double total = 0;
  for (std::size_t i = 0; i < rest_.size(); ++i) {
    Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
    for (std::int32_t k = offsets_[i]; k < offsets_[i + 1]; ++k) {
      const auto j = std::size_t(adjacency_[std::size_t(k)]);
      s += adjacencyWeight_[std::size_t(k)] * (rest_[i] - rest_[j]) * (positions[i] - positions[j]).transpose();
    }
    const Eigen::Matrix3d r = closestRotation(s);
    for (std::int32_t k = offsets_[i]; k < offsets_[i + 1]; ++k) {
      const auto j = std::size_t(adjacency_[std::size_t(k)]);
      total += adjacencyWeight_[std::size_t(k)] * ((positions[i] - positions[j]) - r * (rest_[i] - rest_[j])).squaredNorm();
    }
  }
  return total;
}

std::vector<Eigen::Vector3d> arapDeformCage(const TriMesh& restCage, std::span<const std::int32_t> handles,
                                            const Eigen::MatrixX3d& handleTargets, int iterations) {
  CageArap arap;
  arap.precompute(restCage, handles);
  return arap.solve(handleTargets, iterations);
}

}  // namespace vox
