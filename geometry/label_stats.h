#pragma once
// Per-label voxel counts and bounding boxes: the CPU reference of the GPU
// kernel gpu/kernels/label_stats.

#include "geometry/label_grid.h"

#include <array>
#include <cstdint>
#include <vector>

namespace vox {

struct LabelBox {
  // Inclusive voxel index bounds; an empty label has lo > hi.
  std::array<std::int32_t, 3> lo{INT32_MAX, INT32_MAX, INT32_MAX};
  std::array<std::int32_t, 3> hi{INT32_MIN, INT32_MIN, INT32_MIN};
  bool empty() const { return lo[0] > hi[0]; }
  bool operator==(const LabelBox&) const = default;
};

struct LabelStats {
  std::vector<std::uint64_t> counts;  // indexed by label, size = max label + 1
  std::vector<LabelBox> boxes;        // same size
  bool operator==(const LabelStats&) const = default;

  void resize(std::size_t labels);
  // Number of labels (other than 0) with at least one voxel.
  std::size_t presentLabels() const;
  std::uint64_t foregroundVoxels() const;
};

LabelStats computeLabelStats(const LabelGrid& grid);

class GridSliceReader;
// The same statistics from a grid streamed slab by slab through a buffer of
// at most bufferBytes (one slice at least): memory independent of the grid's
// depth (info --max-memory).
LabelStats computeLabelStats(GridSliceReader& reader, std::int64_t bufferBytes);

// Accumulates slices [k0, k0 + count) of a grid given slice by slice (used by
// the streaming paths); `slices` holds count * nx * ny labels.
void accumulateLabelStats(const GridGeometry& geometry, std::int64_t k0, std::int64_t count, const Label* slices,
                          LabelStats& stats);

}  // namespace vox
