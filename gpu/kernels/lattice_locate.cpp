#include "gpu/kernels/lattice_locate.h"

#include "shaders/shared/interface.h"

#include <algorithm>
#include <cstring>

namespace vox::gpu {

namespace {

using shader::RasterTaskPush;
using shader::RasterTet;

RasterTet rasterTet(const LatticeTet& t) {
  RasterTet r{};
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d& n = t.normal[std::size_t(k)];
    const LatticeIndex& a = t.anchor[std::size_t(k)];
    // Rounding is symmetric, so the two tets of a shared face keep exact
    // negatives of each other.
    r.face[k] = {float(n.x()), float(n.y()), float(n.z()), float(t.offset[std::size_t(k)]), a[0], a[1], a[2], 0};
  }
  r.loX = t.lo[0];
  r.hiX = t.hi[0];
  r.loY = t.lo[1];
  r.hiY = t.hi[1];
  r.loZ = t.lo[2];
  r.hiZ = t.hi[2];
  return r;
}

}  // namespace

LatticeLocateKernel::LatticeLocateKernel(Context& context)
    : context_(context),
      pipeline_(context, {"rasterize_locate.comp",
                          {BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::StorageBuffer},
                          sizeof(RasterTaskPush)}) {}

std::uint64_t LatticeLocateKernel::maxPoints() const { return context_.maxBindingBytes() / sizeof(std::uint32_t); }

bool LatticeLocateKernel::record(CommandBatch& batch, const std::vector<LatticeTet>& tets, const SlabTets& slab,
                                 const GridGeometry& lattice) {
  const std::uint64_t binding = context_.maxBindingBytes();
  const std::uint64_t slices = std::uint64_t(slab.z1 - slab.z0);
  const std::uint64_t points = slices * std::uint64_t(lattice.sliceVoxels());
  if (points > maxPoints() || slices > 0xFFFFu || slab.tets.size() * sizeof(RasterTet) > binding) return false;

  const auto forEachTask = [&](auto&& emit) {
    for (std::size_t local = 0; local < slab.tets.size(); ++local) {
      const LatticeTet& t = tets[std::size_t(slab.tets[local])];
      for (std::int32_t z = std::max(t.lo[2], slab.z0); z <= std::min(t.hi[2], slab.z1 - 1); ++z)
        for (std::int32_t y = t.lo[1]; y <= t.hi[1]; y += VOX_RASTER_ROWS_PER_TASK)
          emit(std::uint32_t(local), std::uint32_t(z - slab.z0) | (std::uint32_t(y) << 16));
    }
  };
  std::uint64_t taskCount = 0;
  forEachTask([&](std::uint32_t, std::uint32_t) { ++taskCount; });
  if (taskCount * 8 > binding) return false;

  tetBytes_ = std::max<std::uint64_t>(16, slab.tets.size() * sizeof(RasterTet));
  taskBytes_ = taskCount * 8;
  stateBytes_ = points * sizeof(std::uint32_t);
  growBuffer(context_, tets_, tetBytes_, MemoryIntent::Upload);
  growBuffer(context_, tasks_, taskBytes_, MemoryIntent::Upload);
  growBuffer(context_, state_, stateBytes_, MemoryIntent::Device);
  writeHostData(tets_, tetBytes_, [&](std::uint8_t* dst) {
    for (std::size_t local = 0; local < slab.tets.size(); ++local) {
      const RasterTet r = rasterTet(tets[std::size_t(slab.tets[local])]);
      std::memcpy(dst + local * sizeof(RasterTet), &r, sizeof(RasterTet));
    }
  });
  writeHostData(tasks_, taskBytes_, [&](std::uint8_t* dst) {
    auto* out = reinterpret_cast<std::uint32_t*>(dst);
    forEachTask([&](std::uint32_t local, std::uint32_t zy) {
      *out++ = local;
      *out++ = zy;
    });
  });

  batch.timestamp("locate");
  batch.fill(state_, VOX_RASTER_NO_TET, 0, stateBytes_);
  RasterTaskPush push{};
  push.latticeNx = std::uint32_t(lattice.dims[0]);
  push.latticeNy = std::uint32_t(lattice.dims[1]);
  push.slabZ0 = std::uint32_t(slab.z0);
  forTaskDispatches([&](std::uint32_t first, std::uint32_t n, std::uint32_t groups) {
    push.taskBase = first;
    push.taskCount = n;
    batch.dispatch(pipeline_, {state(), this->tets(), tasks()}, push, groups);
  });
  batch.barrier();
  return true;
}

void LatticeLocateKernel::forTaskDispatches(
    const std::function<void(std::uint32_t first, std::uint32_t count, std::uint32_t groups)>& dispatch) const {
  dispatchItems(context_, taskCount(), VOX_RASTER_TASK_GROUP_SIZE, dispatch);
}

}  // namespace vox::gpu
