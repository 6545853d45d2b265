#include "gpu/raster_engines.h"

#include "geometry/error.h"
#include "gpu/kernels/rasterize.h"

namespace vox::gpu {

GpuRasterEngines::GpuRasterEngines(std::unique_ptr<Context> context) : GpuRasterEngines(*context) { owned_ = std::move(context); }

GpuRasterEngines::GpuRasterEngines(Context& context) : context_(&context), name_("GPU (" + context.info().name + ")") {}

GpuRasterEngines::~GpuRasterEngines() = default;

VertexFieldInterpolation GpuRasterEngines::interpolation() {
  if (!interpolation_) interpolation_ = std::make_unique<FieldInterpolationKernel>(*context_);
  return [k = interpolation_.get()](const TetMesh& mesh, const std::vector<double>& values, const GridGeometry& target, float fill) {
    return k->run(mesh, values, target, fill);
  };
}

std::unique_ptr<SlabRasterizer> GpuRasterEngines::rasterizer(const RasterSource& source, const TetMesh& rest,
                                                             const std::vector<Eigen::Vector3d>& deformed, int samples,
                                                             const RasterMemoryLimits* limits) {
  RasterizeKernelOptions options{.samples = samples};
  if (limits) {
    options.maxSlabSamples = std::uint64_t(limits->slabSamples);
    options.maxWindowVoxels = std::uint64_t(limits->windowVoxels);
  }
  auto kernel = source.grid ? std::make_unique<RasterizeKernel>(*context_, *source.grid, rest, options)
                            : std::make_unique<RasterizeKernel>(*context_, *source.slices, rest, options);
  kernel->setDeformedPositions(deformed);
  return kernel;
}

std::unique_ptr<RasterEngines> makeRasterEngines(bool cpu, const std::function<void(const std::string&)>& warn) {
  if (!cpu) {
    try {
      return std::make_unique<GpuRasterEngines>(std::make_unique<Context>());
    } catch (const RuntimeFailure& e) {
      if (warn) warn(std::string(e.what()) + "; using the CPU");
    }
  }
  return std::make_unique<CpuRasterEngines>();
}

}  // namespace vox::gpu
