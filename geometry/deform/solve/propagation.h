#pragma once
// Rigidity propagation (thesis 4.2.2, eq. 4.1-4.4): places the transfer mesh
// (TM) vertices that lie outside the cage, given the Green-coordinate
// positions of the vertices inside it.
//
// Notation: V_c the inside vertices, T_c the tets whose four vertices are
// inside, T_u the others (at least one outside vertex), B_t the basis change
// of tet t (deformation_metrics.h), |t| rest volumes.
//
// Step 1 (eq. 4.3): unknowns B_t for t in T_u; B_t for t in T_c are the
// constraints, computed from the GC positions. Rows
//   sqrt|t| Delta B_t = 0   for t in T_u      (Delta B_t of eq. 4.1),
// solved in the least-squares sense for the 9 entries at once (one
// factorization, 9 right-hand sides). With the constraints eliminated the
// system is square with a zero-residual solution, which is computed from the
// equivalent symmetric form sum_n |t||n| (B_t - B_n) = 0 (see the .cpp).
// Each solved B_t is then replaced by its polar rotation
// (deformation_metrics.h): the transforms are blended linearly, and a linear
// blend of rotations shrinks (half-way between a 45 degree rotation and the
// identity, (R + I)/2 scales the plane of the rotation by cos 22.5 degrees:
// -15 % volume), while the outside parts should move rigidly. This is the
// local step of as-rigid-as-possible; step 2 is its global step. On the AM
// arm pose (assets/poses, no refinement) it keeps the upper humerus'
// deformed volume within 0.1 % (the linear blend: -0.7 %) and lowers the
// outside edges' 95th-percentile length distortion from 0.038 to 0.030. A
// rigid or identity motion of the inside is unchanged by it.
// Step 2 (eq. 4.4): unknowns the outside vertex positions. Rows
//   sqrt(W_e) (v_i - v_j) = sum_{t in T1(e)} |t| B_t (v_i^0 - v_j^0) / sqrt(W_e),
// W_e = sum_{t in T1(e)} |t|, for every edge with an outside end; the inside
// vertices are the constraints (3 right-hand sides).
//
// Constraints are hard: the T_c transforms and the V_c positions are
// eliminated from the unknowns instead of entering as the weighted rows of
// eq. 4.3-4.4 (the limit of large constraint weights). The inside vertices
// thus keep their GC positions exactly, so the TM stays consistent with the
// envelope, and both systems only carry the outside part of the TM. Both
// normal-equation matrices are factorized once in precompute (SparseCholesky,
// CHOLMOD); a frame only builds right-hand sides and back-substitutes.
//
// Parts without a constraint. A group of T_u tets connected through faces
// that touches no T_c tet, or a group of outside vertices connected through
// edges that reaches no inside vertex (e.g. a TM component entirely outside
// the cage), would make the systems singular. Each such group gets one
// representative (the member nearest to the group's centroid) that follows
// the affine map of the T_c tet nearest to it; the rest of the group then
// follows that same map through the solves, i.e. it moves rigidly with its
// nearest constrained neighbourhood. diagnostics() counts these groups.

#include "geometry/deform/solve/sparse_cholesky.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace vox {

struct PropagationDiagnostics {
  std::size_t insideVertexCount = 0;
  std::size_t outsideVertexCount = 0;
  std::size_t constrainedTetCount = 0;  // |T_c|
  std::size_t unknownTetCount = 0;      // |T_u| minus pinned representatives
  // Groups without a constraint, handled by pinning (see above).
  std::size_t unconstrainedTetGroups = 0;
  std::size_t unconstrainedVertexGroups = 0;
};

class RigidityPropagation {
public:
  // rest: the TM at rest, positively oriented tets (#V, #T). inside: #V flags,
  // 1 for the vertices whose deformed position the caller provides (inside
  // the cage). Throws InputError(source, ...) for a degenerate or inverted
  // tet, a mask of the wrong size, or outside vertices with no tet inside
  // the cage to follow.
  void precompute(const TetMesh& rest, std::span<const std::uint8_t> inside, const std::string& source = "transfer mesh");

  // positions: #V. On entry the inside vertices hold their deformed
  // positions (the others are ignored); on return the outside vertices are
  // placed by eq. 4.3-4.4.
  void propagate(std::span<Eigen::Vector3d> positions);

  const PropagationDiagnostics& diagnostics() const { return diagnostics_; }
  // Basis changes of the T_u tets from the last propagate(): tet index and B_t.
  const std::vector<std::int32_t>& unknownTets() const { return tuTets_; }
  const std::vector<Eigen::Matrix3d>& unknownTetBasis() const { return tuBasis_; }

private:
  std::size_t vertexCount_ = 0;
  std::vector<Eigen::Vector3d> rest_;
  std::vector<Tet> tets_;

  // Step 1. Known transforms: slot k takes B of T_c tet knownSource_[k].
  std::vector<std::int32_t> knownSource_;
  std::vector<Eigen::Matrix3d> knownEdgeInv_;  // rest edge inverse of each knownSource_ tet
  // tuTets_: the T_u tets; tuSlot_[k] >= 0: unknown row, or -1 - knownSlot
  // for a pinned representative.
  std::vector<std::int32_t> tuTets_;
  std::vector<std::int32_t> tuSlot_;
  Eigen::SparseMatrix<double> step1Rhs_;  // unknown rows by known slots
  SparseCholesky step1_;

  // Step 2. Unknown vertices and pinned representative vertices.
  std::vector<std::int32_t> unknownVertices_;
  struct PinnedVertex {
    std::int32_t vertex;
    std::int32_t sourceTet;  // T_c tet whose affine map it follows
    Eigen::Matrix3d sourceEdgeInv;
  };
  std::vector<PinnedVertex> pinnedVertices_;
  std::vector<std::int32_t> vertexSlot_;  // #V: unknown row, or -1
  // Per T_u tet edge rows: (tet position in tuTets_, i, j, |t|).
  struct EdgeTerm {
    std::int32_t tuIndex;
    std::int32_t i, j;  // unknown rows of the ends, -1 when known
    Eigen::Vector3d restEdge;
    double volume;
  };
  std::vector<EdgeTerm> edgeTerms_;
  struct Coupling {
    std::int32_t row;
    std::int32_t vertex;  // known vertex
    double weight;
  };
  std::vector<Coupling> couplings_;
  SparseCholesky step2_;

  std::vector<Eigen::Matrix3d> tuBasis_;
  PropagationDiagnostics diagnostics_;
};

// One call: precompute + propagate.
void propagateOutsideCage(const TetMesh& rest, std::span<const std::uint8_t> inside, std::span<Eigen::Vector3d> positions);

}  // namespace vox
