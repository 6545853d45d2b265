#include "gpu/kernels/rasterize.h"

#include "geometry/error.h"
#include "geometry/progress.h"
#include "shaders/shared/interface.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

namespace vox::gpu {

namespace {

using shader::RasterMap;
using shader::RasterResolvePush;

constexpr std::uint64_t kPartLabels = std::uint64_t(1) << VOX_RASTER_SOURCE_PART_LABELS_LOG2;
constexpr std::uint64_t kPartBytes = kPartLabels * sizeof(Label);

PipelineDesc windowStage(const char* shader) {
  PipelineDesc d{shader, {BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::StorageBuffer}, sizeof(RasterResolvePush)};
  for (int p = 0; p < VOX_RASTER_SOURCE_PARTS; ++p) d.bindings.push_back(BindingKind::StorageBuffer);
  return d;
}

RasterMap rasterMap(const TetAffineMap<3>& m) {
  RasterMap r{};
  r.ax = m.anchor[0];
  r.ay = m.anchor[1];
  r.az = m.anchor[2];
  // Integer part and a small fraction: float keeps the fraction's precision
  // whatever the grid size.
  const Eigen::Vector3d whole = (m.atAnchor.array() + 0.5).floor().matrix();
  const Eigen::Vector3d frac = m.atAnchor - whole;
  r.sx = std::int32_t(whole.x());
  r.sy = std::int32_t(whole.y());
  r.sz = std::int32_t(whole.z());
  r.fx = float(frac.x());
  r.fy = float(frac.y());
  r.fz = float(frac.z());
  float* l = &r.l00;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) l[3 * i + j] = float(m.linear(i, j));
  return r;
}

}  // namespace

RasterizeKernel::RasterizeKernel(Context& context, const LabelGrid& source, const TetMesh& rest,
                                 const RasterizeKernelOptions& options)
    : RasterizeKernel(context, std::make_unique<LabelGridSlices>(source), nullptr, rest, options) {}

RasterizeKernel::RasterizeKernel(Context& context, GridSliceReader& source, const TetMesh& rest,
                                 const RasterizeKernelOptions& options)
    : RasterizeKernel(context, nullptr, &source, rest, options) {}

RasterizeKernel::RasterizeKernel(Context& context, std::unique_ptr<GridSliceReader> owned, GridSliceReader* borrowed,
                                 const TetMesh& rest, const RasterizeKernelOptions& options)
    : context_(context),
      ownedSource_(std::move(owned)),
      source_(borrowed ? *borrowed : *ownedSource_),
      rest_(rest),
      options_(options),
      locate_(context),
      resolve_(context, windowStage("rasterize_resolve.comp")),
      reduce_(context, windowStage("rasterize_reduce.comp")),
      batch_(context) {
  if (options.samples < 1 || options.samples > VOX_RASTER_MAX_SAMPLES)
    throw InputError("rasterization", "samples per axis must be 1.." + std::to_string(VOX_RASTER_MAX_SAMPLES) + ", got " +
                                          std::to_string(options.samples));
  rest_.validate("transfer mesh");
  maxSlabSamples_ = locate_.maxPoints();
  if (options.maxSlabSamples) maxSlabSamples_ = std::min<std::uint64_t>(maxSlabSamples_, options.maxSlabSamples);

  const GridGeometry& g = source_.geometry();
  const std::uint64_t slice = std::uint64_t(g.sliceVoxels());
  std::uint64_t capacity = std::min<std::uint64_t>(VOX_RASTER_SOURCE_PARTS * kPartLabels,
                                                   context.info().maxAllocationSize / sizeof(Label));
  if (options.maxWindowVoxels) capacity = std::min<std::uint64_t>(capacity, options.maxWindowVoxels);
  if (slice > capacity)
    throw RuntimeFailure("source slices of " + std::to_string(slice) + " voxels exceed the GPU source window of " +
                         std::to_string(capacity) + " voxels");
  windowSlices_ = std::min<std::int64_t>(g.dims[2], std::int64_t(capacity / slice));
  window_ = Buffer(context, (std::uint64_t(windowSlices_) * slice * sizeof(Label) + 3) / 4 * 4, MemoryIntent::Device);
}

const RasterizationPlan& RasterizeKernel::plan() const {
  if (!plan_) throw RuntimeFailure("rasterization: deformed positions not set");
  return *plan_;
}

void RasterizeKernel::setDeformedPositions(const std::vector<Eigen::Vector3d>& deformed) {
  plan_ = std::make_unique<RasterizationPlan>(source_.geometry(), rest_, deformed, options_.samples);
  gpuMs_ = 0.0;
}

std::int64_t RasterizeKernel::slabSlices() const {
  const std::int64_t perSlice = plan().samplesPerOutputSlice();
  // The task encoding holds 16 bits of slab lattice slice.
  const std::int64_t bySlices = 0xFFFF / plan().samples();
  return std::max<std::int64_t>(1, std::min<std::int64_t>(bySlices, std::int64_t(maxSlabSamples_) / perSlice));
}

LabelGrid RasterizeKernel::rasterize(const std::vector<Eigen::Vector3d>& deformed) {
  setDeformedPositions(deformed);
  LabelGrid out(plan_->output());
  const std::int64_t nz = out.dims()[2], step = slabSlices();
  ProgressCounter progress("rasterize", double(nz));
  for (std::int64_t z0 = 0; z0 < nz; z0 += step) {
    const std::int64_t z1 = std::min(nz, z0 + step);
    rasterizeSlab(z0, z1, out.data() + z0 * out.geometry().sliceVoxels());
    progress.advance(double(z1 - z0));
  }
  progress.finish();
  return out;
}

Binding RasterizeKernel::sourcePart(int part) const {
  const std::uint64_t offset = std::uint64_t(part) * kPartBytes;
  if (offset >= window_.size()) return Binding::storage(window_, 0, std::min(kPartBytes, window_.size()));
  return Binding::storage(window_, offset, std::min(kPartBytes, window_.size() - offset));
}

void RasterizeKernel::loadWindow(const SliceRange& window) {
  const std::uint64_t labels = std::uint64_t(window.count() * source_.geometry().sliceVoxels());
  writeHostData(window_, labels * sizeof(Label), [&](std::uint8_t* dst) {
    source_.readSlices(window.first, window.count(), reinterpret_cast<Label*>(dst));
  });
  resident_ = window;
}

void RasterizeKernel::rasterizeSlab(std::int64_t z0, std::int64_t z1, Label* out) {
  const RasterizationPlan& p = plan();
  const GridGeometry& output = p.output();
  const std::uint64_t voxels = std::uint64_t((z1 - z0) * output.sliceVoxels());
  const SlabTets slab = p.slab(z0, z1);
  if (slab.tets.empty()) {
    std::fill(out, out + voxels, Label(0));
    return;
  }
  if (std::uint64_t((z1 - z0) * p.samplesPerOutputSlice()) > maxSlabSamples_ ||
      !locate_.record(batch_, p.tets(), slab, p.lattice())) {
    if (z1 - z0 == 1)
      throw RuntimeFailure("rasterization: one output slice (" + std::to_string(p.samplesPerOutputSlice()) + " samples, " +
                           std::to_string(slab.tets.size()) + " tets) exceeds the GPU's per-binding limits");
    const std::int64_t mid = z0 + (z1 - z0) / 2;
    rasterizeSlab(z0, mid, out);
    rasterizeSlab(mid, z1, out + (mid - z0) * output.sliceVoxels());
    return;
  }
  batch_.timestamp("start");

  const std::uint64_t mapBytes = slab.tets.size() * sizeof(RasterMap);
  growBuffer(context_, maps_, mapBytes, MemoryIntent::Upload);
  writeHostData(maps_, mapBytes, [&](std::uint8_t* dst) {
    for (std::size_t local = 0; local < slab.tets.size(); ++local) {
      const RasterMap m = rasterMap(p.sourceMap(slab.tets[local]));
      std::memcpy(dst + local * sizeof(RasterMap), &m, sizeof(RasterMap));
    }
  });
  const std::uint64_t pairs = (voxels + 1) / 2;
  growBuffer(context_, output_, pairs * 4, MemoryIntent::Readback);

  const GridGeometry& src = source_.geometry();
  RasterResolvePush push{};
  push.latticeNx = std::uint32_t(p.lattice().dims[0]);
  push.latticeNy = std::uint32_t(p.lattice().dims[1]);
  push.slabZ0 = std::uint32_t(slab.z0);
  push.samples = std::uint32_t(p.samples());
  push.outputNx = std::uint32_t(output.dims[0]);
  push.outputNy = std::uint32_t(output.dims[1]);
  push.voxelCount = std::uint32_t(voxels);
  push.sourceNx = std::uint32_t(src.dims[0]);
  push.sourceNy = std::uint32_t(src.dims[1]);
  push.sourceNz = std::uint32_t(src.dims[2]);
  const auto record = [&](const ComputePipeline& stage, std::uint64_t items) {
    dispatchItems(context_, items, VOX_RASTER_GROUP_SIZE, [&](std::uint32_t first, std::uint32_t n, std::uint32_t groups) {
      push.itemBase = first;
      push.itemCount = n;
      batch_.dispatch(stage,
                      {Binding::storage(locate_.state(), 0, locate_.stateBytes()), Binding::storage(maps_, 0, std::max<std::uint64_t>(mapBytes, 16)),
                       Binding::storage(output_, 0, std::max<std::uint64_t>(pairs * 4, 16)), sourcePart(0), sourcePart(1), sourcePart(2),
                       sourcePart(3), sourcePart(4), sourcePart(5), sourcePart(6), sourcePart(7)},
                      push, groups);
    });
    batch_.barrier();
  };
  const auto submit = [&] {
    batch_.timestamp("end");
    batch_.submitAndWait();
    if (batch_.timings().size() >= 2) gpuMs_ += batch_.timings().back().ms;
  };

  const std::vector<SliceRange> windows = sourceWindows(p.sourceSlices(slab), resident_, windowSlices_, src.dims[2]);
  for (std::size_t i = 0; i < windows.size(); ++i) {
    if (!(windows[i] == resident_)) {
      if (i > 0) {  // the window buffer is in use by the recorded work
        submit();
        batch_.timestamp("start");
      }
      loadWindow(windows[i]);
    }
    push.windowFirst = std::uint32_t(windows[i].first);
    push.windowEnd = std::uint32_t(windows[i].last);
    if (i + 1 < windows.size()) record(resolve_, locate_.stateBytes() / sizeof(std::uint32_t));
  }
  if (windows.empty()) push.windowFirst = push.windowEnd = 0;
  record(reduce_, pairs);
  submit();
  output_.download(out, voxels * sizeof(Label));
}

void rasterizeOutOfCore(Context& context, OutOfCoreSource& source, const TetMesh& rest,
                        const std::vector<Eigen::Vector3d>& deformed, const std::string& outputPath,
                        const OutOfCoreOptions& options) {
  const RasterMemoryLimits limits = rasterMemoryLimits(options.maxMemoryBytes, options.samples);
  RasterizeKernel kernel(context, source.slices(), rest,
                         {.samples = options.samples,
                          .maxSlabSamples = std::uint64_t(limits.slabSamples),
                          .maxWindowVoxels = std::uint64_t(limits.windowVoxels)});
  kernel.setDeformedPositions(deformed);
  writeDeformedGrid(kernel, outputPath, source.maxLabel());
}

}  // namespace vox::gpu
