#pragma once
// Injective soft-tissue solve: places the free vertices of a tet mesh (the
// transfer mesh between the bones) given the prescribed positions of the
// constrained ones (the bones, each moved by its part's rigid motion) and
// optional soft targets (the skin or the cage), so that no tet ever inverts,
// in any step of the pose or iteration of the solve. docs/POSES.md
// ("Injective soft tissue") states the formulation; in short:
//
//   E(x) = sum_t (|t| / |Omega|) [ ||J_t||^2 + ||J_t^-1||^2 + lambda (det J_t - 1)^2 ]
//        + sum_k w_k (m_k / |Omega|) ||x_k - p_k||^2 / h^2
//
// J_t the deformation gradient of tet t (3 x 3, rest edges to deformed
// edges), |t| its rest volume, |Omega| the mesh's, m_k a quarter of the rest
// volume of the tets around soft vertex k, h the mean rest edge length. The
// symmetric Dirichlet term (6 at a rotation) goes to infinity as a tet
// flattens: a barrier on inversion. The volume term holds det J near 1.
//
// Method: SLIM (Rabinovich et al. 2017, "Scalable Locally Injective
// Mappings"). Local step, per tet: the SVD J = U S V^T, the closest
// rotation R = U V^T and the weight matrix W = U diag(w) U^T with
// w_i^2 = (s_i - s_i^-3) / (s_i - 1) = (s_i + 1)(s_i^2 + 1) / s_i^3, so that
// the proxy ||W (J - R)||^2 has the gradient of the symmetric Dirichlet term;
// the volume term enters linearized (Gauss-Newton: det J + cof(J) : dJ).
// Global step: the proxy's minimizer, one sparse SPD system in the 3 #free
// coordinates (the metric W^T W couples them), the constrained vertices
// eliminated (hard constraints), factorized by CHOLMOD (SparseCholesky);
// on large meshes solved instead by conjugate gradients preconditioned by the
// rest system's factor (below), which is factorized once.
// Line search: the largest step before any tet's signed volume reaches zero
// (the smallest positive root of its cubic in the step size; Smith &
// Schaefer 2015), times flipShrink, then halved until every tet has a
// positive volume (checked, not assumed) and the merit decreases. The
// constrained vertices move along the same line from where they are to their
// targets; the merit is E plus targetPenalty times their mass-weighted
// squared distance to the targets, so at the targets E never rises, and on
// the way a step may add distortion only by less than it brings them closer.
//
// Interactive mode (frame()): the system of SLIM at rest (J = I: W^T W = 4 I,
// so the tets' Laplacian L, the same for the three coordinates, plus the
// soft targets) is factorized once per constraint set. An iteration takes
// ARAP's global step on it (the tets' closest rotations, extracted
// warm-started from the previous frame's, on the right-hand side), which
// follows large turns; where the line search finds no step along it (ARAP
// does not see the barrier), the system preconditions E's true gradient
// instead, (2 x 4 L) d = -grad E (the quadratic proxy of Kovalsky et al.
// 2016 without its acceleration), a descent direction at the targets
// whatever the distortion. The same injective line search and merit decide
// the step; a fixed number of iterations per frame, warm-started from the
// previous frame's positions.

#include "geometry/deform/solve/sparse_cholesky.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace vox {

struct InjectiveSolveOptions {
  int steps = 8;                 // solveInjective: pose steps from rest to the targets
  int maxIterations = 40;        // SLIM iterations per step at most
  double tolerance = 1e-4;       // a step ends when an iteration lowers E by less than this fraction
  // lambda of the volume term. Soft tissue is nearly incompressible; at 30
  // the volume stays within a percent where bending alone would shrink it.
  double volumeWeight = 30.0;
  double flipShrink = 0.8;       // fraction of the largest inversion-free step tried first
  // mu of the line search's merit while the constrained vertices are on
  // their way to their targets (see lineSearch): the larger, the more
  // distortion a step may add to bring them closer.
  double targetPenalty = 100.0;
  int frameIterations = 2;       // frame(): iterations per frame
  // SLIM unknowns (3 #free) up to which CHOLMOD factorizes the SLIM system
  // every iteration; above, conjugate gradients preconditioned by the rest
  // system's factor (factorized once) solve it to cgTolerance (relative
  // residual) or cgIterations.
  std::int64_t directSolveLimit = 30000;
  int cgIterations = 60;
  double cgTolerance = 1e-4;
  int threads = 0;               // the parallel loop's threads (0: every CPU)
};

// What one step (solveStep) or one frame (frame) did.
struct InjectiveStepReport {
  int iterations = 0;
  double energy = 0.0;             // E at the end
  double minRelativeVolume = 1.0;  // smallest det J_t over every accepted iterate of the step
  bool reachedTargets = false;     // the constrained vertices sit at their targets
  bool converged = false;          // reached the targets and stopped on the tolerance
  // E after each iteration that started with the constrained vertices at
  // their targets (from then on no iteration increases E).
  std::vector<double> energies;
};

class InjectiveSolver {
public:
  // rest: #V positions (mm). tets: #T, indices into rest, positively
  // oriented. constrained: ids of the vertices with prescribed positions, no
  // repeats. softVertices / softWeights: #S ids and weights w_k (> 0) of
  // vertices pulled towards targets (a constrained vertex listed there keeps
  // its prescribed position). Every connected part of the mesh needs a
  // constrained or a soft vertex; a vertex in no tet stays where it is.
  // Throws InputError(source, ...) for an index out of range or repeated, a
  // non-finite coordinate, a degenerate or inverted rest tet, or a part with
  // nothing to hold it. The current positions start at rest.
  void precompute(std::span<const Eigen::Vector3d> rest, std::span<const Tet> tets,
                  std::span<const std::int32_t> constrained, std::span<const std::int32_t> softVertices = {},
                  std::span<const double> softWeights = {}, const InjectiveSolveOptions& options = {},
                  const std::string& source = "transfer mesh");

  // SLIM iterations from the current positions with the constrained vertices
  // moving to constrainedTargets (#constrained) and the soft vertices pulled
  // to softTargets (#S; empty: their rest positions).
  InjectiveStepReport solveStep(std::span<const Eigen::Vector3d> constrainedTargets,
                                std::span<const Eigen::Vector3d> softTargets = {});

  // The interactive mode: `iterations` (0: options.frameIterations)
  // iterations of the prefactorized rest system, warm-started from the
  // current positions.
  InjectiveStepReport frame(std::span<const Eigen::Vector3d> constrainedTargets,
                            std::span<const Eigen::Vector3d> softTargets = {}, int iterations = 0);

  // The soft vertices' weights w_k times scale[k] (#S; 1: as given to
  // precompute), for a continuation that stiffens some targets.
  void scaleSoftWeights(std::span<const double> scale);

  const std::vector<Eigen::Vector3d>& positions() const { return current_; }
  // Replaces the current positions (#V); throws InputError(source, ...) when
  // a tet is not positively oriented in them.
  void setPositions(std::span<const Eigen::Vector3d> positions);
  void resetToRest();

  // E of `positions` (#V) with the soft targets (#S; empty: their rest
  // positions); +infinity when a tet is not positively oriented.
  double energy(std::span<const Eigen::Vector3d> positions, std::span<const Eigen::Vector3d> softTargets = {}) const;
  // Per tet det J_t of `positions` (#T): its volume relative to rest.
  std::vector<double> relativeVolumes(std::span<const Eigen::Vector3d> positions) const;

  std::size_t vertexCount() const { return rest_.size(); }
  std::size_t tetCount() const { return tets_.size(); }
  const std::vector<std::int32_t>& constrained() const { return constrained_; }
  const std::vector<std::int32_t>& softVertices() const { return softVertices_; }
  const InjectiveSolveOptions& options() const { return options_; }

private:
  struct Evaluation {
    double energy = 0.0;
    double minRelativeVolume = 0.0;
  };
  // Per tet, what SLIM's local step hands the assembly of its matrix.
  struct SlimFrame {
    Eigen::Matrix3d metric = Eigen::Matrix3d::Identity();  // W^T W
    std::array<Eigen::Vector3d, 4> volume{};                // c_a = cof(J) g_a, the gradient of det J
  };
  Evaluation evaluate(std::span<const Eigen::Vector3d> positions, std::span<const Eigen::Vector3d> softTargets) const;
  double softEnergy(std::span<const Eigen::Vector3d> positions, std::span<const Eigen::Vector3d> softTargets) const;
  void checkTargets(std::span<const Eigen::Vector3d> constrainedTargets, std::span<const Eigen::Vector3d> softTargets) const;
  // Local steps: fill tetRhs_ (and slimFrames_) from current_ and return E there.
  Evaluation slimLocalStep(std::span<const Eigen::Vector3d> constrainedTargets, std::span<const Eigen::Vector3d> softTargets);
  // frame()'s two right-hand sides of the rest system: the tets' closest
  // rotations (ARAP: the system gives positions), or minus half of E's
  // gradient (the system gives the step).
  enum class RestDirection { Rotations, Gradient };
  Evaluation restLocalStep(std::span<const Eigen::Vector3d> constrainedTargets, std::span<const Eigen::Vector3d> softTargets,
                           RestDirection kind);
  // Global steps: the free vertices' positions (3 #free, vertex-major).
  Eigen::VectorXd slimGlobalStep(std::span<const Eigen::Vector3d> softTargets);
  Eigen::VectorXd restGlobalStep(std::span<const Eigen::Vector3d> softTargets, RestDirection kind);
  void factorizeRestSystem();
  // Per free vertex, the sum of its tets' tetRhs_ and its soft pull.
  std::vector<Eigen::Vector3d> gatherRightHandSide(std::span<const Eigen::Vector3d> softTargets) const;
  // The full #V direction to the global step's solution `freeSolution` with
  // the constrained vertices going to their targets.
  std::vector<Eigen::Vector3d> directionTo(const Eigen::VectorXd& freeSolution,
                                           std::span<const Eigen::Vector3d> constrainedTargets) const;
  // The largest step in [0, 1] along `direction` before a tet's signed volume
  // reaches zero, times flipShrink (1 when no tet would).
  double injectiveStepBound(std::span<const Eigen::Vector3d> direction) const;
  // mu sum_k (m_k / |Omega|) ||x_k - target_k||^2 / h^2 over the
  // constrained vertices: 0 at the targets.
  double targetPenalty(std::span<const Eigen::Vector3d> positions, std::span<const Eigen::Vector3d> constrainedTargets) const;
  // One line search and update of current_, on the merit E + targetPenalty,
  // with at most `halvings` halvings; returns false when no step lowered it.
  bool lineSearch(std::span<const Eigen::Vector3d> direction, std::span<const Eigen::Vector3d> constrainedTargets,
                  std::span<const Eigen::Vector3d> softTargets, double currentMerit, int halvings,
                  InjectiveStepReport& report, double& acceptedEnergy);
  bool atTargets(std::span<const Eigen::Vector3d> constrainedTargets) const;
  InjectiveStepReport iterate(std::span<const Eigen::Vector3d> constrainedTargets,
                              std::span<const Eigen::Vector3d> softTargets, int iterations, bool slim);
  void buildPattern();

  InjectiveSolveOptions options_;
  std::string source_;
  std::vector<Eigen::Vector3d> rest_;
  std::vector<Tet> tets_;
  std::vector<Eigen::Matrix3d> restEdgeInv_;  // #T: inverse of the rest edge matrix
  std::vector<double> tetWeight_;             // #T: |t| / |Omega|
  std::vector<std::int32_t> constrained_;
  std::vector<std::int32_t> constrainedSlot_;  // #V: index into constrained_, or -1
  std::vector<std::int32_t> freeIndex_;        // #V: index among the free vertices, or -1
  std::vector<std::int32_t> freeVertices_;
  std::vector<std::int32_t> softVertices_;
  std::vector<double> softCoefficient_;        // #S: w_k m_k / (|Omega| h^2)
  std::vector<double> softBaseCoefficient_;    // #S: the same with the weights precompute was given
  std::vector<double> penaltyCoefficient_;     // #constrained: mu m_k / (|Omega| h^2)
  std::vector<double> freeSoftCoefficient_;    // #free: its soft coefficient, or 0
  std::vector<std::int32_t> freeSoftSlot_;     // #free: index into softVertices_, or -1
  VertexTets vertexTets_;
  std::vector<std::uint8_t> vertexTetCorner_;  // per entry of vertexTets_.tets: the vertex's corner in that tet

  // The SLIM system's lower triangle: one 3 x 3 block per pair of free
  // vertices sharing a tet (fa >= fb), its entries' places in the values of
  // slimMatrix_, and the (tet, local a, local b) terms summed into it.
  struct Block {
    std::int32_t fa = 0, fb = 0;
    std::array<std::int32_t, 9> value{};  // row-major 3 x 3; -1 above the diagonal of a diagonal block
  };
  std::vector<Block> blocks_;
  std::vector<std::int64_t> blockTermStart_;  // #blocks + 1
  struct BlockTerm {
    std::int32_t tet;
    std::uint8_t a, b;
  };
  std::vector<BlockTerm> blockTerms_;
  Eigen::SparseMatrix<double> slimMatrix_;
  SparseCholesky slimSolver_;

  // The rest system of frame(): #free by #free, factorized on first use.
  SparseCholesky restSolver_;
  bool restFactorized_ = false;

  std::vector<SlimFrame> slimFrames_;                  // #T
  std::vector<std::array<Eigen::Vector3d, 4>> tetRhs_;  // #T: each tet's share of the right-hand side, per corner
  std::vector<Eigen::Quaterniond> restRotation_;  // #T, frame(): each tet's last rotation, the next warm start
  std::vector<Eigen::Vector3d> current_;
};

// A rigid motion taken a fraction s of the way from the identity along its
// screw (the rotation's angle scaled by s about the same axis, the
// translation along it by s): a joint's turn about its centre stays a turn
// about that centre at every step. s in [0, 1].
Eigen::Isometry3d screwInterpolate(const Eigen::Isometry3d& motion, double s);

// Targets of a pose step: s in (0, 1] the fraction of the pose;
// constrainedTargets (#constrained) and softTargets (#S) to fill.
using InjectiveStepTargets =
    std::function<void(double s, std::span<Eigen::Vector3d> constrainedTargets, std::span<Eigen::Vector3d> softTargets)>;

// Step targets for constrained vertices moved rigidly: constrained vertex k
// goes to screwInterpolate(motions[motionOf[k]], s) * rest[constrained[k]].
// Soft targets go linearly from their rest positions to softFinal (#S; empty:
// they stay at rest). The returned function copies what it needs.
InjectiveStepTargets rigidStepTargets(std::span<const Eigen::Vector3d> rest, std::span<const std::int32_t> constrained,
                                      std::span<const std::int32_t> motionOf,
                                      std::span<const Eigen::Isometry3d> motions,
                                      std::span<const std::int32_t> softVertices = {},
                                      std::span<const Eigen::Vector3d> softFinal = {});

struct InjectiveSolveResult {
  std::vector<Eigen::Vector3d> positions;  // #V
  std::vector<InjectiveStepReport> steps;  // one per pose step
  int iterations = 0;                      // over every step
  double energy = 0.0;                     // E at the end
  double minRelativeVolume = 1.0;          // smallest det J_t over every iterate of every step
  std::size_t invertedTets = 0;            // tets with det J_t <= 0 at the end
  bool converged = false;                  // the last step reached its targets and its tolerance
};

// One call: precompute, then options.steps steps from rest, step i (1-based)
// with the targets of s = i / steps. Throws as InjectiveSolver::precompute.
InjectiveSolveResult solveInjective(std::span<const Eigen::Vector3d> rest, std::span<const Tet> tets,
                                    std::span<const std::int32_t> constrained, const InjectiveStepTargets& targets,
                                    const InjectiveSolveOptions& options = {},
                                    std::span<const std::int32_t> softVertices = {},
                                    std::span<const double> softWeights = {});

}  // namespace vox
