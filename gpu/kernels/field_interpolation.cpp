#include "gpu/kernels/field_interpolation.h"

#include "geometry/raster/field_interpolation.h"
#include "geometry/raster/lattice_tets.h"
#include "geometry/error.h"
#include "shaders/shared/interface.h"

#include <algorithm>
#include <cstring>

namespace vox::gpu {

namespace {
using shader::FieldMap;
using shader::RasterTaskPush;
}  // namespace

FieldInterpolationKernel::FieldInterpolationKernel(Context& context, const FieldInterpolationKernelOptions& options)
    : context_(context),
      options_(options),
      locate_(context),
      pipeline_(context, {"interpolate_field.comp",
                          {BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::StorageBuffer,
                           BindingKind::StorageBuffer, BindingKind::StorageBuffer},
                          sizeof(RasterTaskPush)}),
      batch_(context) {}

ScalarGrid FieldInterpolationKernel::run(const TetMesh& mesh, const std::vector<double>& values, const GridGeometry& target,
                                         float fill) {
  validateVertexField(mesh, values);
  target.validate("field grid");
  const std::vector<LatticeTet> tets = latticeTets(target, mesh.positions, mesh.tets);
  ScalarGrid out(target, fill);
  lastGpuMs_ = 0.0;
  std::uint64_t maxPoints = locate_.maxPoints();
  if (options_.maxSlabPoints) maxPoints = std::min(maxPoints, options_.maxSlabPoints);
  const std::int64_t slice = target.sliceVoxels();
  const std::int64_t step = std::max<std::int64_t>(1, std::min<std::int64_t>(0xFFFF, std::int64_t(maxPoints) / slice));
  for (std::int64_t z0 = 0; z0 < target.dims[2]; z0 += step) {
    const std::int64_t z1 = std::min(target.dims[2], z0 + step);
    runSlab(tets, mesh, values, target, fill, z0, z1, out.values.data() + z0 * slice);
  }
  return out;
}

void FieldInterpolationKernel::runSlab(const std::vector<LatticeTet>& tets, const TetMesh& mesh,
                                       const std::vector<double>& values, const GridGeometry& target, float fill,
                                       std::int64_t z0, std::int64_t z1, float* out) {
  const SlabTets slab = slabTets(tets, std::int32_t(z0), std::int32_t(z1));
  if (slab.tets.empty()) return;  // `out` already holds the fill value
  if (!locate_.record(batch_, tets, slab, target)) {
    if (z1 - z0 == 1) throw RuntimeFailure("field interpolation: one grid slice exceeds the GPU's per-binding limits");
    const std::int64_t mid = z0 + (z1 - z0) / 2;
    runSlab(tets, mesh, values, target, fill, z0, mid, out);
    runSlab(tets, mesh, values, target, fill, mid, z1, out + (mid - z0) * target.sliceVoxels());
    return;
  }
  const std::uint64_t mapBytes = slab.tets.size() * sizeof(FieldMap);
  growBuffer(context_, maps_, mapBytes, MemoryIntent::Upload);
  writeHostData(maps_, mapBytes, [&](std::uint8_t* dst) {
    for (std::size_t local = 0; local < slab.tets.size(); ++local) {
      const std::int32_t t = slab.tets[local];
      std::array<Eigen::Matrix<double, 1, 1>, 4> v;
      for (int k = 0; k < 4; ++k) v[std::size_t(k)][0] = values[std::size_t(mesh.tets[std::size_t(t)][std::size_t(k)])];
      const TetAffineMap<1> m = tetAffineMap<1>(tets[std::size_t(t)], v);
      const FieldMap f{m.anchor[0],           m.anchor[1],           m.anchor[2],           float(m.atAnchor[0]),
                       float(m.linear(0, 0)), float(m.linear(0, 1)), float(m.linear(0, 2)), 0.0f};
      std::memcpy(dst + local * sizeof(FieldMap), &f, sizeof(FieldMap));
    }
  });
  const std::uint64_t points = std::uint64_t((z1 - z0) * target.sliceVoxels());
  growBuffer(context_, output_, points * sizeof(float), MemoryIntent::Readback);

  std::uint32_t fillBits;
  std::memcpy(&fillBits, &fill, sizeof(fillBits));
  batch_.fill(output_, fillBits, 0, points * sizeof(float));
  RasterTaskPush push{};
  push.latticeNx = std::uint32_t(target.dims[0]);
  push.latticeNy = std::uint32_t(target.dims[1]);
  push.slabZ0 = std::uint32_t(z0);
  locate_.forTaskDispatches([&](std::uint32_t first, std::uint32_t n, std::uint32_t groups) {
    push.taskBase = first;
    push.taskCount = n;
    batch_.dispatch(pipeline_,
                    {locate_.state(), locate_.tets(), locate_.tasks(), Binding::storage(maps_, 0, std::max<std::uint64_t>(mapBytes, 16)),
                     Binding::storage(output_, 0, points * sizeof(float))},
                    push, groups);
  });
  batch_.barrier();
  batch_.timestamp("end");
  batch_.submitAndWait();
  if (batch_.timings().size() >= 2) lastGpuMs_ += batch_.timings().back().ms;
  output_.download(out, points * sizeof(float));
}

}  // namespace vox::gpu
