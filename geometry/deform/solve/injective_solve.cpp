#include "geometry/deform/solve/injective_solve.h"

#include "geometry/cancellation.h"
#include "geometry/deform/solve/deformation_metrics.h"
#include "geometry/disjoint_sets.h"
#include "geometry/error.h"
#include "geometry/parallel.h"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace vox {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// A rest tet is degenerate below this volume, relative to the mean edge
// length cubed (a regular tet has 0.118).
constexpr double kDegenerateVolume = 1e-9;
// Line-search halvings before a direction is given up: in a solve, down to
// steps of 1e-9 of the first; in a frame, whose time is budgeted, 1/256 (the
// next frame tries again).
constexpr int kSolveHalvings = 30;
constexpr int kFrameHalvings = 8;

using Gradients = std::array<Eigen::Vector3d, 4>;

// Gradients of the four barycentric coordinates of a tet: J = sum_a x_a g_a^T.
Gradients barycentricGradients(const Eigen::Matrix3d& restEdgeInv) {
  Gradients g;
  for (int a = 0; a < 3; ++a) g[std::size_t(a) + 1] = restEdgeInv.row(a).transpose();
  g[0] = -(g[1] + g[2] + g[3]);
  return g;
}

Eigen::Matrix3d edgeMatrix(std::span<const Eigen::Vector3d> x, const Tet& t) {
  Eigen::Matrix3d e;
  for (int a = 0; a < 3; ++a) e.col(a) = x[std::size_t(t[std::size_t(a) + 1])] - x[std::size_t(t[0])];
  return e;
}

// The largest real root of the monic cubic b^3 + p2 b^2 + p1 b + p0 (Cardano,
// or the trigonometric form for three real roots, then Newton polishing).
double largestRealRoot(double p2, double p1, double p0) {
  const double shift = p2 / 3.0;
  const double p = p1 - p2 * shift;
  const double q = 2.0 * shift * shift * shift - p1 * shift + p0;
  const double discriminant = 0.25 * q * q + p * p * p / 27.0;
  double y = 0.0;
  if (discriminant > 0.0) {
    // One real root; the form without cancellation.
    const double u = std::cbrt(-0.5 * q - std::copysign(std::sqrt(discriminant), q));
    y = u != 0.0 ? u - p / (3.0 * u) : 0.0;
  } else if (p < 0.0) {
    const double r = std::sqrt(-p / 3.0);
    const double c = std::clamp(-0.5 * q / (r * r * r), -1.0, 1.0);
    y = 2.0 * r * std::cos(std::acos(c) / 3.0);
  }
  double b = y - shift;
  for (int i = 0; i < 2; ++i) {
    const double f = ((b + p2) * b + p1) * b + p0;
    const double df = (3.0 * b + 2.0 * p2) * b + p1;
    if (df == 0.0) break;
    const double next = b - f / df;
    if (!std::isfinite(next)) break;
    b = next;
  }
  return b;
}

// The smallest alpha > 0 with det(A + alpha B) = 0 (infinity if none), for
// det A > 0: with beta = 1 / alpha, det(A + alpha B) / (alpha^3 det A) is a
// monic cubic in beta whose largest positive root gives the smallest alpha.
double firstZeroVolumeStep(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Vector3d a0 = a.col(0), a1 = a.col(1), a2 = a.col(2);
  const Eigen::Vector3d b0 = b.col(0), b1 = b.col(1), b2 = b.col(2);
  const double c0 = a0.dot(a1.cross(a2));
  const double c1 = b0.dot(a1.cross(a2)) + a0.dot(b1.cross(a2)) + a0.dot(a1.cross(b2));
  const double c2 = a0.dot(b1.cross(b2)) + b0.dot(a1.cross(b2)) + b0.dot(b1.cross(a2));
  const double c3 = b0.dot(b1.cross(b2));
  const double beta = largestRealRoot(c1 / c0, c2 / c0, c3 / c0);
  return beta > 0.0 ? 1.0 / beta : kInfinity;
}

// w^2 of SLIM for the symmetric Dirichlet energy s^2 + s^-2: (f'(s) / 2) / (s - 1),
// in the form without the removable singularity at s = 1 (where it is 4).
double slimWeight(double s) { return (s + 1.0) * (s * s + 1.0) / (s * s * s); }

// Which of the `ranges` ranges of parallelRanges over [0, n) starts at
// `begin` (range i starts at floor(n i / ranges)).
std::size_t rangeIndex(std::int64_t begin, std::int64_t ranges, std::int64_t n) {
  return std::size_t((begin * ranges + n - 1) / n);
}

struct TetSum {
  double sum = 0.0;
  double least = kInfinity;  // the smallest value reported
};

// term(t, value) over every tet, on the parallel loop: the sum of what the
// terms return, added range by range in order (the same for a given thread
// count), and the smallest value they report (det J_t, or a step bound).
template <class Term>
TetSum sumOverTets(std::int64_t tetCount, int threads, const Term& term) {
  const std::int64_t ranges = std::max<std::int64_t>(1, std::min<std::int64_t>(threads, (tetCount + 4095) / 4096));
  std::vector<TetSum> partial(static_cast<std::size_t>(ranges));
  parallelRanges(tetCount, threads, [&](std::int64_t begin, std::int64_t end) {
    TetSum part;
    for (std::int64_t t = begin; t < end; ++t) {
      double value = 0.0;
      part.sum += term(std::size_t(t), value);
      part.least = std::min(part.least, value);
    }
    partial[rangeIndex(begin, ranges, tetCount)] = part;
  });
  TetSum out;
  for (const TetSum& part : partial) {
    out.sum += part.sum;
    out.least = std::min(out.least, part.least);
  }
  return out;
}

// ||J||^2 + ||J^-1||^2 + lambda (det J - 1)^2, with J^-1's rows the cross
// products of J's columns over det J; +infinity unless det J > 0.
double tetDistortion(const Eigen::Matrix3d& j, double lambda, double& det) {
  const Eigen::Vector3d r0 = j.col(1).cross(j.col(2)), r1 = j.col(2).cross(j.col(0)), r2 = j.col(0).cross(j.col(1));
  det = j.col(0).dot(r0);
  if (!(det > 0.0)) return kInfinity;
  return j.squaredNorm() + (r0.squaredNorm() + r1.squaredNorm() + r2.squaredNorm()) / (det * det) +
         lambda * (det - 1.0) * (det - 1.0);
}

// The rotation R maximizing tr(R^T A), from the warm start `q` (Mueller et
// al. 2016, "A robust method to extract the rotational part of
// deformations"): each iteration turns q about the axis and by the angle
// that the torque of A's columns on R's columns asks for. From the previous
// frame's rotation a few iterations reach what a direction needs (1e-6 rad);
// a tet that turns faster converges over the next frames.
Eigen::Matrix3d extractRotation(const Eigen::Matrix3d& a, Eigen::Quaterniond& q) {
  constexpr int kIterations = 4;
  for (int i = 0; i < kIterations; ++i) {
    const Eigen::Matrix3d r = q.toRotationMatrix();
    const Eigen::Vector3d torque = r.col(0).cross(a.col(0)) + r.col(1).cross(a.col(1)) + r.col(2).cross(a.col(2));
    const double scale = std::abs(r.col(0).dot(a.col(0)) + r.col(1).dot(a.col(1)) + r.col(2).dot(a.col(2))) + 1e-9;
    const Eigen::Vector3d omega = torque / scale;
    const double angle = omega.norm();
    if (angle < 1e-6) break;
    q = (Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega / angle)) * q).normalized();
  }
  return q.toRotationMatrix();
}

// dE_t/dJ of the distortion term: 2 J - 2 J^-T J^-1 J^-T + 2 lambda
// (det J - 1) cof(J), for det J > 0.
Eigen::Matrix3d distortionGradient(const Eigen::Matrix3d& j, double lambda) {
  const double det = j.determinant();
  const Eigen::Matrix3d inverseTranspose = j.inverse().transpose();
  return 2.0 * j - 2.0 * inverseTranspose * inverseTranspose.transpose() * inverseTranspose +
         2.0 * lambda * (det - 1.0) * det * inverseTranspose;
}

// The rest system's factor (#free by #free, the same for the three
// coordinates) as the preconditioner of conjugate gradients on the SLIM
// system (3 #free, vertex-major), in the shape Eigen's solvers take.
class RestSystemPreconditioner {
public:
  RestSystemPreconditioner() = default;
  template <class Matrix>
  RestSystemPreconditioner& analyzePattern(const Matrix&) { return *this; }
  template <class Matrix>
  RestSystemPreconditioner& factorize(const Matrix&) { return *this; }
  template <class Matrix>
  RestSystemPreconditioner& compute(const Matrix&) { return *this; }
  Eigen::ComputationInfo info() const { return Eigen::Success; }
  void bind(const SparseCholesky& factor) { factor_ = &factor; }

  Eigen::VectorXd solve(const Eigen::VectorXd& b) const {
    using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
    const Eigen::Index n = b.size() / 3;
    const Eigen::MatrixXd x = factor_->solve(Eigen::MatrixXd(Eigen::Map<const Rows>(b.data(), n, 3)));
    Eigen::VectorXd out(b.size());
    Eigen::Map<Rows>(out.data(), n, 3) = x;
    return out;
  }

private:
  const SparseCholesky* factor_ = nullptr;
};

std::string vertexName(std::int32_t v) { return "vertex " + std::to_string(v); }

}  // namespace

void InjectiveSolver::precompute(std::span<const Eigen::Vector3d> rest, std::span<const Tet> tets,
                                 std::span<const std::int32_t> constrained,
                                 std::span<const std::int32_t> softVertices, std::span<const double> softWeights,
                                 const InjectiveSolveOptions& options, const std::string& source) {
  options_ = options;
  source_ = source;
  const auto n = std::int64_t(rest.size());
  if (!(options.flipShrink > 0.0 && options.flipShrink < 1.0))
    throw InputError(source, "flipShrink must lie in (0, 1)");
  if (!(options.volumeWeight >= 0.0) || !std::isfinite(options.volumeWeight))
    throw InputError(source, "volumeWeight must be finite and non-negative");
  if (!(options.targetPenalty > 0.0) || !std::isfinite(options.targetPenalty))
    throw InputError(source, "targetPenalty must be finite and positive");
  for (std::int64_t v = 0; v < n; ++v)
    if (!rest[std::size_t(v)].allFinite()) throw InputError(source, vertexName(std::int32_t(v)) + " has a non-finite coordinate");
  if (tets.empty()) throw InputError(source, "no tets");
  for (std::size_t t = 0; t < tets.size(); ++t) {
    for (int a = 0; a < 4; ++a) {
      const std::int32_t v = tets[t][std::size_t(a)];
      if (v < 0 || v >= n)
        throw InputError(source, "tet " + std::to_string(t) + " refers to vertex " + std::to_string(v) + " of " +
                                     std::to_string(n));
      for (int b = 0; b < a; ++b)
        if (tets[t][std::size_t(b)] == v) throw InputError(source, "tet " + std::to_string(t) + " repeats " + vertexName(v));
    }
  }

  rest_.assign(rest.begin(), rest.end());
  tets_.assign(tets.begin(), tets.end());
  const std::size_t tetCount = tets_.size();

  // Rest volumes, checked against the mean edge length.
  double edgeSum = 0.0;
  for (const Tet& t : tets_)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) edgeSum += (rest_[std::size_t(t[std::size_t(a)])] - rest_[std::size_t(t[std::size_t(b)])]).norm();
  const double meanEdge = edgeSum / (6.0 * double(tetCount));
  const double degenerate = kDegenerateVolume * meanEdge * meanEdge * meanEdge;
  std::vector<double> volumes(tetCount);
  double total = 0.0;
  for (std::size_t t = 0; t < tetCount; ++t) {
    volumes[t] = signedVolume(rest_, tets_[t]);
    if (std::abs(volumes[t]) <= degenerate || !std::isfinite(volumes[t]))
      throw InputError(source, "tet " + std::to_string(t) + " is degenerate at rest (volume " + std::to_string(volumes[t]) +
                                   " mm^3)");
    if (volumes[t] < 0.0)
      throw InputError(source, "tet " + std::to_string(t) + " is inverted at rest (signed volume " +
                                   std::to_string(volumes[t]) + " mm^3)");
    total += volumes[t];
  }
  restEdgeInv_.resize(tetCount);
  tetWeight_.resize(tetCount);
  for (std::size_t t = 0; t < tetCount; ++t) {
    restEdgeInv_[t] = edgeMatrix(rest_, tets_[t]).inverse();
    tetWeight_[t] = volumes[t] / total;
  }

  // Constrained and soft vertices.
  constrained_.assign(constrained.begin(), constrained.end());
  constrainedSlot_.assign(std::size_t(n), -1);
  for (std::size_t k = 0; k < constrained_.size(); ++k) {
    const std::int32_t v = constrained_[k];
    if (v < 0 || v >= n)
      throw InputError(source, "constrained vertex " + std::to_string(v) + " is out of range (" + std::to_string(n) +
                                   " vertices)");
    if (constrainedSlot_[std::size_t(v)] >= 0) throw InputError(source, "constrained vertex " + std::to_string(v) + " is repeated");
    constrainedSlot_[std::size_t(v)] = std::int32_t(k);
  }
  if (softWeights.size() != softVertices.size())
    throw InputError(source, std::to_string(softWeights.size()) + " soft weights for " + std::to_string(softVertices.size()) +
                                 " soft vertices");
  vertexTets_ = vertexTets(tets_, std::size_t(n));
  vertexTetCorner_.resize(vertexTets_.tets.size());
  for (std::int64_t v = 0; v < n; ++v)
    for (std::int64_t i = vertexTets_.start[std::size_t(v)]; i < vertexTets_.start[std::size_t(v) + 1]; ++i) {
      const Tet& tet = tets_[std::size_t(vertexTets_.tets[std::size_t(i)])];
      vertexTetCorner_[std::size_t(i)] = std::uint8_t(std::find(tet.begin(), tet.end(), std::int32_t(v)) - tet.begin());
    }
  softVertices_.assign(softVertices.begin(), softVertices.end());
  softCoefficient_.resize(softVertices_.size());
  softBaseCoefficient_.resize(softVertices_.size());
  std::vector<std::uint8_t> isSoft(std::size_t(n), 0);
  for (std::size_t k = 0; k < softVertices_.size(); ++k) {
    const std::int32_t v = softVertices_[k];
    if (v < 0 || v >= n)
      throw InputError(source, "soft vertex " + std::to_string(v) + " is out of range (" + std::to_string(n) + " vertices)");
    if (isSoft[std::size_t(v)]) throw InputError(source, "soft vertex " + std::to_string(v) + " is repeated");
    if (!(softWeights[k] > 0.0) || !std::isfinite(softWeights[k]))
      throw InputError(source, "soft vertex " + std::to_string(v) + " has a weight that is not finite and positive");
    isSoft[std::size_t(v)] = 1;
    double share = 0.0;
    for (const std::int32_t t : vertexTets_.of(v)) share += 0.25 * tetWeight_[std::size_t(t)];
    softCoefficient_[k] = softBaseCoefficient_[k] = softWeights[k] * share / (meanEdge * meanEdge);
  }

  penaltyCoefficient_.resize(constrained_.size());
  for (std::size_t k = 0; k < constrained_.size(); ++k) {
    double share = 0.0;
    for (const std::int32_t t : vertexTets_.of(constrained_[k])) share += 0.25 * tetWeight_[std::size_t(t)];
    penaltyCoefficient_[k] = options.targetPenalty * share / (meanEdge * meanEdge);
  }

  // Unknowns: the vertices of tets that are neither constrained; vertices in
  // no tet stay where they are. Every part of the mesh needs an anchor.
  freeIndex_.assign(std::size_t(n), -1);
  freeVertices_.clear();
  DisjointSets parts{std::size_t(n)};
  for (const Tet& t : tets_)
    for (int a = 1; a < 4; ++a) parts.unite(t[0], t[std::size_t(a)]);
  std::vector<std::uint8_t> anchored(std::size_t(n), 0);
  for (std::int64_t v = 0; v < n; ++v)
    if (constrainedSlot_[std::size_t(v)] >= 0 || isSoft[std::size_t(v)]) anchored[std::size_t(parts.find(std::int32_t(v)))] = 1;
  for (std::int64_t v = 0; v < n; ++v) {
    if (vertexTets_.of(std::int32_t(v)).empty() || constrainedSlot_[std::size_t(v)] >= 0) continue;
    const std::int32_t root = parts.find(std::int32_t(v));
    if (!anchored[std::size_t(root)])
      throw InputError(source, "the part of the mesh holding " + vertexName(std::int32_t(v)) +
                                   " has no constrained or soft vertex (its position would be undetermined)");
    freeIndex_[std::size_t(v)] = std::int32_t(freeVertices_.size());
    freeVertices_.push_back(std::int32_t(v));
  }

  freeSoftCoefficient_.assign(freeVertices_.size(), 0.0);
  freeSoftSlot_.assign(freeVertices_.size(), -1);
  for (std::size_t k = 0; k < softVertices_.size(); ++k)
    if (const std::int32_t f = freeIndex_[std::size_t(softVertices_[k])]; f >= 0) {
      freeSoftCoefficient_[std::size_t(f)] = softCoefficient_[k];
      freeSoftSlot_[std::size_t(f)] = std::int32_t(k);
    }

  buildPattern();
  restFactorized_ = false;
  resetToRest();
}

void InjectiveSolver::buildPattern() {
  // One term per ordered pair of free tet vertices (fa > fb) and per free
  // vertex (fa == fb), sorted into blocks.
  std::vector<std::tuple<std::int32_t, std::int32_t, BlockTerm>> terms;
  terms.reserve(tets_.size() * 10);
  for (std::size_t t = 0; t < tets_.size(); ++t)
    for (int a = 0; a < 4; ++a) {
      const std::int32_t fa = freeIndex_[std::size_t(tets_[t][std::size_t(a)])];
      if (fa < 0) continue;
      for (int b = 0; b < 4; ++b) {
        const std::int32_t fb = freeIndex_[std::size_t(tets_[t][std::size_t(b)])];
        if (fb < 0 || fb > fa || (fb == fa && b != a)) continue;
        terms.emplace_back(fb, fa, BlockTerm{std::int32_t(t), std::uint8_t(a), std::uint8_t(b)});
      }
    }
  // Column-major order (by fb, then fa) matches the compressed columns.
  std::sort(terms.begin(), terms.end(), [](const auto& x, const auto& y) {
    return std::tie(std::get<0>(x), std::get<1>(x), std::get<2>(x).tet) < std::tie(std::get<0>(y), std::get<1>(y), std::get<2>(y).tet);
  });
  blocks_.clear();
  blockTermStart_.clear();
  blockTerms_.clear();
  blockTerms_.reserve(terms.size());
  for (const auto& [fb, fa, term] : terms) {
    if (blocks_.empty() || blocks_.back().fa != fa || blocks_.back().fb != fb) {
      blocks_.push_back({fa, fb, {}});
      blockTermStart_.push_back(std::int64_t(blockTerms_.size()));
    }
    blockTerms_.push_back(term);
  }
  blockTermStart_.push_back(std::int64_t(blockTerms_.size()));

  const auto unknowns = Eigen::Index(3 * freeVertices_.size());
  std::vector<Eigen::Triplet<double>> pattern;
  pattern.reserve(blocks_.size() * 9);
  for (const Block& block : blocks_)
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q)
        if (block.fa != block.fb || p >= q) pattern.emplace_back(3 * block.fa + p, 3 * block.fb + q, 0.0);
  slimMatrix_.resize(unknowns, unknowns);
  slimMatrix_.setFromTriplets(pattern.begin(), pattern.end());
  slimMatrix_.makeCompressed();
  const int* outer = slimMatrix_.outerIndexPtr();
  const int* inner = slimMatrix_.innerIndexPtr();
  for (Block& block : blocks_)
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q) {
        std::int32_t& slot = block.value[std::size_t(3 * p + q)];
        slot = -1;
        if (block.fa == block.fb && p < q) continue;
        const int column = 3 * block.fb + q, row = 3 * block.fa + p;
        const int* found = std::lower_bound(inner + outer[column], inner + outer[column + 1], row);
        slot = std::int32_t(found - inner);
      }
}

void InjectiveSolver::checkTargets(std::span<const Eigen::Vector3d> constrainedTargets,
                                   std::span<const Eigen::Vector3d> softTargets) const {
  if (constrainedTargets.size() != constrained_.size())
    throw InputError(source_, std::to_string(constrainedTargets.size()) + " targets for " +
                                  std::to_string(constrained_.size()) + " constrained vertices");
  if (!softTargets.empty() && softTargets.size() != softVertices_.size())
    throw InputError(source_, std::to_string(softTargets.size()) + " soft targets for " +
                                  std::to_string(softVertices_.size()) + " soft vertices");
  for (const Eigen::Vector3d& p : constrainedTargets)
    if (!p.allFinite()) throw InputError(source_, "a constrained target is not finite");
  for (const Eigen::Vector3d& p : softTargets)
    if (!p.allFinite()) throw InputError(source_, "a soft target is not finite");
}

InjectiveSolver::Evaluation InjectiveSolver::evaluate(std::span<const Eigen::Vector3d> positions,
                                                      std::span<const Eigen::Vector3d> softTargets) const {
  const double lambda = options_.volumeWeight;
  const TetSum tets = sumOverTets(std::int64_t(tets_.size()), workerThreads(options_.threads), [&](std::size_t t, double& det) {
    return tetWeight_[t] * tetDistortion(edgeMatrix(positions, tets_[t]) * restEdgeInv_[t], lambda, det);
  });
  return {tets.sum + softEnergy(positions, softTargets), tets.least};
}

double InjectiveSolver::softEnergy(std::span<const Eigen::Vector3d> positions,
                                   std::span<const Eigen::Vector3d> softTargets) const {
  double sum = 0.0;
  for (std::size_t k = 0; k < softVertices_.size(); ++k) {
    const std::int32_t v = softVertices_[k];
    if (constrainedSlot_[std::size_t(v)] >= 0) continue;
    const Eigen::Vector3d& target = softTargets.empty() ? rest_[std::size_t(v)] : softTargets[k];
    sum += softCoefficient_[k] * (positions[std::size_t(v)] - target).squaredNorm();
  }
  return sum;
}

double InjectiveSolver::energy(std::span<const Eigen::Vector3d> positions,
                               std::span<const Eigen::Vector3d> softTargets) const {
  if (positions.size() != rest_.size())
    throw InputError(source_, std::to_string(positions.size()) + " positions for " + std::to_string(rest_.size()) + " vertices");
  if (!softTargets.empty() && softTargets.size() != softVertices_.size())
    throw InputError(source_, std::to_string(softTargets.size()) + " soft targets for " +
                                  std::to_string(softVertices_.size()) + " soft vertices");
  return evaluate(positions, softTargets).energy;
}

std::vector<double> InjectiveSolver::relativeVolumes(std::span<const Eigen::Vector3d> positions) const {
  std::vector<double> out(tets_.size());
  parallelRanges(std::int64_t(tets_.size()), workerThreads(options_.threads), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t t = begin; t < end; ++t)
      out[std::size_t(t)] = (edgeMatrix(positions, tets_[std::size_t(t)]) * restEdgeInv_[std::size_t(t)]).determinant();
  });
  return out;
}

void InjectiveSolver::resetToRest() {
  current_ = rest_;
  restRotation_.assign(tets_.size(), Eigen::Quaterniond::Identity());
}

void InjectiveSolver::setPositions(std::span<const Eigen::Vector3d> positions) {
  if (positions.size() != rest_.size())
    throw InputError(source_, std::to_string(positions.size()) + " positions for " + std::to_string(rest_.size()) + " vertices");
  const std::vector<double> volumes = relativeVolumes(positions);
  for (std::size_t t = 0; t < volumes.size(); ++t)
    if (!(volumes[t] > 0.0))
      throw InputError(source_, "tet " + std::to_string(t) + " is not positively oriented in the given positions");
  current_.assign(positions.begin(), positions.end());
}

InjectiveSolver::Evaluation InjectiveSolver::slimLocalStep(std::span<const Eigen::Vector3d> constrainedTargets,
                                                           std::span<const Eigen::Vector3d> softTargets) {
  // Per tet: the rotation, the SLIM metric and the linearized volume term,
  // folded into the tet's share of the right-hand side; and E's term.
  const double lambda = options_.volumeWeight;
  slimFrames_.resize(tets_.size());
  tetRhs_.resize(tets_.size());
  const TetSum sum = sumOverTets(std::int64_t(tets_.size()), workerThreads(options_.threads), [&](std::size_t t, double& det) {
    const Tet& tet = tets_[t];
    const Eigen::Matrix3d j = edgeMatrix(current_, tet) * restEdgeInv_[t];
    const double distortion = tetDistortion(j, lambda, det);
    if (!std::isfinite(distortion)) return kInfinity;
    const Gradients g = barycentricGradients(restEdgeInv_[t]);
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(j, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d u = svd.matrixU(), v = svd.matrixV();
    if (u.determinant() < 0.0) {  // det J > 0: U and V are both reflections; flip one axis of each
      u.col(2) = -u.col(2);
      v.col(2) = -v.col(2);
    }
    const Eigen::Vector3d s = svd.singularValues();
    const Eigen::Vector3d w2(slimWeight(s[0]), slimWeight(s[1]), slimWeight(s[2]));
    SlimFrame& frame = slimFrames_[t];
    frame.metric = u * w2.asDiagonal() * u.transpose();
    const Eigen::Matrix3d rotation = u * v.transpose();
    const Eigen::Matrix3d cofactor = det * j.inverse().transpose();
    double linear = 0.0;  // c . x0
    for (int a = 0; a < 4; ++a) {
      frame.volume[std::size_t(a)] = cofactor * g[std::size_t(a)];
      linear += frame.volume[std::size_t(a)].dot(current_[std::size_t(tet[std::size_t(a)])]);
    }
    const double volumeRhs = lambda * (linear - (det - 1.0));
    for (int a = 0; a < 4; ++a) {
      Eigen::Vector3d r = frame.metric * (rotation * g[std::size_t(a)]) + frame.volume[std::size_t(a)] * volumeRhs;
      if (freeIndex_[std::size_t(tet[std::size_t(a)])] >= 0)
        for (int b = 0; b < 4; ++b) {
          const std::int32_t slot = constrainedSlot_[std::size_t(tet[std::size_t(b)])];
          if (slot < 0) continue;
          const Eigen::Vector3d& x = constrainedTargets[std::size_t(slot)];
          r -= g[std::size_t(a)].dot(g[std::size_t(b)]) * (frame.metric * x) +
               lambda * frame.volume[std::size_t(a)] * frame.volume[std::size_t(b)].dot(x);
        }
      tetRhs_[t][std::size_t(a)] = tetWeight_[t] * r;
    }
    return tetWeight_[t] * distortion;
  });
  return {sum.sum + softEnergy(current_, softTargets), sum.least};
}

Eigen::VectorXd InjectiveSolver::slimGlobalStep(std::span<const Eigen::Vector3d> softTargets) {
  const double lambda = options_.volumeWeight;
  const int threads = workerThreads(options_.threads);
  double* values = slimMatrix_.valuePtr();
  parallelRanges(std::int64_t(blocks_.size()), threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t k = begin; k < end; ++k) {
      const Block& block = blocks_[std::size_t(k)];
      Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
      for (std::int64_t i = blockTermStart_[std::size_t(k)]; i < blockTermStart_[std::size_t(k) + 1]; ++i) {
        const BlockTerm& term = blockTerms_[std::size_t(i)];
        const SlimFrame& frame = slimFrames_[std::size_t(term.tet)];
        const Gradients g = barycentricGradients(restEdgeInv_[std::size_t(term.tet)]);
        sum += tetWeight_[std::size_t(term.tet)] *
               (g[term.a].dot(g[term.b]) * frame.metric + lambda * frame.volume[term.a] * frame.volume[term.b].transpose());
      }
      if (block.fa == block.fb) sum.diagonal().array() += freeSoftCoefficient_[std::size_t(block.fa)];
      for (int e = 0; e < 9; ++e)
        if (block.value[std::size_t(e)] >= 0) values[block.value[std::size_t(e)]] = sum(e / 3, e % 3);
    }
  });
  const std::vector<Eigen::Vector3d> rhs = gatherRightHandSide(softTargets);
  Eigen::MatrixXd b(3 * Eigen::Index(rhs.size()), 1);
  for (std::size_t f = 0; f < rhs.size(); ++f) b.block<3, 1>(3 * Eigen::Index(f), 0) = rhs[f];
  if (std::int64_t(b.rows()) <= options_.directSolveLimit) {
    slimSolver_.factorize(slimMatrix_);
    return slimSolver_.solve(b).col(0);
  }
  // Too large to factorize every iteration: conjugate gradients from the
  // current positions, preconditioned by the rest system's factor (the SLIM
  // system at rest). An inexact solve still gives a direction the line
  // search makes safe.
  factorizeRestSystem();
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower, RestSystemPreconditioner> cg;
  cg.setMaxIterations(options_.cgIterations);
  cg.setTolerance(options_.cgTolerance);
  cg.compute(slimMatrix_);
  cg.preconditioner().bind(restSolver_);
  Eigen::VectorXd guess(b.rows());
  for (std::size_t f = 0; f < freeVertices_.size(); ++f)
    guess.segment<3>(3 * Eigen::Index(f)) = current_[std::size_t(freeVertices_[f])];
  return cg.solveWithGuess(b.col(0), guess);
}

std::vector<Eigen::Vector3d> InjectiveSolver::gatherRightHandSide(std::span<const Eigen::Vector3d> softTargets) const {
  std::vector<Eigen::Vector3d> out(freeVertices_.size());
  parallelRanges(std::int64_t(freeVertices_.size()), workerThreads(options_.threads), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t f = begin; f < end; ++f) {
      const std::int32_t v = freeVertices_[std::size_t(f)];
      Eigen::Vector3d r = Eigen::Vector3d::Zero();
      for (std::int64_t i = vertexTets_.start[std::size_t(v)]; i < vertexTets_.start[std::size_t(v) + 1]; ++i)
        r += tetRhs_[std::size_t(vertexTets_.tets[std::size_t(i)])][vertexTetCorner_[std::size_t(i)]];
      if (const std::int32_t k = freeSoftSlot_[std::size_t(f)]; k >= 0)
        r += freeSoftCoefficient_[std::size_t(f)] * (softTargets.empty() ? rest_[std::size_t(v)] : softTargets[std::size_t(k)]);
      out[std::size_t(f)] = r;
    }
  });
  return out;
}

// The SLIM system at rest (J = I: W^T W = 4 I, without the volume term) is
// the same for the three coordinates.
constexpr double kRestMetric = 4.0;

InjectiveSolver::Evaluation InjectiveSolver::restLocalStep(std::span<const Eigen::Vector3d> constrainedTargets,
                                                           std::span<const Eigen::Vector3d> softTargets,
                                                           RestDirection kind) {
  // Rotations: ARAP's right-hand side, 4 |t| / |Omega| R_t g_a, for the
  // positions. Gradient: the rest system stands for half of E's Hessian
  // (2 x 4 |t| / |Omega| per unit of the tets' Laplacian) and the right-hand
  // side is minus half of E's gradient, for the step. Both less the coupling
  // to the constrained vertices (their targets, or their moves).
  const double lambda = options_.volumeWeight;
  tetRhs_.resize(tets_.size());
  const TetSum sum = sumOverTets(std::int64_t(tets_.size()), workerThreads(options_.threads), [&](std::size_t t, double& det) {
    const Tet& tet = tets_[t];
    const Eigen::Matrix3d j = edgeMatrix(current_, tet) * restEdgeInv_[t];
    const double distortion = tetDistortion(j, lambda, det);
    if (!std::isfinite(distortion)) return kInfinity;
    const Gradients g = barycentricGradients(restEdgeInv_[t]);
    const double weight = kRestMetric * tetWeight_[t];
    const Eigen::Matrix3d m = kind == RestDirection::Rotations ? Eigen::Matrix3d(weight * extractRotation(j, restRotation_[t]))
                                                               : Eigen::Matrix3d(-0.5 * tetWeight_[t] * distortionGradient(j, lambda));
    for (int a = 0; a < 4; ++a) {
      Eigen::Vector3d r = m * g[std::size_t(a)];
      if (freeIndex_[std::size_t(tet[std::size_t(a)])] >= 0)
        for (int b = 0; b < 4; ++b) {
          const std::int32_t v = tet[std::size_t(b)];
          const std::int32_t slot = constrainedSlot_[std::size_t(v)];
          if (slot < 0) continue;
          const Eigen::Vector3d x = kind == RestDirection::Rotations
                                        ? constrainedTargets[std::size_t(slot)]
                                        : Eigen::Vector3d(constrainedTargets[std::size_t(slot)] - current_[std::size_t(v)]);
          r -= weight * g[std::size_t(a)].dot(g[std::size_t(b)]) * x;
        }
      tetRhs_[t][std::size_t(a)] = r;
    }
    return tetWeight_[t] * distortion;
  });
  return {sum.sum + softEnergy(current_, softTargets), sum.least};
}

void InjectiveSolver::factorizeRestSystem() {
  if (!restFactorized_) {
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(blocks_.size());
    for (std::size_t k = 0; k < blocks_.size(); ++k) {
      double sum = 0.0;
      for (std::int64_t i = blockTermStart_[k]; i < blockTermStart_[k + 1]; ++i) {
        const BlockTerm& term = blockTerms_[std::size_t(i)];
        const Gradients g = barycentricGradients(restEdgeInv_[std::size_t(term.tet)]);
        sum += tetWeight_[std::size_t(term.tet)] * kRestMetric * g[term.a].dot(g[term.b]);
      }
      if (blocks_[k].fa == blocks_[k].fb) sum += freeSoftCoefficient_[std::size_t(blocks_[k].fa)];
      entries.emplace_back(blocks_[k].fa, blocks_[k].fb, sum);
    }
    Eigen::SparseMatrix<double> matrix(Eigen::Index(freeVertices_.size()), Eigen::Index(freeVertices_.size()));
    matrix.setFromTriplets(entries.begin(), entries.end());
    restSolver_.factorize(matrix);
    restFactorized_ = true;
  }
}

Eigen::VectorXd InjectiveSolver::restGlobalStep(std::span<const Eigen::Vector3d> softTargets, RestDirection kind) {
  factorizeRestSystem();
  // The soft pull c_k p_k; for the step, the soft term's share of minus
  // half the gradient, c_k (p_k - x_k).
  const bool step = kind == RestDirection::Gradient;
  std::vector<Eigen::Vector3d> rhs = gatherRightHandSide(softTargets);
  if (step)
    for (std::size_t f = 0; f < rhs.size(); ++f)
      if (freeSoftSlot_[f] >= 0) rhs[f] -= freeSoftCoefficient_[f] * current_[std::size_t(freeVertices_[f])];
  Eigen::MatrixXd b(Eigen::Index(rhs.size()), 3);
  for (std::size_t f = 0; f < rhs.size(); ++f) b.row(Eigen::Index(f)) = rhs[f].transpose();
  const Eigen::MatrixXd solution = restSolver_.solve(b);
  Eigen::VectorXd out(3 * solution.rows());
  for (Eigen::Index f = 0; f < solution.rows(); ++f) {
    out.segment<3>(3 * f) = solution.row(f).transpose();
    if (step) out.segment<3>(3 * f) += current_[std::size_t(freeVertices_[std::size_t(f)])];
  }
  return out;
}

std::vector<Eigen::Vector3d> InjectiveSolver::directionTo(const Eigen::VectorXd& freeSolution,
                                                          std::span<const Eigen::Vector3d> constrainedTargets) const {
  std::vector<Eigen::Vector3d> direction(rest_.size(), Eigen::Vector3d::Zero());
  for (std::size_t f = 0; f < freeVertices_.size(); ++f) {
    const auto v = std::size_t(freeVertices_[f]);
    direction[v] = freeSolution.segment<3>(3 * Eigen::Index(f)) - current_[v];
  }
  for (std::size_t k = 0; k < constrained_.size(); ++k) {
    const auto v = std::size_t(constrained_[k]);
    direction[v] = constrainedTargets[k] - current_[v];
  }
  return direction;
}

double InjectiveSolver::injectiveStepBound(std::span<const Eigen::Vector3d> direction) const {
  const double largest =
      sumOverTets(std::int64_t(tets_.size()), workerThreads(options_.threads), [&](std::size_t t, double& step) {
        step = firstZeroVolumeStep(edgeMatrix(current_, tets_[t]), edgeMatrix(direction, tets_[t]));
        return 0.0;
      }).least;
  return std::min(1.0, options_.flipShrink * largest);
}

bool InjectiveSolver::atTargets(std::span<const Eigen::Vector3d> constrainedTargets) const {
  for (std::size_t k = 0; k < constrained_.size(); ++k)
    if (current_[std::size_t(constrained_[k])] != constrainedTargets[k]) return false;
  return true;
}

double InjectiveSolver::targetPenalty(std::span<const Eigen::Vector3d> positions,
                                      std::span<const Eigen::Vector3d> constrainedTargets) const {
  double sum = 0.0;
  for (std::size_t k = 0; k < constrained_.size(); ++k)
    sum += penaltyCoefficient_[k] * (positions[std::size_t(constrained_[k])] - constrainedTargets[k]).squaredNorm();
  return sum;
}

bool InjectiveSolver::lineSearch(std::span<const Eigen::Vector3d> direction,
                                 std::span<const Eigen::Vector3d> constrainedTargets,
                                 std::span<const Eigen::Vector3d> softTargets, double currentMerit, int halvings,
                                 InjectiveStepReport& report, double& acceptedEnergy) {
  // The merit is E plus the penalty on the constrained vertices' distance to
  // their targets: at the targets, E itself must decrease; on the way, a
  // step that brings the bones closer may raise E, by less than it gains,
  // so a tet's barrier energy bounds how far it can be squeezed.
  double alpha = injectiveStepBound(direction);
  std::vector<Eigen::Vector3d> trial(current_.size());
  for (int halving = 0; halving < halvings; ++halving, alpha *= 0.5) {
    for (std::size_t v = 0; v < trial.size(); ++v) trial[v] = current_[v] + alpha * direction[v];
    if (alpha == 1.0)
      for (std::size_t k = 0; k < constrained_.size(); ++k) trial[std::size_t(constrained_[k])] = constrainedTargets[k];
    const Evaluation e = evaluate(trial, softTargets);
    if (!(e.minRelativeVolume > 0.0) || !std::isfinite(e.energy)) continue;
    if (!(e.energy + targetPenalty(trial, constrainedTargets) < currentMerit)) continue;
    current_.swap(trial);
    acceptedEnergy = e.energy;
    report.minRelativeVolume = std::min(report.minRelativeVolume, e.minRelativeVolume);
    return true;
  }
  return false;
}

InjectiveStepReport InjectiveSolver::iterate(std::span<const Eigen::Vector3d> constrainedTargets,
                                             std::span<const Eigen::Vector3d> softTargets, int iterations, bool slim) {
  checkTargets(constrainedTargets, softTargets);
  InjectiveStepReport report;
  double energy = 0.0;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    throwIfCancelled();
    const bool startedAtTargets = atTargets(constrainedTargets);
    // The local step evaluates E at the current positions on the way.
    const Evaluation here = slim ? slimLocalStep(constrainedTargets, softTargets)
                                 : restLocalStep(constrainedTargets, softTargets, RestDirection::Rotations);
    if (iteration == 0) {
      if (!(here.minRelativeVolume > 0.0))
        throw InputError(source_, "the starting positions invert a tet (smallest relative volume " +
                                      std::to_string(here.minRelativeVolume) + ")");
      report.minRelativeVolume = here.minRelativeVolume;
      report.energy = energy = here.energy;
    }
    const Eigen::VectorXd solution = slim ? slimGlobalStep(softTargets) : restGlobalStep(softTargets, RestDirection::Rotations);
    double next = energy;
    const double merit = energy + targetPenalty(current_, constrainedTargets);
    const int halvings = slim ? kSolveHalvings : kFrameHalvings;
    bool moved =
        lineSearch(directionTo(solution, constrainedTargets), constrainedTargets, softTargets, merit, halvings, report, next);
    if (!moved && !slim) {
      // ARAP's direction does not see the barrier; the preconditioned
      // gradient does (a descent direction at the targets).
      restLocalStep(constrainedTargets, softTargets, RestDirection::Gradient);
      moved = lineSearch(directionTo(restGlobalStep(softTargets, RestDirection::Gradient), constrainedTargets),
                         constrainedTargets, softTargets, merit, halvings, report, next);
    }
    if (!moved && !startedAtTargets) {
      // The bones cannot come closer along this direction without squeezing
      // a tet by more than they gain: relax the tissue around where they
      // are (a descent direction of E), then chase again.
      std::vector<Eigen::Vector3d> held(constrained_.size());
      for (std::size_t k = 0; k < constrained_.size(); ++k) held[k] = current_[std::size_t(constrained_[k])];
      const Eigen::VectorXd relaxed = slim ? (slimLocalStep(held, softTargets), slimGlobalStep(softTargets))
                                           : (restLocalStep(held, softTargets, RestDirection::Gradient),
                                              restGlobalStep(softTargets, RestDirection::Gradient));
      moved = lineSearch(directionTo(relaxed, held), held, softTargets, energy, halvings, report, next);
    }
    if (!moved) {
      // No decrease along the direction at the targets: stationary as far as
      // the line search can tell.
      report.converged = startedAtTargets;
      break;
    }
    ++report.iterations;
    if (startedAtTargets) {
      report.energies.push_back(next);
      if (energy - next <= options_.tolerance * std::abs(next)) {
        report.converged = true;
        energy = next;
        break;
      }
    }
    energy = next;
  }
  report.energy = energy;
  report.reachedTargets = atTargets(constrainedTargets);
  report.converged = report.converged && report.reachedTargets;
  return report;
}

void InjectiveSolver::scaleSoftWeights(std::span<const double> scale) {
  if (scale.size() != softVertices_.size())
    throw InputError(source_, std::to_string(scale.size()) + " weight scales for " + std::to_string(softVertices_.size()) + " soft vertices");
  for (std::size_t k = 0; k < scale.size(); ++k) softCoefficient_[k] = softBaseCoefficient_[k] * scale[k];
  for (std::size_t f = 0; f < freeSoftSlot_.size(); ++f)
    if (freeSoftSlot_[f] >= 0) freeSoftCoefficient_[f] = softCoefficient_[std::size_t(freeSoftSlot_[f])];
  restFactorized_ = false;
}

InjectiveStepReport InjectiveSolver::solveStep(std::span<const Eigen::Vector3d> constrainedTargets,
                                               std::span<const Eigen::Vector3d> softTargets) {
  return iterate(constrainedTargets, softTargets, options_.maxIterations, true);
}

InjectiveStepReport InjectiveSolver::frame(std::span<const Eigen::Vector3d> constrainedTargets,
                                           std::span<const Eigen::Vector3d> softTargets, int iterations) {
  return iterate(constrainedTargets, softTargets, iterations > 0 ? iterations : options_.frameIterations, false);
}

Eigen::Isometry3d screwInterpolate(const Eigen::Isometry3d& motion, double s) {
  const Eigen::AngleAxisd turn(motion.linear());
  const Eigen::Vector3d t = motion.translation();
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  if (std::abs(turn.angle()) < 1e-12) {
    out.translation() = s * t;
    return out;
  }
  // motion = rotation by theta about the axis k through c, then a slide
  // along k: t = (I - R) c + (k . t) k, with c (perpendicular to k) =
  // (t_perp + cot(theta / 2) k x t_perp) / 2.
  const Eigen::Vector3d k = turn.axis();
  const Eigen::Vector3d along = k.dot(t) * k;
  const Eigen::Vector3d across = t - along;
  const Eigen::Vector3d centre = 0.5 * (across + k.cross(across) / std::tan(0.5 * turn.angle()));
  const Eigen::Matrix3d r = Eigen::AngleAxisd(s * turn.angle(), k).toRotationMatrix();
  out.linear() = r;
  out.translation() = centre - r * centre + s * along;
  return out;
}

InjectiveStepTargets rigidStepTargets(std::span<const Eigen::Vector3d> rest, std::span<const std::int32_t> constrained,
                                      std::span<const std::int32_t> motionOf,
                                      std::span<const Eigen::Isometry3d> motions,
                                      std::span<const std::int32_t> softVertices,
                                      std::span<const Eigen::Vector3d> softFinal) {
  if (motionOf.size() != constrained.size())
    throw InputError("pose", std::to_string(motionOf.size()) + " motion indices for " + std::to_string(constrained.size()) +
                                 " constrained vertices");
  if (!softFinal.empty() && softFinal.size() != softVertices.size())
    throw InputError("pose", std::to_string(softFinal.size()) + " soft targets for " + std::to_string(softVertices.size()) +
                                 " soft vertices");
  std::vector<Eigen::Vector3d> constrainedRest(constrained.size()), softRest(softVertices.size());
  for (std::size_t k = 0; k < constrained.size(); ++k) {
    if (constrained[k] < 0 || std::size_t(constrained[k]) >= rest.size())
      throw InputError("pose", "constrained vertex " + std::to_string(constrained[k]) + " is out of range");
    if (motionOf[k] < 0 || std::size_t(motionOf[k]) >= motions.size())
      throw InputError("pose", "motion " + std::to_string(motionOf[k]) + " of constrained vertex " +
                                   std::to_string(constrained[k]) + " is out of range (" + std::to_string(motions.size()) +
                                   " motions)");
    constrainedRest[k] = rest[std::size_t(constrained[k])];
  }
  for (std::size_t k = 0; k < softVertices.size(); ++k) {
    if (softVertices[k] < 0 || std::size_t(softVertices[k]) >= rest.size())
      throw InputError("pose", "soft vertex " + std::to_string(softVertices[k]) + " is out of range");
    softRest[k] = rest[std::size_t(softVertices[k])];
  }
  return [constrainedRest, softRest, motionIndex = std::vector<std::int32_t>(motionOf.begin(), motionOf.end()),
          motionList = std::vector<Eigen::Isometry3d>(motions.begin(), motions.end()),
          softEnd = std::vector<Eigen::Vector3d>(softFinal.begin(), softFinal.end())](
             double s, std::span<Eigen::Vector3d> constrainedTargets, std::span<Eigen::Vector3d> softTargets) {
    std::vector<Eigen::Isometry3d> partial(motionList.size());
    for (std::size_t m = 0; m < motionList.size(); ++m) partial[m] = screwInterpolate(motionList[m], s);
    for (std::size_t k = 0; k < constrainedRest.size(); ++k)
      constrainedTargets[k] = partial[std::size_t(motionIndex[k])] * constrainedRest[k];
    for (std::size_t k = 0; k < softRest.size(); ++k)
      softTargets[k] = softEnd.empty() ? softRest[k] : ((1.0 - s) * softRest[k] + s * softEnd[k]).eval();
  };
}

InjectiveSolveResult solveInjective(std::span<const Eigen::Vector3d> rest, std::span<const Tet> tets,
                                    std::span<const std::int32_t> constrained, const InjectiveStepTargets& targets,
                                    const InjectiveSolveOptions& options, std::span<const std::int32_t> softVertices,
                                    std::span<const double> softWeights) {
  InjectiveSolver solver;
  solver.precompute(rest, tets, constrained, softVertices, softWeights, options);
  InjectiveSolveResult result;
  const int steps = std::max(1, options.steps);
  std::vector<Eigen::Vector3d> constrainedTargets(constrained.size()), softTargets(softVertices.size());
  for (int step = 1; step <= steps; ++step) {
    targets(double(step) / double(steps), constrainedTargets, softTargets);
    InjectiveStepReport report = solver.solveStep(constrainedTargets, softTargets);
    result.iterations += report.iterations;
    result.minRelativeVolume = std::min(result.minRelativeVolume, report.minRelativeVolume);
    result.energy = report.energy;
    result.converged = report.converged;
    result.steps.push_back(std::move(report));
  }
  result.positions = solver.positions();
  for (const double volume : solver.relativeVolumes(result.positions))
    if (!(volume > 0.0)) ++result.invertedTets;
  return result;
}

}  // namespace vox
