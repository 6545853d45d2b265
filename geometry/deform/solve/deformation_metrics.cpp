#include "geometry/deform/solve/deformation_metrics.h"

#include "geometry/error.h"
#include "geometry/parallel.h"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace vox {

namespace {

Eigen::Matrix3d edgeMatrix(std::span<const Eigen::Vector3d> p, const Tet& t) {
  Eigen::Matrix3d e;
  const Eigen::Vector3d& a = p[std::size_t(t[0])];
  e.col(0) = p[std::size_t(t[1])] - a;
  e.col(1) = p[std::size_t(t[2])] - a;
  e.col(2) = p[std::size_t(t[3])] - a;
  return e;
}

// Accumulates samples weighted by volume; finish() normalizes.
class HistogramBuilder {
public:
  HistogramBuilder(int bins, double lo, double hi, double ideal) : ideal_(ideal) {
    h_.lo = lo;
    h_.hi = hi;
    h_.fractions.assign(std::size_t(std::max(bins, 1)), 0.0);
    h_.min = std::numeric_limits<double>::infinity();
    h_.max = -std::numeric_limits<double>::infinity();
  }
  void add(double value, double weight) {
    total_ += weight;
    sum_ += weight * value;
    squares_ += weight * (value - ideal_) * (value - ideal_);
    h_.min = std::min(h_.min, value);
    h_.max = std::max(h_.max, value);
    if (value < h_.lo) {
      h_.below += weight;
    } else if (value >= h_.hi) {
      h_.above += weight;
    } else {
      const auto bins = double(h_.fractions.size());
      const auto b = std::min(std::size_t((value - h_.lo) / (h_.hi - h_.lo) * bins), h_.fractions.size() - 1);
      h_.fractions[b] += weight;
    }
  }
  DistortionHistogram finish() {
    if (total_ > 0) {
      for (double& f : h_.fractions) f /= total_;
      h_.below /= total_;
      h_.above /= total_;
      h_.mean = sum_ / total_;
      h_.rmsDeviation = std::sqrt(squares_ / total_);
    } else {
      h_.min = h_.max = ideal_;
    }
    return h_;
  }

private:
  DistortionHistogram h_;
  double ideal_;
  double total_ = 0, sum_ = 0, squares_ = 0;
};

}  // namespace

Eigen::Matrix3d restEdgeInverse(const std::vector<Eigen::Vector3d>& rest, const Tet& t) {
  return edgeMatrix(rest, t).inverse();
}

Eigen::Matrix3d polarRotation(const Eigen::Matrix3d& b) {
  const double det = b.determinant();
  if (det > 1e-12 * std::max(1.0, b.squaredNorm() * b.norm())) {
    Eigen::Matrix3d x = b;
    for (int iteration = 0; iteration < 30; ++iteration) {
      const double g = std::cbrt(1.0 / std::abs(x.determinant()));
      const Eigen::Matrix3d next = 0.5 * (g * x + x.inverse().transpose() / g);
      const double change = (next - x).norm();
      x = next;
      if (change <= 1e-14 * std::sqrt(3.0)) return x;
    }
  }
  return svdRotation(b);
}

Eigen::Matrix3d svdRotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  const Eigen::Matrix3d& v = svd.matrixV();
  Eigen::Matrix3d r = u * v.transpose();
  if (r.determinant() < 0) {
    u.col(2) = -u.col(2);  // singular values are sorted: column 2 is the smallest
    r = u * v.transpose();
  }
  return r;
}

Eigen::Matrix3d basisChange(const Eigen::Matrix3d& restEdgeInv, std::span<const Eigen::Vector3d> deformed, const Tet& t) {
  return edgeMatrix(deformed, t) * restEdgeInv;
}

std::vector<double> tetVolumes(const TetMesh& rest) {
  std::vector<double> v(rest.tetCount());
  for (std::size_t t = 0; t < rest.tetCount(); ++t) v[t] = std::abs(signedVolume(rest.positions, rest.tets[t]));
  return v;
}

std::vector<Eigen::Matrix3d> basisChanges(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed) {
  if (deformed.size() != rest.vertexCount())
    throw InputError("transfer mesh", "deformed positions (" + std::to_string(deformed.size()) + ") do not match its " +
                                          std::to_string(rest.vertexCount()) + " vertices");
  std::vector<Eigen::Matrix3d> b(rest.tetCount());
  // Each range stops at its first degenerate tet; the smallest of those is
  // the mesh's first, whatever the thread count.
  std::atomic<std::int64_t> degenerate{std::numeric_limits<std::int64_t>::max()};
  parallelRanges(std::int64_t(rest.tetCount()), workerThreads(0), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t t = begin; t < end; ++t) {
      const Tet& tet = rest.tets[std::size_t(t)];
      const Eigen::Matrix3d e = edgeMatrix(rest.positions, tet);
      if (!(std::abs(e.determinant()) > 0)) {
        for (std::int64_t first = degenerate.load(); t < first && !degenerate.compare_exchange_weak(first, t);) {
        }
        return;
      }
      b[std::size_t(t)] = edgeMatrix(deformed, tet) * e.inverse();
    }
  });
  if (degenerate.load() != std::numeric_limits<std::int64_t>::max())
    throw InputError("transfer mesh", "tet " + std::to_string(degenerate.load()) + " is degenerate");
  return b;
}

std::vector<Eigen::Matrix3d> basisChangeLaplacian(std::span<const Eigen::Matrix3d> basis, std::span<const double> volumes,
                                                  std::span<const std::array<std::int32_t, 4>> neighbors) {
  std::vector<Eigen::Matrix3d> delta(basis.size(), Eigen::Matrix3d::Zero());
  parallelRanges(std::int64_t(basis.size()), workerThreads(0), [&](std::int64_t begin, std::int64_t end) {
    for (auto t = std::size_t(begin); t < std::size_t(end); ++t) {
      Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
      double weight = 0;
      for (std::int32_t n : neighbors[t]) {
        if (n < 0) continue;
        sum += volumes[std::size_t(n)] * basis[std::size_t(n)];
        weight += volumes[std::size_t(n)];
      }
      if (weight > 0) delta[t] = basis[t] - sum / weight;
    }
  });
  return delta;
}

std::vector<double> tetDeformationError(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed) {
  const auto basis = basisChanges(rest, deformed);
  const auto volumes = tetVolumes(rest);
  const auto neighbors = faceNeighbors(rest, "transfer mesh");
  const auto delta = basisChangeLaplacian(basis, volumes, neighbors);
  std::vector<double> e(delta.size());
  parallelRanges(std::int64_t(delta.size()), workerThreads(0), [&](std::int64_t begin, std::int64_t end) {
    for (auto t = std::size_t(begin); t < std::size_t(end); ++t) e[t] = delta[t].norm();
  });
  return e;
}

std::vector<double> vertexDeformationError(const TetMesh& rest, std::span<const double> tetError) {
  std::vector<double> sum(rest.vertexCount(), 0.0), weight(rest.vertexCount(), 0.0);
  for (std::size_t t = 0; t < rest.tetCount(); ++t) {
    const double v = std::abs(signedVolume(rest.positions, rest.tets[t]));
    for (std::int32_t i : rest.tets[t]) {
      sum[std::size_t(i)] += v * tetError[t];
      weight[std::size_t(i)] += v;
    }
  }
  for (std::size_t i = 0; i < sum.size(); ++i) sum[i] = weight[i] > 0 ? sum[i] / weight[i] : 0.0;
  return sum;
}

DistortionHistograms distortionHistograms(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed,
                                          const DistortionHistogramOptions& options) {
  const auto basis = basisChanges(rest, deformed);
  HistogramBuilder angle(options.angleBins, options.angleMin, options.angleMax, 90.0);
  HistogramBuilder stretch(options.stretchBins, options.stretchMin, options.stretchMax, 1.0);
  DistortionHistograms out;
  constexpr double kDegrees = 180.0 / std::numbers::pi;
  for (std::size_t t = 0; t < rest.tetCount(); ++t) {
    const double volume = std::abs(signedVolume(rest.positions, rest.tets[t]));
    out.volume += volume;
    const Eigen::Matrix3d& b = basis[t];
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d u = b.col(a), v = b.col((a + 1) % 3);
      stretch.add(u.norm(), volume);
      // atan2 of |u x v| and u.v: accurate near 0 and 180 degrees too.
      angle.add(kDegrees * std::atan2(u.cross(v).norm(), u.dot(v)), volume);
    }
  }
  out.angle = angle.finish();
  out.stretch = stretch.finish();
  return out;
}

}  // namespace vox
