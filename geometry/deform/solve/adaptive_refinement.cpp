#include "geometry/deform/solve/adaptive_refinement.h"

#include "geometry/deform/solve/deformation_metrics.h"
#include "geometry/raster/field_interpolation.h"
#include "geometry/progress.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace vox {

namespace {

// Voxels within this many 6-neighbour steps of the TM's covered voxels take
// their neighbours' factor: the TM's boundary lies 1.4 voxels off the
// foreground, and the mesher samples F there.
constexpr int kExtensionRings = 2;

// Eq. 4.7's factor cbrt(e_mean / max(e_g, e_mean)) per voxel (0 where the
// voxel is neither covered nor near a covered one).
std::vector<float> sizingFactors(const GridError& error) {
  const GridGeometry& g = error.field.geometry;
  std::vector<float> factor(error.field.values.size(), 0.0f);
  if (!(error.mean > 0.0)) {
    for (std::size_t v = 0; v < factor.size(); ++v) factor[v] = error.field.values[v] >= 0.0f ? 1.0f : 0.0f;
    return factor;
  }
  for (std::size_t v = 0; v < factor.size(); ++v) {
    const double e = error.field.values[v];
    if (e >= 0.0) factor[v] = float(std::cbrt(error.mean / std::max(e, error.mean)));
  }
  for (int ring = 0; ring < kExtensionRings; ++ring) {
    std::vector<float> next = factor;
    for (std::int64_t k = 0; k < g.dims[2]; ++k)
      for (std::int64_t j = 0; j < g.dims[1]; ++j)
        for (std::int64_t i = 0; i < g.dims[0]; ++i) {
          const std::int64_t v = g.index(i, j, k);
          if (factor[std::size_t(v)] > 0.0f) continue;
          float best = 0.0f;
          const std::int64_t n[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
          for (const auto& q : n)
            if (g.contains(q[0], q[1], q[2])) {
              const float f = factor[std::size_t(g.index(q[0], q[1], q[2]))];
              if (f > 0.0f && (best == 0.0f || f < best)) best = f;
            }
          next[std::size_t(v)] = best;
        }
    factor = std::move(next);
  }
  return factor;
}

// Predicted tet count ratio for strength s: the mean of factor^(-3 s) over
// the covered voxels.
double predictedGrowth(const GridError& error, const std::vector<float>& factor, double strength) {
  double sum = 0.0;
  std::int64_t n = 0;
  for (std::size_t v = 0; v < factor.size(); ++v)
    if (error.field.values[v] >= 0.0f) {
      sum += std::pow(double(factor[v]), -3.0 * strength);
      ++n;
    }
  return n > 0 ? sum / double(n) : 1.0;
}

void applyFactors(ScalarGrid& sizing, const std::vector<float>& factor, double strength) {
  for (std::size_t v = 0; v < factor.size(); ++v)
    if (factor[v] > 0.0f) sizing.values[v] *= float(std::pow(double(factor[v]), strength));
}

}  // namespace

GridError gridDeformationError(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed, const GridGeometry& geometry,
                               const VertexFieldInterpolation& interpolate) {
  const std::vector<double> tetError = tetDeformationError(rest, deformed);
  const std::vector<double> vertexError = vertexDeformationError(rest, tetError);
  GridError out;
  out.field = interpolate(rest, vertexError, geometry, -1.0f);
  double sum = 0.0;
  for (const float e : out.field.values)
    if (e >= 0.0f) {
      sum += e;
      out.max = std::max(out.max, double(e));
      ++out.coveredVoxels;
    }
  out.mean = out.coveredVoxels > 0 ? sum / double(out.coveredVoxels) : 0.0;
  return out;
}

double updateSizingField(ScalarGrid& sizing, const GridError& error, double strength) {
  const std::vector<float> factor = sizingFactors(error);
  applyFactors(sizing, factor, strength);
  return predictedGrowth(error, factor, strength);
}

RefinementResult refineTransferMesh(const RefinementSubject& subject, ScalarGrid& sizing,
                                    const VertexFieldInterpolation& interpolate, const RefinementOptions& options) {
  using Clock = std::chrono::steady_clock;
  RefinementResult result;
  auto measure = [&](double seconds) {
    const TetMesh& rest = subject.restMesh();
    GridError error = gridDeformationError(rest, subject.deformedPositions(), sizing.geometry, interpolate);
    result.steps.push_back({.vertices = rest.vertexCount(),
                            .tets = rest.tetCount(),
                            .meanError = error.mean,
                            .maxError = error.max,
                            .seconds = seconds});
    return error;
  };
  reportProgress("refinement", 0.0);
  GridError error = measure(0.0);
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
    // The strongest update (s <= 1) whose predicted TM fits the budget.
    const std::vector<float> factor = sizingFactors(error);
    const double tets = double(step.tets);
    double strength = 1.0;
    if (tets * predictedGrowth(error, factor, 1.0) > double(options.maxTets)) {
      double lo = 0.0, hi = 1.0;
      for (int b = 0; b < 20; ++b) {
        const double mid = 0.5 * (lo + hi);
        (tets * predictedGrowth(error, factor, mid) <= double(options.maxTets) ? lo : hi) = mid;
      }
      strength = lo;
    }
    // Below this the update would move F by a few percent at most.
    constexpr double kMinStrength = 0.1;
    if (strength < kMinStrength) {
      result.stopReason = "tet budget";
      break;
    }
    applyFactors(sizing, factor, strength);
    result.steps.back().strength = strength;
    const auto start = Clock::now();
    subject.regenerate(sizing);
    error = measure(std::chrono::duration<double>(Clock::now() - start).count());
    reportProgress("refinement", double(iteration + 1) / double(std::max(options.maxIterations, 1)));
  }
  reportProgress("refinement", 1.0);
  return result;
}

}  // namespace vox
