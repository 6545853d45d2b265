#pragma once
// The GPU behind geometry/raster/raster_engines.h: RasterizeKernel for G'
// and FieldInterpolationKernel for the refinement's fields, on one Context.

#include "geometry/raster/raster_engines.h"
#include "gpu/context.h"
#include "gpu/kernels/field_interpolation.h"

#include <functional>
#include <memory>
#include <string>

namespace vox::gpu {

class GpuRasterEngines final : public RasterEngines {
public:
  explicit GpuRasterEngines(std::unique_ptr<Context> context);
  explicit GpuRasterEngines(Context& context);  // which must outlive the engines
  ~GpuRasterEngines() override;

  const std::string& name() const override { return name_; }
  VertexFieldInterpolation interpolation() override;
  void releaseInterpolation() override { interpolation_.reset(); }
  std::unique_ptr<SlabRasterizer> rasterizer(const RasterSource& source, const TetMesh& rest,
                                             const std::vector<Eigen::Vector3d>& deformed, int samples,
                                             const RasterMemoryLimits* limits) override;
  Context& context() { return *context_; }

private:
  std::unique_ptr<Context> owned_;
  Context* context_;
  std::string name_;
  std::unique_ptr<FieldInterpolationKernel> interpolation_;
};

// The engines a command runs on: the GPU's unless `cpu`, or when no device
// can be used (then `warn` says why and the CPU references run).
std::unique_ptr<RasterEngines> makeRasterEngines(bool cpu, const std::function<void(const std::string&)>& warn);

}  // namespace vox::gpu
