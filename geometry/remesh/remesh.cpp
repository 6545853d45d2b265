#include "geometry/remesh/remesh.h"

#include "geometry/error.h"
#include "geometry/progress.h"
#include "geometry/remesh/collapse_short_edges.h"
#include "geometry/remesh/edge_length_bounds.h"
#include "geometry/remesh/hull_constraint.h"
#include "geometry/remesh/interface_bound.h"
#include "geometry/remesh/interface_surfaces.h"
#include "geometry/remesh/smooth_vertices.h"
#include "geometry/remesh/split_long_edges.h"

#include <chrono>
#include <cmath>
#include <memory>

namespace vox::remesh {

namespace {

// Mean length of the edges of the boundary facets (what the PSS samples).
double meanBoundaryEdgeLength(const RemeshComplex& complex) {
  double sum = 0.0;
  std::size_t count = 0;
  for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
    if (!complex.tetAlive(t) || complex.isDummyTet(t)) continue;
    for (int k = 0; k < 4; ++k) {
      const std::int32_t n = complex.neighbor(t, k);
      if (complex.label(n) == complex.label(t)) continue;
      const Tri f = tetFace(complex.tet(t), k);
      for (int e = 0; e < 3; ++e) {
        sum += (complex.position(f[std::size_t(e)]) - complex.position(f[std::size_t((e + 1) % 3)])).norm();
        ++count;
      }
    }
  }
  return count ? sum / double(count) : 0.0;
}

}  // namespace

void remeshComplex(RemeshComplex& complex, const RemeshOptions& options, RemeshStats* stats) {
  if (!(options.targetLength > 0.0) || !std::isfinite(options.targetLength))
    throw InputError("remesh", "the target edge length must be positive");
  const auto start = std::chrono::steady_clock::now();
  const EdgeLengthBounds bounds = EdgeLengthBounds::forSizing(options.targetLength, options.sizing);
  const HullConstraint hull(complex);
  std::unique_ptr<InterfaceBound> interfaceBound;
  if (options.hausdorff > 0.0)
    interfaceBound = std::make_unique<InterfaceBound>(complex, options.hausdorff * options.targetLength);

  std::unique_ptr<InterfaceSurfaces> surfaces;
  if (options.projectOnInterfaces) {
    const double radius = options.mlsRadius > 0.0
                              ? options.mlsRadius
                              : std::max(0.5 * options.targetLength, meanBoundaryEdgeLength(complex));
    surfaces = std::make_unique<InterfaceSurfaces>(complex, radius, options.hermite);
  }

  const int total = options.iterations + options.flipSmoothCycles;
  reportProgress("remesh", 0.0);
  for (int round = 0; round < total; ++round) {
    const auto t0 = std::chrono::steady_clock::now();
    // Ids along a space-filling curve, so that the stars every operation walks lie close in memory.
    complex.reorderForLocality();
    RemeshStep step;
    const bool refine = round < options.iterations;
    step.name = refine ? "iteration " + std::to_string(round + 1)
                       : "flip-smooth " + std::to_string(round - options.iterations + 1);
    // Four stages per refining round (split, collapse, flip, smooth); flip-smooth cycles run the last two.
    int stage = refine ? 0 : 2;
    auto lap = [&, clock = std::chrono::steady_clock::now()]() mutable {
      const auto now = std::chrono::steady_clock::now();
      const double s = std::chrono::duration<double>(now - clock).count();
      clock = now;
      reportProgress("remesh", (double(round) + double(++stage) / 4.0) / double(total));
      return s;
    };
    if (refine) {
      step.splits = splitLongEdges(complex, bounds, options.threads);
      step.splitSeconds = lap();
      step.collapses = collapseShortEdges(complex, bounds, hull, options.threads, interfaceBound.get());
      step.collapseSeconds = lap();
    }
    FlipOptions flipOptions = options.flip;
    flipOptions.threads = options.threads;
    flipOptions.interfaces = interfaceBound.get();
    const FlipCounts flips = flipEdges(complex, flipOptions);
    step.surfaceFlips = flips.surface;
    step.innerFlips = flips.inner;
    step.faceFlips = flips.face;
    step.flipSeconds = lap();
    const SmoothCounts smoothed = smoothVertices(complex, surfaces.get(), hull, options.threads, interfaceBound.get());
    step.smoothSeconds = lap();
    step.smoothedFeature = smoothed.feature;
    step.smoothedSurface = smoothed.surface;
    step.smoothedInside = smoothed.inside;
    step.tets = complex.liveTetCount();
    step.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (stats) stats->steps.push_back(step);
  }
  // Sliver removal: flips on the poor tets ran in the cycles above; then the
  // vertices of the worst tets move, and Steiner points go where no flip or
  // move helps. The new vertices open room for one more round of flips,
  // moves and insertions.
  const auto polishStart = std::chrono::steady_clock::now();
  std::size_t polished = polishWorstTets(complex, surfaces.get(), hull, options.polishAngle, options.threads,
                                       interfaceBound.get());
  const auto insertStart = std::chrono::steady_clock::now();
  std::size_t inserted = insertSteinerPoints(complex, options.steiner);
  std::size_t sliverFlips = 0;
  if (inserted > 0) {
    FlipOptions flipOptions = options.flip;
    flipOptions.threads = options.threads;
    flipOptions.interfaces = interfaceBound.get();
    const FlipCounts flips = flipEdges(complex, flipOptions);
    sliverFlips = flips.surface + flips.inner + flips.face;
    polished += polishWorstTets(complex, surfaces.get(), hull, options.steiner.angle, options.threads, interfaceBound.get());
    inserted += insertSteinerPoints(complex, options.steiner);
  }
  if (stats) {
    stats->polished = polished;
    stats->polishSeconds = std::chrono::duration<double>(insertStart - polishStart).count();
    stats->inserted = inserted;
    stats->sliverFlips = sliverFlips;
    stats->insertSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - insertStart).count();
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
}

void tagFeatures(RemeshComplex& complex, const RemeshOptions& options, RemeshStats* stats) {
  std::size_t lines = 0;
  if (options.featureSegments && !options.featureSegments->empty())
    lines += tagPolylines(complex, *options.featureSegments, options.targetLength, options.featureAngle,
                          options.featureSource);
  if (options.sharpFeatures)
    lines += tagSharpFeatures(complex, options.featureAngle, options.targetLength * options.targetLength);
  if (stats) {
    stats->featureLines = lines;
    stats->featureEdges = complex.features().edgeCount();
    // What the output's lines are measured against: the creases' edges and
    // the user's polylines as given (not the mesh paths they snapped to).
    stats->featureInput.clear();
    for (std::int32_t line = 0; line < complex.features().lineCount(); ++line) {
      const std::vector<FeatureSegment>& g = complex.features().lineGeometry(line);
      stats->featureInput.insert(stats->featureInput.end(), g.begin(), g.end());
    }
  }
}

TetMesh remeshTetMesh(const TetMesh& mesh, const RemeshOptions& options, RemeshStats* stats, bool keepImaginary,
                      const std::string& source, std::vector<TaggedEdge>* features) {
  RemeshComplex complex(mesh, source);
  tagFeatures(complex, options, stats);
  remeshComplex(complex, options, stats);
  return complex.toTetMesh(keepImaginary, features);
}

}  // namespace vox::remesh
