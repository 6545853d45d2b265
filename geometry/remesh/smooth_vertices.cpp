#include "geometry/remesh/smooth_vertices.h"

#include "geometry/cancellation.h"
#include "geometry/remesh/element_classification.h"
#include "geometry/remesh/parallel_ranges.h"
#include "geometry/remesh/tet_shape.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <condition_variable>
#include <mutex>

namespace vox::remesh {

namespace {

struct VertexTets {
  std::vector<std::int64_t> start;
  std::vector<std::int32_t> tets;
  void of(std::int32_t v, std::vector<std::int32_t>& out) const {
    out.assign(tets.begin() + start[std::size_t(v)], tets.begin() + start[std::size_t(v) + 1]);
  }
};

VertexTets vertexTets(const RemeshComplex& complex) {
  VertexTets vt;
  vt.start.assign(std::size_t(complex.vertexSlots()) + 1, 0);
  for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (complex.tetAlive(t))
      for (std::int32_t v : complex.tet(t)) ++vt.start[std::size_t(v) + 1];
  }
  for (std::size_t v = 1; v < vt.start.size(); ++v) vt.start[v] += vt.start[v - 1];
  vt.tets.resize(std::size_t(vt.start.back()));
  std::vector<std::int64_t> fill(vt.start.begin(), vt.start.end() - 1);
  for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (complex.tetAlive(t))
      for (std::int32_t v : complex.tet(t)) vt.tets[std::size_t(fill[std::size_t(v)]++)] = t;
  }
  return vt;
}

class Smoother {
public:
  Smoother(RemeshComplex& complex, const InterfaceSurfaces* surfaces, const HullConstraint& hull, const VertexTets& vt,
           const InterfaceBound* interfaces)
      : complex_(complex), surfaces_(surfaces), hull_(hull), vt_(vt), interfaces_(interfaces) {}

  // Where v should go, from the current positions; false to stay.
  bool target(VertexNeighborhood& nb, Eigen::Vector3d& out) const {
    const std::int32_t dummy = complex_.dummyVertex();
    const Eigen::Vector3d p = complex_.position(nb.vertex);
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    int count = 0;
    switch (nb.kind) {
      case VertexKind::Corner:
        return false;
      case VertexKind::Inside:
        for (std::int32_t w : nb.neighbors)
          if (w != dummy) {
            g += complex_.position(w);
            ++count;
          }
        if (count == 0) return false;
        out = g / count;
        return true;
      case VertexKind::Feature:
        if (nb.featureLine >= 0) {
          // A tagged line: the mean of its two neighbours on it, onto its input geometry.
          out = complex_.features().projectOnLine(
              nb.featureLine, 0.5 * (complex_.position(nb.tagged[0]) + complex_.position(nb.tagged[1])));
          return keepsBend(nb, out);
        }
        // Neighbours along the same 1-junction (Table 2.3 similarity or inclusion).
        for (std::size_t i = 0; i < nb.neighbors.size(); ++i)
          if (nb.neighbors[i] != dummy && isFeatureEdge(nb.edgeLabels[i]) && nb.edgeLabels[i] == nb.labels) {
            g += complex_.position(nb.neighbors[i]);
            ++count;
          }
        if (count != 2) return false;
        out = g / count;
        if (surfaces_) surfaces_->projectOnCurve(nb.labels, out);
        return true;
      case VertexKind::Surface: {
        for (std::size_t i = 0; i < nb.neighbors.size(); ++i)
          if (nb.neighbors[i] != dummy && nb.edgeLabels[i] == nb.labels) {
            g += complex_.position(nb.neighbors[i]);
            ++count;
          }
        if (count == 0) return false;
        g /= count;
        if (nb.onHull()) {
          const HullConstraint::Planes planes = hull_.planes(complex_, nb);
          if (planes.frozen) return false;
          out = hull_.snap(planes, g);
          return true;
        }
        const std::int32_t x = nb.labels[0], y = nb.labels[1];
        const Eigen::Vector3d n = interfaceNormal(nb, x, y);
        if (!(n.squaredNorm() > 0.0)) return false;
        out = g - n * n.dot(g - p);  // tangential Laplacian
        if (surfaces_) surfaces_->projectOnSurface(x, y, n, out);
        return true;
      }
    }
    return false;
  }

  // Moves v towards `to`, halving the step until no incident tet degrades.
  bool moveTowards(std::int32_t v, const Eigen::Vector3d& to, std::vector<std::int32_t>& tets) const {
    vt_.of(v, tets);
    const Eigen::Vector3d from = complex_.position(v);
    double worstBefore = kUnknownCosine;
    for (double f : {1.0, 0.5, 0.25, 0.125}) {
      const Eigen::Vector3d p = from + f * (to - from);
      if (valid(v, p, tets, worstBefore) && (!interfaces_ || interfaces_->keepsMove(complex_, v, tets, p))) {
        complex_.setPosition(v, p);
        return true;
      }
    }
    return false;
  }

  // Compass search for v (its neighbourhood in nb) maximizing the smallest
  // dihedral angle of its domain tets; true when v moved.
  bool polish(VertexNeighborhood& nb) const {
    const std::int32_t v = nb.vertex, dummy = complex_.dummyVertex();
    if (nb.kind == VertexKind::Corner || nb.onHull()) return false;
    const Eigen::Vector3d start = complex_.position(v);
    double shortest = std::numeric_limits<double>::infinity();
    for (std::int32_t w : nb.neighbors)
      if (w != dummy) shortest = std::min(shortest, (complex_.position(w) - start).norm());
    if (!std::isfinite(shortest) || !(shortest > 0.0)) return false;

    // Directions of the search and the projection back onto the constraint.
    std::vector<Eigen::Vector3d> dirs;
    std::function<bool(Eigen::Vector3d&)> project = [](Eigen::Vector3d&) { return true; };
    switch (nb.kind) {
      case VertexKind::Inside:
        for (int x = -1; x <= 1; ++x)
          for (int y = -1; y <= 1; ++y)
            for (int z = -1; z <= 1; ++z)
              if (std::abs(x) + std::abs(y) + std::abs(z) == 1 || std::abs(x) + std::abs(y) + std::abs(z) == 3)
                dirs.push_back(Eigen::Vector3d(x, y, z).normalized());
        break;
      case VertexKind::Surface: {
        const std::int32_t x = nb.labels[0], y = nb.labels[1];
        const Eigen::Vector3d n = interfaceNormal(nb, x, y);
        if (!(n.squaredNorm() > 0.0)) return false;
        const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
        for (const Eigen::Vector3d& d : {u, w, Eigen::Vector3d((u + w).normalized()), Eigen::Vector3d((u - w).normalized())}) {
          dirs.push_back(d);
          dirs.push_back(-d);
        }
        if (surfaces_) project = [this, x, y, n](Eigen::Vector3d& p) { return surfaces_->projectOnSurface(x, y, n, p); };
        break;
      }
      case VertexKind::Feature: {
        // Along the chord of its two neighbours on the same 1-junction (or tagged line).
        std::vector<Eigen::Vector3d> ends;
        if (nb.featureLine >= 0) {
          for (std::int32_t w : nb.tagged) ends.push_back(complex_.position(w));
        } else {
          for (std::size_t i = 0; i < nb.neighbors.size(); ++i)
            if (nb.neighbors[i] != dummy && isFeatureEdge(nb.edgeLabels[i]) && nb.edgeLabels[i] == nb.labels)
              ends.push_back(complex_.position(nb.neighbors[i]));
        }
        if (ends.size() != 2) return false;
        const Eigen::Vector3d t = ends[1] - ends[0];
        if (!(t.squaredNorm() > 0.0)) return false;
        dirs = {t.normalized(), -t.normalized()};
        if (nb.featureLine >= 0) {
          project = [this, &nb](Eigen::Vector3d& p) {
            p = complex_.features().projectOnLine(nb.featureLine, p);
            return keepsBend(nb, p);
          };
        } else if (surfaces_) {
          project = [this, &nb](Eigen::Vector3d& p) { return surfaces_->projectOnCurve(nb.labels, p); };
        }
        break;
      }
      case VertexKind::Corner:
        return false;
    }

    double best = polishScore(v, start, nb.tets);
    if (!(best < 2.0)) return false;  // already invalid: leave it
    Eigen::Vector3d at = start;
    const double first = 0.25 * shortest;
    for (double step = first; step > 0.02 * first;) {
      double found = best;
      Eigen::Vector3d next = at;
      for (const Eigen::Vector3d& d : dirs) {
        Eigen::Vector3d p = at + step * d;
        if (!project(p) || !p.allFinite()) continue;
        const double score = polishScore(v, p, nb.tets);
        if (score < found && (!interfaces_ || interfaces_->keepsMove(complex_, v, nb.tets, p))) {
          found = score;
          next = p;
        }
      }
      if (found < best - 1e-12) {
        best = found;
        at = next;
      } else {
        step *= 0.5;
      }
    }
    if (at == start) return false;
    complex_.setPosition(v, at);
    return true;
  }

private:
  // Where a vertex of a tagged line is, the input line may bend: with the
  // vertex at p its two edges must still pass within a sixteenth of the
  // shorter one of the input line's point nearest to it, so that the line
  // does not cut the bend (the collapse keeps the same bound).
  bool keepsBend(const VertexNeighborhood& nb, const Eigen::Vector3d& p) const {
    const Eigen::Vector3d v = complex_.features().projectOnLine(nb.featureLine, complex_.position(nb.vertex));
    const Eigen::Vector3d a = complex_.position(nb.tagged[0]), b = complex_.position(nb.tagged[1]);
    const double tolerance = std::min((a - v).norm(), (b - v).norm()) / 16.0;
    auto distance = [&](const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
      const Eigen::Vector3d d = y - x;
      const double t = d.squaredNorm() > 0.0 ? std::clamp((v - x).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      return (x + t * d - v).norm();
    };
    return std::min(distance(a, p), distance(p, b)) <= tolerance;
  }

  // Largest cosine of the smallest dihedral angle over v's domain tets with v
  // at p (lower is better); 3 when a tet around v inverts or falls under the
  // quality floor that it met before.
  double polishScore(std::int32_t v, const Eigen::Vector3d& p, const std::vector<std::int32_t>& tets) const {
    const auto& P = complex_.positions();
    double worst = -1.0;
    for (std::int32_t q : tets) {
      if (complex_.isDummyTet(q)) continue;
      const Tet& t = complex_.tet(q);
      Eigen::Vector3d x[4];
      for (int i = 0; i < 4; ++i) x[i] = t[std::size_t(i)] == v ? p : P[std::size_t(t[std::size_t(i)])];
      if (signedVolume(x[0], x[1], x[2], x[3]) <= 0.0) return 3.0;
      const double quality = volumeLengthQuality(x[0], x[1], x[2], x[3]);
      if (!(quality > 0.0)) return 3.0;
      if (quality < kQualityFloor &&
          quality < volumeLengthQuality(P[std::size_t(t[0])], P[std::size_t(t[1])], P[std::size_t(t[2])], P[std::size_t(t[3])]))
        return 3.0;
      if (complex_.label(q) > 0) worst = std::max(worst, minDihedralCosine(x[0], x[1], x[2], x[3]));
    }
    return worst;
  }

  // Area-weighted normal of the x|y facets around v, pointing from x to y.
  Eigen::Vector3d interfaceNormal(const VertexNeighborhood& nb, std::int32_t x, std::int32_t y) const {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    const auto& P = complex_.positions();
    for (std::int32_t q : nb.tets) {
      const std::int32_t l = complex_.label(q);
      if ((l != x && l != y) || complex_.isDummyTet(q)) continue;
      const std::int32_t other = l == x ? y : x;
      for (int k = 0; k < 4; ++k) {
        if (complex_.tet(q)[std::size_t(k)] == nb.vertex || complex_.label(complex_.neighbor(q, k)) != other) continue;
        const Tri f = tetFace(complex_.tet(q), k);
        const Eigen::Vector3d a = P[std::size_t(f[0])];
        const Eigen::Vector3d outward = (P[std::size_t(f[1])] - a).cross(P[std::size_t(f[2])] - a);
        n += l == x ? outward : Eigen::Vector3d(-outward);
      }
    }
    const double len = n.norm();
    return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
  }

  // No incident tet inverts or falls under the quality floor, and none gets
  // a dihedral angle under 30 degrees that is worse than the worst around v
  // before the move (computed into worstBefore when first needed).
  bool valid(std::int32_t v, const Eigen::Vector3d& p, const std::vector<std::int32_t>& tets,
             double& worstBefore) const {
    const auto& P = complex_.positions();
    for (std::int32_t q : tets) {
      if (complex_.isDummyTet(q)) continue;
      const Tet& t = complex_.tet(q);
      Eigen::Vector3d x[4];
      for (int i = 0; i < 4; ++i) x[i] = t[std::size_t(i)] == v ? p : P[std::size_t(t[std::size_t(i)])];
      const double after = volumeLengthQuality(x[0], x[1], x[2], x[3]);
      if (!(after > 0.0) || signedVolume(x[0], x[1], x[2], x[3]) <= 0.0) return false;
      if (after < kQualityFloor && after < volumeLengthQuality(P[std::size_t(t[0])], P[std::size_t(t[1])],
                                                               P[std::size_t(t[2])], P[std::size_t(t[3])]))
        return false;
      const double worst = minDihedralCosine(x[0], x[1], x[2], x[3]);
      if (worst > kGoodAngleCosine) {
        if (worstBefore == kUnknownCosine) worstBefore = complex_.worstDihedralCosineOf(tets);
        if (worst > worstBefore) return false;
      }
    }
    return true;
  }

  static constexpr double kGoodAngleCosine = 0.8660254037844387;  // cos 30 degrees
  static constexpr double kUnknownCosine = 3.0;
  RemeshComplex& complex_;
  const InterfaceSurfaces* surfaces_;
  const HullConstraint& hull_;
  const VertexTets& vt_;
  const InterfaceBound* interfaces_;
};

// Moves level[i] towards targets[i] where moves[i], with the result of doing
// so one vertex at a time in index order: a move reads only the positions
// of the vertex's one-ring, so a vertex moves once every moving neighbour of
// lower index has moved and before any of higher index does. Those
// dependencies are a DAG; its vertices are handed to the threads as they
// become free. Returns the vertices moved.
std::size_t applyMoves(RemeshComplex& complex, const Smoother& smoother, const VertexTets& vt,
                       const std::vector<std::int32_t>& level, const std::vector<Eigen::Vector3d>& targets,
                       const std::vector<char>& moves, int threads) {
  const std::int64_t n = std::int64_t(level.size());
  std::vector<std::int32_t> slot(std::size_t(complex.vertexSlots()), -1);
  for (std::int64_t i = 0; i < n; ++i)
    if (moves[std::size_t(i)]) slot[std::size_t(level[std::size_t(i)])] = std::int32_t(i);
  // Later moving neighbours of each moving vertex (CSR), counted then filled.
  std::vector<std::int64_t> start(std::size_t(n) + 1, 0);
  std::vector<std::int32_t> later;
  for (int pass = 0; pass < 2; ++pass) {
    parallelRanges(n, threads, [&](std::int64_t b, std::int64_t e) {
      std::vector<std::int32_t> tets, found;
      for (std::int64_t i = b; i < e; ++i) {
        if ((i - b) % 4096 == 0) throwIfCancelled();
        if (!moves[std::size_t(i)]) continue;
        vt.of(level[std::size_t(i)], tets);
        // Filtered by move index, not by vertex, then sorted once (the star's
        // vertices are not wanted in vertex order here).
        found.clear();
        for (std::int32_t q : tets)
          for (std::int32_t w : complex.tet(q)) {
            const std::int32_t j = w == complex.dummyVertex() ? -1 : slot[std::size_t(w)];
            if (j > i) found.push_back(j);
          }
        std::sort(found.begin(), found.end());
        found.erase(std::unique(found.begin(), found.end()), found.end());
        if (pass == 0)
          start[std::size_t(i) + 1] = std::int64_t(found.size());
        else
          std::copy(found.begin(), found.end(), later.begin() + start[std::size_t(i)]);
      }
    });
    throwIfCancelled();
    if (pass == 0) {
      for (std::int64_t i = 0; i < n; ++i) start[std::size_t(i) + 1] += start[std::size_t(i)];
      later.resize(std::size_t(start.back()));
    }
  }
  std::vector<std::atomic<std::int32_t>> waiting(static_cast<std::size_t>(n));
  for (auto& w : waiting) w.store(0, std::memory_order_relaxed);
  for (std::int32_t j : later) waiting[std::size_t(j)].fetch_add(1, std::memory_order_relaxed);
  std::vector<std::int32_t> ready;
  std::int64_t remaining = 0;
  for (std::int64_t i = n - 1; i >= 0; --i)
    if (moves[std::size_t(i)]) {
      ++remaining;
      if (waiting[std::size_t(i)].load(std::memory_order_relaxed) == 0) ready.push_back(std::int32_t(i));
    }
  std::vector<char> moved(std::size_t(n), 0);
  std::mutex mutex;
  std::condition_variable wake;
  const int workers = std::max(1, threads);
  bool stopped = false;  // a worker failed (or was cancelled): the others leave too
  parallelRanges(workers, workers, [&](std::int64_t, std::int64_t) {
    std::vector<std::int32_t> tets, freed;
    for (;;) {
      std::int32_t i;
      {
        std::unique_lock lock(mutex);
        wake.wait(lock, [&] { return !ready.empty() || remaining == 0 || stopped; });
        if (stopped || ready.empty()) return;
        i = ready.back();
        ready.pop_back();
      }
      try {
        throwIfCancelled();
        moved[std::size_t(i)] = smoother.moveTowards(level[std::size_t(i)], targets[std::size_t(i)], tets);
      } catch (...) {
        {
          std::lock_guard lock(mutex);
          stopped = true;
        }
        wake.notify_all();
        throw;
      }
      freed.clear();
      for (std::int64_t x = start[std::size_t(i)]; x < start[std::size_t(i) + 1]; ++x) {
        const std::int32_t j = later[std::size_t(x)];
        if (waiting[std::size_t(j)].fetch_sub(1, std::memory_order_acq_rel) == 1) freed.push_back(j);
      }
      bool done;
      {
        std::lock_guard lock(mutex);
        ready.insert(ready.end(), freed.begin(), freed.end());
        done = --remaining == 0;
      }
      if (done || freed.size() > 1) wake.notify_all();
      else if (!freed.empty()) wake.notify_one();
    }
  }, 1);
  return std::size_t(std::count(moved.begin(), moved.end(), char(1)));
}

// One pass of polishWorstTets: the vertices of the domain tets under the
// angle, in index order. Returns the vertices moved.
std::size_t polishPass(RemeshComplex& complex, const InterfaceSurfaces* surfaces, const HullConstraint& hull,
                       double angleDeg, int threads, const InterfaceBound* interfaces) {
  const double cosine = std::cos(angleDeg * M_PI / 180.0);
  const std::int32_t nv = complex.vertexSlots();
  // Marks are idempotent writes of 1: racing threads agree.
  std::vector<std::atomic<char>> marks(static_cast<std::size_t>(nv));
  for (auto& m : marks) m.store(0, std::memory_order_relaxed);
  parallelRanges(complex.tetSlots(), threads, [&](std::int64_t b, std::int64_t e) {
    for (std::int32_t t = std::int32_t(b); t < std::int32_t(e); ++t) {
      if (t % 65536 == 0) throwIfCancelled();
      if (!complex.tetAlive(t) || complex.isDummyTet(t) || complex.label(t) <= 0) continue;
      if (complex.minDihedralCosineOf(t) > cosine)
        for (std::int32_t v : complex.tet(t)) marks[std::size_t(v)].store(1, std::memory_order_relaxed);
    }
  });
  throwIfCancelled();
  std::vector<std::int32_t> vertices;
  for (std::int32_t v = 0; v < nv; ++v)
    if (marks[std::size_t(v)].load(std::memory_order_relaxed) && v != complex.dummyVertex()) vertices.push_back(v);
  if (vertices.empty()) return 0;
  const VertexTets vt = vertexTets(complex);
  Smoother smoother(complex, surfaces, hull, vt, interfaces);
  VertexNeighborhood nb;
  std::size_t moved = 0;
  for (std::int32_t v : vertices) {
    throwIfCancelled();
    vt.of(v, nb.tets);
    classifyNeighborhood(complex, v, nb);
    moved += smoother.polish(nb) ? 1 : 0;
  }
  return moved;
}

}  // namespace

std::size_t polishWorstTets(RemeshComplex& complex, const InterfaceSurfaces* surfaces, const HullConstraint& hull,
                            double angleDeg, int threads, const InterfaceBound* interfaces) {
  if (!(angleDeg > 0.0)) return 0;
  // A vertex moved changes its neighbours' stars: a second pass over the
  // tets still poor uses that room.
  std::size_t moved = 0;
  for (int pass = 0; pass < 2; ++pass) {
    const std::size_t n = polishPass(complex, surfaces, hull, angleDeg, threads, interfaces);
    moved += n;
    if (n == 0) break;
  }
  return moved;
}

SmoothCounts smoothVertices(RemeshComplex& complex, const InterfaceSurfaces* surfaces, const HullConstraint& hull,
                            int threads, const InterfaceBound* interfaces) {
  const VertexTets vt = vertexTets(complex);
  const std::int32_t nv = complex.vertexSlots();
  const std::int32_t dummy = complex.dummyVertex();
  constexpr std::uint8_t kSkip = 0xFF;
  std::vector<std::uint8_t> kind(std::size_t(nv), kSkip);
  parallelRanges(nv, threads, [&](std::int64_t b, std::int64_t e) {
    VertexNeighborhood nb;
    for (std::int32_t v = std::int32_t(b); v < std::int32_t(e); ++v) {
      throwIfCancelled();
      if (v == dummy || !complex.vertexAlive(v)) continue;
      vt.of(v, nb.tets);
      classifyNeighborhood(complex, v, nb);
      if (nb.labels[nb.labels.size() - 1] <= 0) continue;  // no domain tet: the imaginary layer is not output
      kind[std::size_t(v)] = std::uint8_t(nb.kind);
    }
  });

  Smoother smoother(complex, surfaces, hull, vt, interfaces);
  SmoothCounts counts;
  std::vector<std::int32_t> level;
  std::vector<Eigen::Vector3d> targets;
  std::vector<char> moves;
  for (VertexKind k : {VertexKind::Feature, VertexKind::Surface, VertexKind::Inside}) {
    throwIfCancelled();
    level.clear();
    for (std::int32_t v = 0; v < nv; ++v)
      if (kind[std::size_t(v)] == std::uint8_t(k)) level.push_back(v);
    targets.assign(level.size(), Eigen::Vector3d::Zero());
    moves.assign(level.size(), 0);
    parallelRanges(std::int64_t(level.size()), threads, [&](std::int64_t b, std::int64_t e) {
      VertexNeighborhood nb;
      for (std::int64_t i = b; i < e; ++i) {
        throwIfCancelled();
        vt.of(level[std::size_t(i)], nb.tets);
        classifyNeighborhood(complex, level[std::size_t(i)], nb);
        moves[std::size_t(i)] = smoother.target(nb, targets[std::size_t(i)]);
      }
    });
    const std::size_t moved = applyMoves(complex, smoother, vt, level, targets, moves, threads);
    (k == VertexKind::Feature ? counts.feature : k == VertexKind::Surface ? counts.surface : counts.inside) = moved;
  }
  return counts;
}

}  // namespace vox::remesh
