#include "geometry/deform/cage/envelope.h"

#include "geometry/cancellation.h"
#include "geometry/distance_transform.h"
#include "geometry/deform/cage/restricted_delaunay.h"
#include "geometry/error.h"
#include "geometry/parallel.h"
#include "geometry/progress.h"

#include <cmath>
#include <vector>

namespace vox {

namespace {

// Separable Gaussian of standard deviation sigmaMm (per-axis widths follow
// the spacing), truncated at 3 sigma; values outside the grid count as 0.
void gaussianSmooth(ScalarGrid& field, double sigmaMm) {
  if (sigmaMm <= 0.0) return;
  const GridGeometry& g = field.geometry;
  const std::int64_t dims[3] = {g.dims[0], g.dims[1], g.dims[2]};
  const std::int64_t stride[3] = {1, dims[0], dims[0] * dims[1]};
  for (int axis = 0; axis < 3; ++axis) {
    const double sigma = sigmaMm / g.spacing[axis];
    const int radius = int(std::ceil(3.0 * sigma));
    if (radius == 0) continue;
    std::vector<double> kernel(std::size_t(2 * radius + 1));
    double sum = 0.0;
    for (int r = -radius; r <= radius; ++r) sum += kernel[r + radius] = std::exp(-0.5 * double(r * r) / (sigma * sigma));
    for (double& w : kernel) w /= sum;
    const std::int64_t len = dims[axis];
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    // Lines are independent: ranges of them on the parallel loop.
    parallelRanges(dims[a2], workerThreads(0), [&](std::int64_t u0, std::int64_t u1) {
      std::vector<float> line(static_cast<std::size_t>(len));
      for (std::int64_t u = u0; u < u1; ++u) {
        throwIfCancelled();
        for (std::int64_t t = 0; t < dims[a1]; ++t) {
          const std::int64_t base = t * stride[a1] + u * stride[a2];
          for (std::int64_t p = 0; p < len; ++p) line[std::size_t(p)] = field.values[std::size_t(base + p * stride[axis])];
          for (std::int64_t p = 0; p < len; ++p) {
            double v = 0.0;
            for (int r = -radius; r <= radius; ++r) {
              const std::int64_t q = p + r;
              if (q >= 0 && q < len) v += kernel[std::size_t(r + radius)] * line[std::size_t(q)];
            }
            field.values[std::size_t(base + p * stride[axis])] = float(v);
          }
        }
      }
    }, 4);
  }
}

}  // namespace

TriMesh extractEnvelope(const LabelGrid& grid, const EnvelopeOptions& options) {
  reportProgress("envelope", 0.0);
  // Pad so the smoothed foreground ends two voxels before the border: the
  // level set is closed even where the body touches the grid's faces.
  const GridGeometry padded = padGeometry(grid.geometry(), padForDistance(grid.geometry(), 3.0 * options.smoothingMm, 2));
  const LabelGrid labels = padLabels(grid, padded);
  ScalarGrid smooth(padded, 0.0f);
  bool any = false;
  for (std::size_t v = 0; v < smooth.values.size(); ++v)
    if (labels.labels()[v]) smooth.values[v] = 1.0f, any = true;
  if (!any) throw InputError("grid", "has no foreground voxels to wrap in an envelope");
  gaussianSmooth(smooth, options.smoothingMm);

  LabelGrid inside(padded, 0);
  for (std::size_t v = 0; v < smooth.values.size(); ++v) inside.labels()[v] = Label(smooth.values[v] > 0.5f);
  SampledDomain domain;
  domain.labels = &inside;
  domain.labelAt = [&smooth](const Eigen::Vector3d& p) { return int(smooth.sample(p) > 0.5f); };
  TriMesh envelope = restrictedDelaunaySurface(domain, {options.facetAngleDeg, options.facetSizeMm, options.facetDistanceMm});
  reportProgress("envelope", 1.0);
  return envelope;
}

}  // namespace vox
