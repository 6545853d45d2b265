#include "geometry/raster/field_interpolation.h"

#include "geometry/raster/lattice_tets.h"
#include "geometry/error.h"
#include "geometry/parallel.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace vox {

void validateVertexField(const TetMesh& mesh, const std::vector<double>& values) {
  mesh.validate("field mesh");
  if (values.size() != mesh.positions.size())
    throw InputError("vertex field", std::to_string(values.size()) + " values for a mesh of " +
                                         std::to_string(mesh.positions.size()) + " vertices");
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i])) throw InputError("vertex field", "value " + std::to_string(i) + " is not finite");
}

ScalarGrid interpolateVertexField(const TetMesh& mesh, const std::vector<double>& values, const GridGeometry& target,
                                  const FieldInterpolationOptions& options) {
  validateVertexField(mesh, values);
  target.validate("field grid");

  const std::vector<LatticeTet> tets = latticeTets(target, mesh.positions, mesh.tets);
  ScalarGrid out(target, options.fill);
  const std::int64_t nx = target.dims[0], ny = target.dims[1];
  const std::int64_t slabSlices = slabSlicesHolding(kSlabPoints, target.sliceVoxels());
  forEachLocatedSlab(tets, target, slabSlices, options.threads, [&](const SlabTets& slab, const std::uint32_t* state) {
    const std::int64_t z0 = slab.z0;
    parallelFor((slab.z1 - z0) * ny, options.threads, [&](std::int64_t r) {
      const std::int32_t y = std::int32_t(r % ny), z = std::int32_t(z0 + r / ny);
      const std::uint32_t* in = state + r * nx;
      float* row = out.values.data() + (z0 * ny + r) * nx;
      for (std::int32_t x = 0; x < nx; ++x) {
        if (in[x] == kNoTet) continue;
        const std::int32_t t = slab.tets[in[x]];
        const Eigen::Vector4d lambda = tets[std::size_t(t)].barycentric(x, y, z);
        const Tet& tet = mesh.tets[std::size_t(t)];
        double v = 0.0;
        for (int k = 0; k < 4; ++k) v += lambda[k] * values[std::size_t(tet[std::size_t(k)])];
        row[x] = float(v);
      }
    });
  });
  return out;
}

VertexFieldInterpolation cpuFieldInterpolation(int threads) {
  return [threads](const TetMesh& mesh, const std::vector<double>& values, const GridGeometry& target, float fill) {
    return interpolateVertexField(mesh, values, target, {.fill = fill, .threads = threads});
  };
}

}  // namespace vox
