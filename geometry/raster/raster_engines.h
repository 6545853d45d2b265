#pragma once
// The engines a deformation run (geometry/deform/run/deform_run.h) does its
// grid-sized work with: the rasterizer of G' and the interpolation of
// per-vertex fields onto grids (the refinement's). CpuRasterEngines are the
// CPU references; gpu/raster_engines.h provides the GPU kernels behind the
// same interface, and the caller chooses (the run knows nothing of Vulkan).

#include "geometry/grid_slices.h"
#include "geometry/label_grid.h"
#include "geometry/raster/field_interpolation.h"
#include "geometry/raster/out_of_core.h"
#include "geometry/raster/rasterize.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace vox {

// The source G' is rasterized from: the whole grid in memory (a GPU engine
// uploads it once), or slices streamed from `slices` (out of core). Both
// must outlive the rasterizer.
struct RasterSource {
  const LabelGrid* grid = nullptr;
  GridSliceReader* slices = nullptr;  // used when grid is null
};

class RasterEngines {
public:
  virtual ~RasterEngines() = default;
  // As the report gives it: "CPU", "GPU (<device name>)".
  virtual const std::string& name() const = 0;
  // Interpolation of vertex fields onto grids; valid until
  // releaseInterpolation() (which frees its buffers before the
  // rasterization's) or the engines' end.
  virtual VertexFieldInterpolation interpolation() = 0;
  virtual void releaseInterpolation() {}
  // G' of the deformed TM positions, slab by slab. `limits`: slab and
  // window sizes under a memory budget (rasterMemoryLimits); null: the
  // engine's own. Throws InputError as RasterizationPlan does.
  virtual std::unique_ptr<SlabRasterizer> rasterizer(const RasterSource& source, const TetMesh& rest,
                                                     const std::vector<Eigen::Vector3d>& deformed, int samples,
                                                     const RasterMemoryLimits* limits) = 0;
};

// The rasterizer of G' on `engines`; slabs and source windows sized by
// `budgetBytes` (rasterMemoryLimits) when positive, else by the engine.
// With writePosedGrid, the path `voxmorph deform` takes (out of core under
// --max-memory).
std::unique_ptr<SlabRasterizer> makeRasterizer(RasterEngines& engines, const RasterSource& source, const TetMesh& rest,
                                               const std::vector<Eigen::Vector3d>& deformed, int samples, std::int64_t budgetBytes);

// The CPU references: CpuSlabRasterizer (every hardware thread) and
// interpolateVertexField.
class CpuRasterEngines final : public RasterEngines {
public:
  const std::string& name() const override { return name_; }
  VertexFieldInterpolation interpolation() override { return cpuFieldInterpolation(); }
  std::unique_ptr<SlabRasterizer> rasterizer(const RasterSource& source, const TetMesh& rest,
                                             const std::vector<Eigen::Vector3d>& deformed, int samples,
                                             const RasterMemoryLimits* limits) override;

private:
  std::string name_ = "CPU";
};

}  // namespace vox
