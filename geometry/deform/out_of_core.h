#pragma once
// Out-of-core deformation (thesis 4.2.3): the pipeline runs on a downsampled
// copy of the source grid, and only the final rasterization touches full
// resolution, reading the source and writing G' in slabs so that neither is
// ever whole in memory.
//
//   OutOfCoreSource source(path, maxDownsampledVoxels, tempDirectory);
//   ... cage, transfer mesh, deformation on source.downsampled() ...
//   rasterizeOutOfCore(source, tm, deformed, outputPath, options);        // CPU
//   gpu::rasterizeOutOfCore(context, source, tm, deformed, outputPath, options);  // GPU
//
// The downsampled grid keeps the source's grid frame (its voxel corners are
// source voxel corners), so a transfer mesh built on it applies to the source.

#include "geometry/body_projection.h"
#include "geometry/raster/rasterize.h"
#include "geometry/io/grid_io.h"
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
// The smallest factor whose downsampled grid has at most maxVoxels voxels.
int downsampleFactor(const GridGeometry& source, std::int64_t maxVoxels);

// A full-resolution source opened for out-of-core deformation. Construction
// reads the source once, in slice order: it builds the downsampled grid,
// finds the largest label, counts the labels, and copies a compressed file
// (.gz) to a raw temporary in `tempDirectory` so that slab windows can be
// read in any order (the temporary is unlinked at once: nothing is left
// behind, even on a crash). Uncompressed files are read in place.
class OutOfCoreSource {
public:
  OutOfCoreSource(const std::string& path, std::int64_t maxDownsampledVoxels, const std::string& tempDirectory);
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

struct OutOfCoreOptions {
  // Budget (bytes) for the rasterization's slab and source window buffers.
  std::int64_t maxMemoryBytes = std::int64_t(2048) << 20;
  int samples = 1;  // RasterizeOptions::samples
  int threads = 0;  // CPU engine threads; 0 = every hardware thread
};

// How a memory budget splits between a slab's sample states (4 bytes each,
// plus 4 bytes of output per voxel) and the source window (2 bytes a voxel).
struct RasterMemoryLimits {
  std::int64_t slabSamples = 0;
  std::int64_t windowVoxels = 0;
};
RasterMemoryLimits rasterMemoryLimits(std::int64_t budgetBytes, int samples);

// Writes G' to `outputPath` (any format createGridSlices streams: .nii,
// .nii.gz, .mha, .mhd) slab by slab from `engine`; the file appears only
// when complete. `maxLabel` (the source's) decides the stored type.
void writeDeformedGrid(SlabRasterizer& engine, const std::string& outputPath, Label maxLabel);

// Out-of-core rasterization with the CPU reference engine.
void rasterizeOutOfCore(OutOfCoreSource& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed,
                        const std::string& outputPath, const OutOfCoreOptions& options = {});

}  // namespace vox
