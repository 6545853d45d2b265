#pragma once
// Out-of-core deformation (thesis 4.2.3): the pipeline runs on a downsampled
// copy of the source grid, and only the final rasterization touches full
// resolution, reading the source and writing G' in slabs so that neither is
// ever whole in memory.
//
//   OutOfCoreSource source(openGridSlices(path), path, gridSlicesSeekable(path), maxDownsampledVoxels, tempDirectory);
//   ... cage, transfer mesh, deformation on source.downsampled() ...
//   engine = engines.rasterizer(...source.slices()..., rasterMemoryLimits(budget, samples));
//   writePosedGrid(*engine, *createGridSlices(outputPath, engine->outputGeometry(), source.maxLabel()));
//
// (geometry/deform/run/deform_run.cpp does this under --max-memory; the
// engines are raster_engines.h's.)
// The downsampled grid keeps the source's grid frame (its voxel corners are
// source voxel corners), so a transfer mesh built on it applies to the source.

#include "geometry/body_projection.h"
#include "geometry/raster/rasterize.h"
#include "geometry/grid_slices.h"
#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vox {

// Block downsampling by `factor` per axis: a block takes its most frequent
// non-zero label (ties to the lowest), 0 only when all its voxels are 0, so
// the downsampled foreground covers the source's. Geometry: spacing * factor,
// origin moved so that block corners are source voxel corners. Streams the
// source `factor` slices at a time.
LabelGrid downsampleLabels(GridSliceReader& source, int factor);
// The same of a grid in memory, its slices of output on the parallel loop.
LabelGrid downsampleLabels(const LabelGrid& source, int factor);
// The smallest factor whose downsampled grid has at most maxVoxels voxels.
int downsampleFactor(const GridGeometry& source, std::int64_t maxVoxels);

// A full-resolution source opened for out-of-core deformation. Construction
// reads `reader` once, in slice order: it builds the downsampled grid, finds
// the largest label, counts the labels, and unless the reader is `seekable`
// (an uncompressed file) copies the slices to a raw temporary in
// `tempDirectory` so that slab windows can be read in any order (the
// temporary is unlinked at once: nothing is left behind, even on a crash).
// `path` names the source in messages.
class OutOfCoreSource {
public:
  OutOfCoreSource(std::unique_ptr<GridSliceReader> reader, const std::string& path, bool seekable,
                  std::int64_t maxDownsampledVoxels, const std::string& tempDirectory);
  ~OutOfCoreSource();
  OutOfCoreSource(const OutOfCoreSource&) = delete;
  OutOfCoreSource& operator=(const OutOfCoreSource&) = delete;

  const std::string& path() const { return path_; }
  const GridGeometry& geometry() const { return slices_->geometry(); }
  Label maxLabel() const { return maxLabel_; }
  int downsampleFactor() const { return factor_; }
  const LabelGrid& downsampled() const { return downsampled_; }
  // Voxels per label of the full-resolution source (index = label), counted
  // during the read.
  const std::vector<std::uint64_t>& labelCounts() const { return labelCounts_; }
  // The full-resolution source's body projection, measured during the read.
  const BodyProjection& bodyProjection() const { return projection_; }
  // Random access to full-resolution slices.
  GridSliceReader& slices() { return *slices_; }

private:
  std::string path_;
  std::unique_ptr<GridSliceReader> slices_;
  LabelGrid downsampled_;
  Label maxLabel_ = 0;
  int factor_ = 1;
  std::vector<std::uint64_t> labelCounts_;
  BodyProjection projection_;
};

// How a memory budget splits between a slab's sample states (4 bytes each,
// plus 4 bytes of output per voxel) and the source window (2 bytes a voxel).
struct RasterMemoryLimits {
  std::int64_t slabSamples = 0;
  std::int64_t windowVoxels = 0;
};
RasterMemoryLimits rasterMemoryLimits(std::int64_t budgetBytes, int samples);

// A slab engine that measures the slabs it hands out: the posed grid's
// per-label voxel counts and its body projection (body_projection.h),
// without holding the grid.
class MeasuringRasterizer : public SlabRasterizer {
public:
  explicit MeasuringRasterizer(SlabRasterizer& engine) : engine_(engine), projection_(engine.outputGeometry()) {}
  const GridGeometry& outputGeometry() const override { return engine_.outputGeometry(); }
  std::int64_t slabSlices() const override { return engine_.slabSlices(); }
  void rasterizeSlab(std::int64_t z0, std::int64_t z1, Label* out) override;
  // The engine's slab alone, and its measures: rasterizeSlab is the two in turn.
  void rasterizeUnmeasured(std::int64_t z0, std::int64_t z1, Label* out) { engine_.rasterizeSlab(z0, z1, out); }
  void measureSlab(std::int64_t z0, std::int64_t z1, const Label* slab);
  // Voxels per label (index = label) over every slab so far.
  const std::vector<std::uint64_t>& counts() const { return counts_; }
  BodyProjection projection() const { return projection_.result(); }

private:
  SlabRasterizer& engine_;
  std::vector<std::uint64_t> counts_;
  BodyProjectionAccumulator projection_;
};

struct PosedGridMeasures {
  std::vector<std::uint64_t> counts;  // voxels per label (index = label)
  BodyProjection projection;
};

// Writes G' from `engine` to `sink` slab by slab and, with `commit`, commits
// it (a grid file appears complete or not at all; without, the caller
// commits once it has judged the measures); returns G''s per-label voxel
// counts and body projection. A slab is measured on the calling thread while
// another writes it (the sink's encoding and compression, one thread).
PosedGridMeasures writePosedGrid(SlabRasterizer& engine, GridSliceWriter& sink, bool commit = true);

}  // namespace vox
