#pragma once
// Locate stage on the GPU (shaders/rasterize_locate.comp), shared by the
// rasterization and field interpolation kernels: for every lattice point of a
// slab, the slab-local index of the lowest-index tet whose closed test it
// passes (VOX_RASTER_NO_TET where none). CPU reference: locateLatticePoints
// in geometry/raster/lattice_tets.h.
//
// Work is one task per (tet, lattice slice, block of VOX_RASTER_ROWS_PER_TASK
// rows): the task walks the tet's scanline spans and claims their points by
// atomicMin, so the cost is one atomic per covered point plus a span per row,
// independent of how many tets a region holds. The later stages (resolve,
// field) reuse the uploaded tets and tasks: each task then handles the points
// its tet won, loading the tet's data once.

#include "geometry/raster/lattice_tets.h"
#include "gpu/buffer.h"
#include "gpu/command.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <vector>

namespace vox::gpu {

class LatticeLocateKernel {
public:
  explicit LatticeLocateKernel(Context& context);

  // Largest slab, in lattice points, whose states fit one storage binding.
  std::uint64_t maxPoints() const;

  // Uploads the slab's tets (float copies of `tets`' planes) and tasks, and
  // records into `batch`: a "locate" timestamp, states <- VOX_RASTER_NO_TET,
  // locate, barrier.
  // Returns false, recording nothing, when the slab's points, tets or tasks
  // exceed one storage binding or its slices exceed the task encoding: the
  // caller splits the slab. The previous use of the buffers must be complete.
  bool record(CommandBatch& batch, const std::vector<LatticeTet>& tets, const SlabTets& slab, const GridGeometry& lattice);

  // The last recorded slab: sample states (its points, lattice order), tets
  // and tasks, as bindings, and the task count.
  Binding state() const { return Binding::storage(state_, 0, stateBytes_); }
  Binding tets() const { return Binding::storage(tets_, 0, tetBytes_); }
  Binding tasks() const { return Binding::storage(tasks_, 0, taskBytes_); }
  std::uint64_t taskCount() const { return taskBytes_ / 8; }

  // Records `dispatch(first, count, groups)` for every slice of the tasks
  // that one dispatch can hold (see dispatchItems).
  void forTaskDispatches(const std::function<void(std::uint32_t first, std::uint32_t count, std::uint32_t groups)>& dispatch) const;

private:
  Context& context_;
  ComputePipeline pipeline_;
  Buffer tets_, tasks_, state_;
  std::uint64_t stateBytes_ = 0, tetBytes_ = 0, taskBytes_ = 0;
};

// Reallocates `buffer` when it holds fewer than `bytes` (at least 16) bytes.
inline void growBuffer(Context& context, Buffer& buffer, std::uint64_t bytes, MemoryIntent intent) {
  bytes = std::max<std::uint64_t>(bytes, 16);
  if (!buffer.valid() || buffer.size() < bytes) {
    buffer = Buffer();
    buffer = Buffer(context, bytes, intent);
  }
}

// fill(dst) writes `bytes` bytes of host data: straight into mapped memory,
// or into one staging buffer of that size copied afterwards.
template <class Fill>
void writeHostData(Buffer& buffer, std::uint64_t bytes, Fill&& fill) {
  // One chunk (granule = bytes): `fill` writes the whole range at once.
  buffer.write(0, bytes, bytes, [&](std::uint64_t, std::uint64_t, std::uint8_t* dst) { fill(dst); });
}

// Dispatches `items` invocations of a 1D kernel in groups of `groupSize`, as
// several dispatches when the work-group count limit requires:
// record(firstItem, itemCount, groups) records one of them.
template <class Record>
void dispatchItems(const Context& context, std::uint64_t items, std::uint32_t groupSize, Record&& record) {
  const std::uint64_t perDispatch = std::uint64_t(context.info().maxWorkGroupCount[0]) * groupSize;
  for (std::uint64_t first = 0; first < items; first += perDispatch) {
    const std::uint64_t n = std::min(perDispatch, items - first);
    record(std::uint32_t(first), std::uint32_t(n), std::uint32_t((n + groupSize - 1) / groupSize));
  }
}

}  // namespace vox::gpu
