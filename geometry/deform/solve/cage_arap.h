#pragma once
// As-rigid-as-possible deformation of the cage (Sorkine & Alexa 2007; thesis
// eq. 3.1-3.2), laid out like libigl's arap: data + precompute + solve.
//
// Energy: E = sum_i sum_{j in N(i)} w_ij |(v'_i - v'_j) - R_i (v_i - v_j)|^2
// with cotangent weights w_ij = (cot alpha_ij + cot beta_ij) / 2 on the cage's
// triangles. Local step: R_i from the SVD of the weighted edge covariance
// (reflections removed), for the free vertices and their neighbours only:
// the global step reads no other R_i (a pose that holds most of the cage fits
// a few dozen rotations, not one per vertex). Global step (eq. 3.2): L v' = b
// with the handles eliminated from the system (hard constraints), L
// factorized once per handle set (SparseCholesky, CHOLMOD).
//
// Negative cotangent weights. An edge whose two opposite angles sum to more
// than pi gets a negative cotangent weight; QEM-simplified cages have many
// such obtuse pairs. They are CLAMPED to a small positive floor,
// kMinWeightFraction times the mean of the positive weights. Why clamp:
//  - with every weight positive the constrained Laplacian is a symmetric
//    M-matrix, positive definite as soon as each connected component holds a
//    handle, so the Cholesky factorization always exists;
//  - local and global steps then minimize one energy that is a sum of
//    non-negative terms, so no iteration increases it (the property the
//    alternating scheme relies on);
//  - taking the absolute value instead would turn an almost-degenerate
//    obtuse pair (cot -> -infinity) into the stiffest spring of the mesh; the
//    clamp keeps such an edge nearly free, which is what its geometry says.
// The same clamped weights are used in the local and the global step.

#include "geometry/deform/solve/sparse_cholesky.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

class CageArap {
public:
  static constexpr double kMinWeightFraction = 1e-3;

  // restCage: closed or open triangle mesh (#V vertices). handles: indices
  // into restCage.positions of the constrained vertices (fixed or moving), no
  // repeats. Builds the weights and factorizes the free-vertex block of L.
  // Throws InputError("cage", ...) when a handle index is out of range or
  // repeated, or when a connected component of the cage holds no handle (its
  // position would be undetermined).
  void precompute(const TriMesh& restCage, std::span<const std::int32_t> handles);

  // handleTargets: #handles by 3, row k the target of handles[k]. Runs
  // `iterations` local/global iterations starting from the previous solution
  // (the rest cage on the first call, or after resetWarmStart()), with the
  // handles moved to their targets. Returns the #V deformed positions.
  const std::vector<Eigen::Vector3d>& solve(const Eigen::MatrixX3d& handleTargets, int iterations);

  // The next solve() starts from the rest cage again.
  void resetWarmStart();

  const std::vector<Eigen::Vector3d>& positions() const { return current_; }
  const std::vector<std::int32_t>& handles() const { return handles_; }
  // Clamped cotangent weight of each undirected edge (edges() order).
  const std::vector<double>& weights() const { return weights_; }
  const std::vector<std::array<std::int32_t, 2>>& edges() const { return edges_; }
  // Number of edges whose cotangent weight was negative (or below the floor)
  // and was clamped.
  std::size_t clampedWeightCount() const { return clamped_; }
  // ARAP energy (eq. 3.1 summed over cells) of `positions` with the
  // rotations fitted to them.
  double energy(std::span<const Eigen::Vector3d> positions) const;

private:
  // Local step: R_i fitted to `positions` for rotationVertices_ (the others are
  // never read).
  void fitRotations(std::span<const Eigen::Vector3d> positions);

  std::vector<Eigen::Vector3d> rest_;
  std::vector<std::array<std::int32_t, 2>> edges_;
  std::vector<double> weights_;
  std::size_t clamped_ = 0;
  // Adjacency in CSR form: neighbours of i are adjacency_[offsets_[i] ..
  // offsets_[i+1]), with the weight of that edge in adjacencyWeight_.
  std::vector<std::int32_t> offsets_;
  std::vector<std::int32_t> adjacency_;
  std::vector<double> adjacencyWeight_;

  std::vector<std::int32_t> handles_;
  std::vector<std::int32_t> freeIndex_;  // #V: index among free vertices, or -1 for handles
  std::vector<std::int32_t> freeVertices_;
  std::vector<std::int32_t> rotationVertices_;  // free vertices and their neighbours, increasing
  // L restricted to (free, handle) pairs: rows of the free block's right-hand
  // side that the handle positions feed: (free row, handle slot, weight).
  struct Coupling {
    std::int32_t freeRow;
    std::int32_t handleSlot;
    double weight;
  };
  std::vector<Coupling> couplings_;
  SparseCholesky solver_;

  std::vector<Eigen::Matrix3d> rotations_;
  std::vector<Eigen::Vector3d> current_;
};

// One call: precompute + solve from the rest cage. Returns #V positions.
std::vector<Eigen::Vector3d> arapDeformCage(const TriMesh& restCage, std::span<const std::int32_t> handles,
                                            const Eigen::MatrixX3d& handleTargets, int iterations);

}  // namespace vox
