#pragma once
// Label grids by whole z-slices: the source a slab-wise consumer reads
// (label statistics, downsampling, rasterization of G') and the sink a
// slab-wise producer writes. The grid formats implement both
// (io/grid_io.h: openGridSlices, createGridSlices); LabelGridSlices reads
// a grid in memory.

#include "geometry/label_grid.h"

#include <cstdint>

namespace vox {

// Streaming access by whole z-slices, for grids that do not fit in memory.
// Slices must be requested in non-decreasing order for compressed files.
class GridSliceReader {
public:
  virtual ~GridSliceReader() = default;
  virtual const GridGeometry& geometry() const = 0;
  // Reads `count` slices starting at slice k0 into out (count * nx * ny labels).
  virtual void readSlices(std::int64_t k0, std::int64_t count, Label* out) = 0;
};

// Writes a grid slice by slice; commit() completes it once every slice was
// written (the file formats: a temporary renamed into place). Destroying it
// without commit() leaves nothing.
class GridSliceWriter {
public:
  virtual ~GridSliceWriter() = default;
  virtual void writeSlices(const Label* in, std::int64_t count) = 0;
  virtual void commit() = 0;
};

// A GridSliceReader over an in-memory grid (which must outlive it).
class LabelGridSlices : public GridSliceReader {
public:
  explicit LabelGridSlices(const LabelGrid& grid) : grid_(grid) {}
  const GridGeometry& geometry() const override { return grid_.geometry(); }
  void readSlices(std::int64_t k0, std::int64_t count, Label* out) override;
  const LabelGrid& grid() const { return grid_; }

private:
  const LabelGrid& grid_;
};

}  // namespace vox
