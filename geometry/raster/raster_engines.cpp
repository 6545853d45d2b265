#include "geometry/raster/raster_engines.h"

namespace vox {

namespace {

// The CPU reference with what it reads from: its plan and, in core, the
// slices of the grid in memory.
class CpuEngine final : public SlabRasterizer {
public:
  CpuEngine(const RasterSource& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed, int samples,
            const RasterMemoryLimits* limits)
      : plan_(source.grid ? source.grid->geometry() : source.slices->geometry(), rest, deformed, samples),
        gridSlices_(source.grid ? std::make_unique<LabelGridSlices>(*source.grid) : nullptr),
        engine_(plan_, gridSlices_ ? *gridSlices_ : *source.slices,
                limits ? CpuRasterizerLimits{.slabSamples = limits->slabSamples, .windowVoxels = limits->windowVoxels}
                       : CpuRasterizerLimits{}) {}
  const GridGeometry& outputGeometry() const override { return engine_.outputGeometry(); }
  std::int64_t slabSlices() const override { return engine_.slabSlices(); }
  void rasterizeSlab(std::int64_t z0, std::int64_t z1, Label* out) override { engine_.rasterizeSlab(z0, z1, out); }

private:
  RasterizationPlan plan_;
  std::unique_ptr<LabelGridSlices> gridSlices_;
  CpuSlabRasterizer engine_;
};

}  // namespace

std::unique_ptr<SlabRasterizer> makeRasterizer(RasterEngines& engines, const RasterSource& source, const TetMesh& rest,
                                               const std::vector<Eigen::Vector3d>& deformed, int samples, std::int64_t budgetBytes) {
  const RasterMemoryLimits limits = budgetBytes > 0 ? rasterMemoryLimits(budgetBytes, samples) : RasterMemoryLimits{};
  return engines.rasterizer(source, rest, deformed, samples, budgetBytes > 0 ? &limits : nullptr);
}

std::unique_ptr<SlabRasterizer> CpuRasterEngines::rasterizer(const RasterSource& source, const TetMesh& rest,
                                                             const std::vector<Eigen::Vector3d>& deformed, int samples,
                                                             const RasterMemoryLimits* limits) {
  return std::make_unique<CpuEngine>(source, rest, deformed, samples, limits);
}

}  // namespace vox
