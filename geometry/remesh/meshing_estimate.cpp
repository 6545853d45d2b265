#include "geometry/remesh/meshing_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace vox::remesh {

namespace {

void finish(MeshingEstimate& e, double targetLength) {
  const double tets = kTetsPerCubicLength * e.domainVolumeMm3 / (targetLength * targetLength * targetLength);
  const double cap = double(std::numeric_limits<std::int64_t>::max() / 1024);
  e.tets = std::int64_t(std::min(cap, std::ceil(tets)));
  e.bytes = std::int64_t(std::min(cap, std::ceil(tets * kRemeshBytesPerTet)));
}

// The peak is at least the starting mesh's.
void boundByStart(MeshingEstimate& e) {
  e.bytes = std::max(e.bytes, std::int64_t(std::ceil(double(e.startTets) * kRemeshBytesPerDecompositionTet)));
}

}  // namespace

MeshingEstimate estimateMeshing(const LabelGrid& grid, double targetLength) {
  const GridGeometry& g = grid.geometry();
  std::int64_t labelled = 0, faces = 0;
  Index3 lo = g.dims, hi{-1, -1, -1};
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const Label l = grid.at(i, j, k);
        // Faces towards +x, +y, +z, and towards -x, -y, -z on the grid's border.
        faces += (l != grid.atOr(i + 1, j, k, 0)) + (l != grid.atOr(i, j + 1, k, 0)) + (l != grid.atOr(i, j, k + 1, 0));
        if (l == 0) continue;
        faces += (i == 0) + (j == 0) + (k == 0);
        ++labelled;
        const Index3 c{i, j, k};
        for (int a = 0; a < 3; ++a) {
          lo[a] = std::min(lo[a], c[a]);
          hi[a] = std::max(hi[a], c[a]);
        }
      }
  MeshingEstimate e;
  e.domainVolumeMm3 = double(labelled) * g.voxelVolume();
  for (int a = 0; a < 3; ++a)
    if (hi[a] >= lo[a]) e.extentMm = std::max(e.extentMm, double(hi[a] - lo[a] + 1) * g.spacing[a]);
  finish(e, targetLength);
  e.startTets = std::int64_t(std::ceil(kDecompositionTetsPerInterfaceFace * double(faces)));
  e.fromGrid = true;
  boundByStart(e);
  return e;
}

MeshingEstimate estimateMeshing(const TetMesh& mesh, double targetLength) {
  MeshingEstimate e;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    if (mesh.labels[t] <= 0) continue;
    ++e.startTets;
    e.domainVolumeMm3 += std::abs(signedVolume(mesh.positions, mesh.tets[t]));
    for (const auto v : mesh.tets[t]) {
      lo = lo.cwiseMin(mesh.positions[std::size_t(v)]);
      hi = hi.cwiseMax(mesh.positions[std::size_t(v)]);
    }
  }
  if (e.domainVolumeMm3 > 0.0) e.extentMm = (hi - lo).maxCoeff();
  finish(e, targetLength);
  // The volume does not bound the work on needles: an edge of length L is
  // split at least ceil(L / e_max) - 1 times, each split adding a tet for
  // every tet around it, so the splits of the input's edges alone add at
  // least the sum over its tets and their edges of that count (a tet 10^16 mm
  // long and 1 mm wide has almost no volume and asks for 10^11 tets at l = 10^5).
  const double emax = 4.0 / 3.0 * targetLength;
  double added = 0.0;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    if (mesh.labels[t] <= 0) continue;
    const Tet& q = mesh.tets[t];
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        added += std::max(0.0, std::ceil((mesh.positions[std::size_t(q[i])] - mesh.positions[std::size_t(q[j])]).norm() / emax) - 1.0);
  }
  const double cap = double(std::numeric_limits<std::int64_t>::max() / 1024);
  if (added > double(e.tets)) {
    e.tets = std::int64_t(std::min(cap, added));
    e.bytes = std::int64_t(std::min(cap, added * kRemeshBytesPerTet));
  }
  boundByStart(e);
  return e;
}

std::string describeEstimate(const MeshingEstimate& e) {
  char tets[48], start[64] = "", memory[32];
  if (e.tets >= 1000000) std::snprintf(tets, sizeof tets, "%.3g M tets", double(e.tets) * 1e-6);
  else std::snprintf(tets, sizeof tets, "%lld tets", (long long)e.tets);
  if (e.startTets > e.tets)
    std::snprintf(start, sizeof start, " (%.3g M in the %s)", double(e.startTets) * 1e-6,
                  e.fromGrid ? "voxel decomposition" : "input");
  const double mb = double(e.bytes) / double(1 << 20);
  if (mb >= 10240.0) std::snprintf(memory, sizeof memory, "%.1f GB", mb / 1024.0);
  else std::snprintf(memory, sizeof memory, "%.0f MB", std::max(1.0, mb));
  return std::string("about ") + tets + start + " and " + memory;
}

}  // namespace vox::remesh
