#include "geometry/label_stats.h"

#include "geometry/grid_slices.h"
#include "geometry/progress.h"

#include <algorithm>

namespace vox {

void LabelStats::resize(std::size_t labels) {
  if (counts.size() < labels) {
    counts.resize(labels, 0);
    boxes.resize(labels);
  }
}

std::size_t LabelStats::presentLabels() const {
  std::size_t n = 0;
  for (std::size_t l = 1; l < counts.size(); ++l) n += counts[l] > 0;
  return n;
}

std::uint64_t LabelStats::foregroundVoxels() const {
  std::uint64_t n = 0;
  for (std::size_t l = 1; l < counts.size(); ++l) n += counts[l];
  return n;
}

void accumulateLabelStats(const GridGeometry& g, std::int64_t k0, std::int64_t count, const Label* slices,
                          LabelStats& stats) {
  const std::int64_t nx = g.dims[0], ny = g.dims[1];
  for (std::int64_t k = k0; k < k0 + count; ++k) {
    for (std::int64_t j = 0; j < ny; ++j) {
      const Label* row = slices + ((k - k0) * ny + j) * nx;
      // Runs of equal labels along a row update the box once.
      for (std::int64_t i = 0; i < nx;) {
        const Label l = row[i];
        std::int64_t e = i + 1;
        while (e < nx && row[e] == l) ++e;
        stats.resize(std::size_t(l) + 1);
        stats.counts[l] += std::uint64_t(e - i);
        LabelBox& b = stats.boxes[l];
        b.lo[0] = std::min(b.lo[0], std::int32_t(i));
        b.hi[0] = std::max(b.hi[0], std::int32_t(e - 1));
        b.lo[1] = std::min(b.lo[1], std::int32_t(j));
        b.hi[1] = std::max(b.hi[1], std::int32_t(j));
        b.lo[2] = std::min(b.lo[2], std::int32_t(k));
        b.hi[2] = std::max(b.hi[2], std::int32_t(k));
        i = e;
      }
    }
  }
}

LabelStats computeLabelStats(const LabelGrid& grid) {
  LabelStats s;
  s.resize(std::size_t(grid.maxLabel()) + 1);
  accumulateLabelStats(grid.geometry(), 0, grid.dims()[2], grid.data(), s);
  return s;
}

LabelStats computeLabelStats(GridSliceReader& reader, std::int64_t bufferBytes) {
  const GridGeometry& g = reader.geometry();
  const std::int64_t sliceBytes = g.sliceVoxels() * std::int64_t(sizeof(Label));
  const std::int64_t slab = std::clamp<std::int64_t>(bufferBytes / sliceBytes, 1, g.dims[2]);
  std::vector<Label> buffer(std::size_t(slab * g.sliceVoxels()));
  LabelStats s;
  ProgressCounter progress("label statistics", double(g.dims[2]));
  for (std::int64_t k = 0; k < g.dims[2]; k += slab) {
    const std::int64_t n = std::min(slab, g.dims[2] - k);
    reader.readSlices(k, n, buffer.data());
    accumulateLabelStats(g, k, n, buffer.data(), s);
    progress.advance(double(n));
  }
  progress.finish();
  return s;
}

}  // namespace vox
