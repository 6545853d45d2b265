#include "gpu/kernels/rasterize.h"

#include "geometry/error.h"
#include "shaders/shared/interface.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

namespace vox::gpu {

namespace {

using shader::RasterMap;
using shader::RasterReducePush;
using shader::RasterTaskPush;

constexpr std::uint64_t kPartLabels = std::uint64_t(1) << VOX_RASTER_SOURCE_PART_LABELS_LOG2;
constexpr std::uint64_t kPartBytes = kPartLabels * sizeof(Label);

PipelineDesc resolveStage(std::uint32_t sourceParts) {
  PipelineDesc d{"rasterize_resolve.comp", {}, sizeof(RasterTaskPush), {sourceParts}};
  d.bindings.assign(4 + VOX_RASTER_SOURCE_PARTS, BindingKind::StorageBuffer);
  return d;
}

PipelineDesc reduceStage(int samples) {
  if (samples < 1 || samples > VOX_RASTER_MAX_SAMPLES)
    throw InputError("rasterization", "samples per axis must be 1.." + std::to_string(VOX_RASTER_MAX_SAMPLES) + ", got " +
                                          std::to_string(samples));
  return {"rasterize_reduce.comp", {BindingKind::StorageBuffer, BindingKind::StorageBuffer}, sizeof(RasterReducePush),
          {std::uint32_t(samples)}};
}

std::uint64_t windowBytes(const GridGeometry& source, std::int64_t slices) {
  return (std::uint64_t(slices * source.sliceVoxels()) * sizeof(Label) + 3) / 4 * 4;
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
      windowSlices_(windowSlicesFor(context, source_.geometry(), options)),
      resolve_(context, resolveStage(std::uint32_t((windowBytes(source_.geometry(), windowSlices_) + kPartBytes - 1) / kPartBytes))),
      reduce_(context, reduceStage(options.samples)),
      batch_(context) {
  rest_.validate("transfer mesh");
  maxSlabSamples_ = locate_.maxPoints();
  if (options.maxSlabSamples) maxSlabSamples_ = std::min<std::uint64_t>(maxSlabSamples_, options.maxSlabSamples);

  window_ = Buffer(context, windowBytes(source_.geometry(), windowSlices_), MemoryIntent::Device);
}

std::int64_t RasterizeKernel::windowSlicesFor(const Context& context, const GridGeometry& source,
                                              const RasterizeKernelOptions& options) {
  const std::uint64_t slice = std::uint64_t(source.sliceVoxels());
  std::uint64_t capacity = std::min<std::uint64_t>(VOX_RASTER_SOURCE_PARTS * kPartLabels,
                                                   context.info().maxAllocationSize / sizeof(Label));
  if (options.maxWindowVoxels) capacity = std::min<std::uint64_t>(capacity, options.maxWindowVoxels);
  if (slice > capacity)
    throw RuntimeFailure("source slices of " + std::to_string(slice) + " voxels exceed the GPU source window of " +
                         std::to_string(capacity) + " voxels");
  return std::min<std::int64_t>(source.dims[2], std::int64_t(capacity / slice));
}

const RasterizationPlan& RasterizeKernel::plan() const {
  if (!plan_) throw RuntimeFailure("rasterization: deformed positions not set");
  return *plan_;
}

void RasterizeKernel::setDeformedPositions(const std::vector<Eigen::Vector3d>& deformed) {
  plan_ = std::make_unique<RasterizationPlan>(source_.geometry(), rest_, deformed, options_.samples);
  gpuMs_ = locateMs_ = resolveMs_ = 0.0;
}

std::int64_t RasterizeKernel::slabSlices() const {
  const std::int64_t perSlice = plan().samplesPerOutputSlice();
  // The task encoding holds 16 bits of slab lattice slice.
  const std::int64_t bySlices = 0xFFFF / plan().samples();
  return std::max<std::int64_t>(1, std::min<std::int64_t>(bySlices, std::int64_t(maxSlabSamples_) / perSlice));
}

LabelGrid RasterizeKernel::rasterize(const std::vector<Eigen::Vector3d>& deformed) {
  setDeformedPositions(deformed);
  return rasterizeAllSlabs(*this);
}

Binding RasterizeKernel::sourcePart(int part) const {
  const std::uint64_t offset = std::uint64_t(part) * kPartBytes;
  if (offset >= window_.size()) return Binding::storage(window_, 0, std::min(kPartBytes, window_.size()));
  return Binding::storage(window_, offset, std::min(kPartBytes, window_.size() - offset));
}

void RasterizeKernel::loadWindow(const SliceRange& window) {
  // Slice by slice through the staging buffer where the window is not host
  // visible (a discrete GPU): the window is the budget's largest buffer, so no
  // host copy of it is made.
  const std::uint64_t sliceBytes = std::uint64_t(source_.geometry().sliceVoxels()) * sizeof(Label);
  window_.write(0, std::uint64_t(window.count()) * sliceBytes, sliceBytes, [&](std::uint64_t first, std::uint64_t n, std::uint8_t* dst) {
    source_.readSlices(window.first + std::int64_t(first / sliceBytes), std::int64_t(n / sliceBytes), reinterpret_cast<Label*>(dst));
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
  batch_.timestamp("located");

  const std::uint64_t mapBytes = slab.tets.size() * sizeof(RasterMap);
  growBuffer(context_, maps_, mapBytes, MemoryIntent::Upload);
  writeHostData(maps_, mapBytes, [&](std::uint8_t* dst) {
    for (std::size_t local = 0; local < slab.tets.size(); ++local) {
      const RasterMap m = rasterMap(p.sourceMap(slab.tets[local]));
      std::memcpy(dst + local * sizeof(RasterMap), &m, sizeof(RasterMap));
    }
  });
  const auto submit = [&] {
    batch_.submitAndWait();
    const auto& t = batch_.timings();
    // Each stamp ends the stage it names ("locate" and "loaded" start GPU work).
    for (std::size_t i = 1; i < t.size(); ++i) {
      const double ms = t[i].ms - t[i - 1].ms;
      gpuMs_ += ms;
      if (t[i].label == "located") locateMs_ += ms;
      if (t[i].label == "resolved") resolveMs_ += ms;
    }
  };

  const GridGeometry& src = source_.geometry();
  RasterTaskPush push{};
  push.latticeNx = std::uint32_t(p.lattice().dims[0]);
  push.latticeNy = std::uint32_t(p.lattice().dims[1]);
  push.slabZ0 = std::uint32_t(slab.z0);
  push.sourceNx = std::uint32_t(src.dims[0]);
  push.sourceNy = std::uint32_t(src.dims[1]);
  push.sourceNz = std::uint32_t(src.dims[2]);
  const std::vector<SliceRange> windows = sourceWindows(p.sourceSlices(slab), resident_, windowSlices_, src.dims[2]);
  for (std::size_t i = 0; i < windows.size(); ++i) {
    if (!(windows[i] == resident_)) {
      if (i > 0) submit();  // the window buffer is in use by the recorded work
      loadWindow(windows[i]);
      if (i > 0) batch_.timestamp("loaded");
    }
    push.windowFirst = std::uint32_t(windows[i].first);
    push.windowEnd = std::uint32_t(windows[i].last);
    locate_.forTaskDispatches([&](std::uint32_t first, std::uint32_t n, std::uint32_t groups) {
      push.taskBase = first;
      push.taskCount = n;
      batch_.dispatch(resolve_,
                      {locate_.state(), locate_.tets(), locate_.tasks(), Binding::storage(maps_, 0, std::max<std::uint64_t>(mapBytes, 16)),
                       sourcePart(0), sourcePart(1), sourcePart(2), sourcePart(3), sourcePart(4), sourcePart(5), sourcePart(6),
                       sourcePart(7)},
                      push, groups);
    });
    batch_.barrier();
    batch_.timestamp("resolved");
  }

  const std::uint64_t runs = (voxels + VOX_RASTER_REDUCE_RUN - 1) / VOX_RASTER_REDUCE_RUN;
  const std::uint64_t outputBytes = runs * VOX_RASTER_REDUCE_RUN * sizeof(Label);
  growBuffer(context_, output_, outputBytes, MemoryIntent::Readback);
  RasterReducePush reduce{};
  reduce.latticeNx = push.latticeNx;
  reduce.latticeNy = push.latticeNy;
  reduce.outputNx = std::uint32_t(output.dims[0]);
  reduce.outputNy = std::uint32_t(output.dims[1]);
  reduce.voxelCount = std::uint32_t(voxels);
  dispatchItems(context_, runs, VOX_RASTER_REDUCE_GROUP_SIZE, [&](std::uint32_t first, std::uint32_t n, std::uint32_t groups) {
    reduce.runBase = first;
    reduce.runCount = n;
    batch_.dispatch(reduce_, {locate_.state(), Binding::storage(output_, 0, outputBytes)}, reduce, groups);
  });
  batch_.barrier();
  batch_.timestamp("reduced");
  submit();
  output_.download(out, voxels * sizeof(Label));
}

}  // namespace vox::gpu
