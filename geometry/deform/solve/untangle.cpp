#include "geometry/deform/solve/untangle.h"

#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/parallel.h"

#include <Eigen/Dense>
#include <LBFGS.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace vox {
namespace {

// chi(D) = (D + sqrt(eps^2 + D^2)) / 2, written for D < 0 as
// eps^2 / (2 (sqrt(eps^2 + D^2) - D)), which keeps its digits there.
double chi(double d, double eps) {
  const double s = std::sqrt(eps * eps + d * d);
  return d >= 0.0 ? 0.5 * (d + s) : eps * eps / (2.0 * (s - d));
}

struct Problem {
  std::span<const Tet> tets;
  std::vector<std::size_t> active;           // tets with a free vertex
  std::vector<Eigen::Matrix3d> restInverse;  // per active tet: (rest edges)^-1
  std::vector<double> weight;                // per active tet: rest volume / total
  std::vector<std::int32_t> freeIndex;       // per vertex: index among the free ones, or -1
  std::vector<std::int32_t> freeVertices;
  std::vector<UntangleAnchor> anchors;       // weight already times m_k / |Omega| / h^2
  std::vector<Eigen::Vector3d>* positions = nullptr;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double scale = 1.0;  // unknowns are (p - origin) / scale
  double lambda = 1.0;
  int threads = 0;

  Eigen::Vector3d point(const Eigen::VectorXd& x, std::int32_t v) const {
    const std::int32_t k = freeIndex[std::size_t(v)];
    return k < 0 ? (*positions)[std::size_t(v)] : Eigen::Vector3d(origin + scale * x.segment<3>(3 * k));
  }

  Eigen::Matrix3d jacobian(const Eigen::VectorXd& x, std::size_t a) const {
    const Tet& t = tets[active[a]];
    const Eigen::Vector3d p0 = point(x, t[0]);
    Eigen::Matrix3d e;
    for (int c = 0; c < 3; ++c) e.col(c) = point(x, t[std::size_t(c) + 1]) - p0;
    return e * restInverse[a];
  }

  // E_eps and its gradient in the unknowns; per-tet terms summed in tet
  // order, so the result never depends on the threads.
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& grad, double eps) const {
    std::vector<double> energy(active.size());
    std::vector<std::array<Eigen::Vector3d, 4>> g(active.size());
    parallelRanges(
        std::int64_t(active.size()), workerThreads(threads),
        [&](std::int64_t begin, std::int64_t end) {
          for (std::int64_t i = begin; i < end; ++i) {
            const auto a = std::size_t(i);
            const Eigen::Matrix3d j = jacobian(x, a);
            Eigen::Matrix3d cof;  // d det / dJ
            cof.col(0) = j.col(1).cross(j.col(2));
            cof.col(1) = j.col(2).cross(j.col(0));
            cof.col(2) = j.col(0).cross(j.col(1));
            const double d = j.col(0).dot(cof.col(0));
            const double c = chi(d, eps);
            const double dc = c / std::sqrt(eps * eps + d * d);  // chi'(D)
            const double t = j.squaredNorm();
            const double c23 = std::cbrt(c * c);
            energy[a] = weight[a] * (t / c23 + lambda * (d * d + 1.0) / c);
            const double k = -(2.0 / 3.0) * t / (c23 * c) * dc + lambda * (2.0 * d / c - (d * d + 1.0) * dc / (c * c));
            const Eigen::Matrix3d dfdj = weight[a] * (2.0 / c23 * j + k * cof);
            const Eigen::Matrix3d de = dfdj * restInverse[a].transpose();  // d f / d (edge columns)
            g[a][0] = -(de.col(0) + de.col(1) + de.col(2));
            for (int col = 0; col < 3; ++col) g[a][std::size_t(col) + 1] = de.col(col);
          }
        },
        1024);
    grad.setZero(x.size());
    double e = 0.0;
    for (std::size_t a = 0; a < active.size(); ++a) {
      e += energy[a];
      const Tet& t = tets[active[a]];
      for (std::size_t c = 0; c < 4; ++c) {
        const std::int32_t k = freeIndex[std::size_t(t[c])];
        if (k >= 0) grad.segment<3>(3 * k) += scale * g[a][c];
      }
    }
    for (const UntangleAnchor& an : anchors) {
      const std::int32_t k = freeIndex[std::size_t(an.vertex)];
      const Eigen::Vector3d r = point(x, an.vertex) - an.target;
      e += an.weight * r.squaredNorm();
      grad.segment<3>(3 * k) += 2.0 * an.weight * scale * r;
    }
    return e;
  }

  double smallestDet(const Eigen::VectorXd& x, std::size_t* inverted, double below) const {
    double m = std::numeric_limits<double>::infinity();
    std::size_t n = 0;
    for (std::size_t a = 0; a < active.size(); ++a) {
      const double d = jacobian(x, a).determinant();
      m = std::min(m, d);
      n += d <= below;
    }
    if (inverted) *inverted = n;
    return m;
  }
};

}  // namespace

UntangleReport untangleTets(std::span<const Eigen::Vector3d> rest, std::span<const Tet> tets,
                            std::span<const std::uint8_t> free, std::span<const UntangleAnchor> anchors,
                            std::vector<Eigen::Vector3d>& positions, const UntangleOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = rest.size();
  if (free.size() != n || positions.size() != n)
    throw InputError("untangle", "the free flags or positions do not match the rest vertices");
  Problem pb;
  pb.tets = tets;
  pb.positions = &positions;
  pb.lambda = options.volumeWeight;
  pb.threads = options.threads;
  pb.freeIndex.assign(n, -1);
  for (std::size_t v = 0; v < n; ++v)
    if (free[v]) {
      pb.freeIndex[v] = std::int32_t(pb.freeVertices.size());
      pb.freeVertices.push_back(std::int32_t(v));
    }
  double volume = 0.0, edgeSum = 0.0;
  std::size_t edges = 0;
  std::vector<double> mass(n, 0.0);
  for (std::size_t ti = 0; ti < tets.size(); ++ti) {
    const Tet& t = tets[ti];
    bool any = false;
    for (const std::int32_t v : t) {
      if (v < 0 || std::size_t(v) >= n) throw InputError("untangle", "tet " + std::to_string(ti) + " has a vertex index out of range");
      any = any || free[std::size_t(v)];
    }
    if (!any) continue;
    Eigen::Matrix3d e;
    for (int c = 0; c < 3; ++c) e.col(c) = rest[std::size_t(t[std::size_t(c) + 1])] - rest[std::size_t(t[0])];
    const double vol = e.determinant() / 6.0;
    if (!(vol > 0.0)) throw InputError("untangle", "rest tet " + std::to_string(ti) + " is flat or inverted");
    pb.active.push_back(ti);
    pb.restInverse.push_back(e.inverse());
    pb.weight.push_back(vol);
    volume += vol;
    for (const std::int32_t v : t) mass[std::size_t(v)] += 0.25 * vol;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        edgeSum += (rest[std::size_t(t[std::size_t(a)])] - rest[std::size_t(t[std::size_t(b)])]).norm();
        ++edges;
      }
  }
  UntangleReport report;
  report.freeVertices = pb.freeVertices.size();
  report.tets = pb.active.size();
  if (pb.active.empty()) {
    report.untangled = true;
    return report;
  }
  for (double& w : pb.weight) w /= volume;
  const double h = edgeSum / double(edges);
  for (const UntangleAnchor& a : anchors) {
    if (a.vertex < 0 || std::size_t(a.vertex) >= n) throw InputError("untangle", "an anchor's vertex is out of range");
    if (!free[std::size_t(a.vertex)]) continue;
    pb.anchors.push_back({a.vertex, a.target, a.weight * mass[std::size_t(a.vertex)] / volume / (h * h)});
  }
  // Unknowns in units of the mean rest edge about the free vertices' centroid.
  for (const std::int32_t v : pb.freeVertices) pb.origin += positions[std::size_t(v)];
  pb.origin /= double(std::max<std::size_t>(1, pb.freeVertices.size()));
  pb.scale = h;
  Eigen::VectorXd x(3 * pb.freeVertices.size());
  for (std::size_t k = 0; k < pb.freeVertices.size(); ++k)
    x.segment<3>(3 * std::int64_t(k)) = (positions[std::size_t(pb.freeVertices[k])] - pb.origin) / h;

  const double below = options.minRelativeVolume;
  double detMin = pb.smallestDet(x, &report.invertedBefore, below);
  report.minRelativeVolumeBefore = detMin;
  const std::size_t invertedBefore = report.invertedBefore;

  LBFGSpp::LBFGSParam<double> param;
  param.epsilon = 1e-8;
  param.epsilon_rel = 0.0;
  param.past = 3;
  param.delta = 1e-7;
  param.max_iterations = options.iterationsPerRound;
  param.max_linesearch = 60;
  LBFGSpp::LBFGSSolver<double> solver(param);

  // eps from the smallest det J (Garanzha et al.), at most initialEpsilon:
  // a few tets crushed where bones clash would otherwise set it for the
  // whole region, and the rounds would spend themselves at an eps that
  // does not see inversion.
  double eps = detMin > 0.0 ? 1e-10 : std::min(options.initialEpsilon, std::sqrt(1e-12 + 0.04 * detMin * detMin));
  Eigen::VectorXd grad(x.size());
  double energyPrevious = pb.evaluate(x, grad, eps);
  // The best round (fewest tets at or under `below`, then the largest
  // smallest det J): where the tangle cannot be undone (two fixed bones
  // too close), a smaller eps only spreads the fold.
  Eigen::VectorXd bestX = x;
  std::size_t bestInverted = invertedBefore;
  double bestDet = detMin, bestEnergy = energyPrevious;
  int sinceBest = 0;
  for (int round = 0; round < options.rounds; ++round) {
    throwIfCancelled();
    // The round's lowest point: a line search that fails leaves x where it tried last.
    Eigen::VectorXd lowest = x;
    double lowestEnergy = energyPrevious;
    auto f = [&](const Eigen::VectorXd& y, Eigen::VectorXd& gy) {
      const double e = pb.evaluate(y, gy, eps);
      if (std::isfinite(e) && e < lowestEnergy) {
        lowestEnergy = e;
        lowest = y;
      }
      return std::isfinite(e) ? e : std::numeric_limits<double>::max();
    };
    double fx = 0.0;
    try {
      report.iterations += solver.minimize(f, x, fx);
    } catch (const std::runtime_error&) {
      // The line search found no lower point: the round ends where it got.
    } catch (const std::logic_error&) {
    }
    x = lowest;
    ++report.rounds;
    const double energy = pb.evaluate(x, grad, eps);
    std::size_t inverted = 0;
    detMin = pb.smallestDet(x, &inverted, below);
    const bool better = options.lowestEnergy ? energy < bestEnergy : detMin > bestDet;
    if (inverted < bestInverted || (inverted == bestInverted && better)) {
      sinceBest = inverted < bestInverted ? 0 : sinceBest + 1;
      bestX = x;
      bestInverted = inverted;
      bestDet = detMin;
      bestEnergy = energy;
    } else {
      ++sinceBest;
    }
    const double decrease = (energyPrevious - energy) / std::max(std::abs(energyPrevious), 1e-300);
    if (detMin > below && eps <= 1e-10 && decrease < options.tolerance) break;
    if (inverted > 0 && sinceBest >= options.patience) break;
    const double sigma = std::max(1.0 - energy / energyPrevious, 0.1);
    const double mu = (1.0 - sigma) * chi(detMin, eps);
    eps = detMin < mu ? 2.0 * std::sqrt(mu * (mu - detMin)) : 1e-10;
    energyPrevious = pb.evaluate(x, grad, eps);
    // Energies at another eps do not compare.
    if (options.lowestEnergy) bestEnergy = bestX == x ? energyPrevious : pb.evaluate(bestX, grad, eps);
  }
  x = bestX;
  detMin = pb.smallestDet(x, &report.invertedAfter, below);
  report.minRelativeVolumeAfter = detMin;
  report.untangled = report.invertedAfter == 0;
  const bool taken = options.lowestEnergy ? report.invertedAfter <= invertedBefore
                                          : report.invertedAfter < invertedBefore ||
                                                (report.invertedAfter == invertedBefore && detMin > report.minRelativeVolumeBefore);
  if (taken) {
    for (std::size_t k = 0; k < pb.freeVertices.size(); ++k)
      positions[std::size_t(pb.freeVertices[k])] = pb.point(x, pb.freeVertices[k]);
  } else {
    report.invertedAfter = invertedBefore;
    report.minRelativeVolumeAfter = report.minRelativeVolumeBefore;
    report.untangled = false;
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace vox
