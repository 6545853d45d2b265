// libFuzzer harness: the mesh path (voxmorph mesh) on tiny label grids made
// from the bytes: the first three give the dimensions (1 to 8 voxels each),
// the fourth the target length (1 to 4 voxels), the rest the labels (0 to 3,
// missing ones 0). The grid is cut into tets (the adaptive voxel
// tetrahedralization) and remeshed for one round on one thread (no
// flip-smooth cycles, no polish: they walk as a round does, and each costs
// as much), and every label's topology and junction must come out as in the
// grid. An InputError
// (a grid without a labelled voxel) is the expected refusal; anything else
// thrown, a topology change, a hang or a sanitizer report is a finding.

#include "geometry/error.h"
#include "geometry/label_grid.h"
#include "geometry/remesh/adaptive_voxel_tetrahedralization.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh.h"
#include "tests/fuzz/remesh_round.h"

#include <cstdio>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 4) return 0;
  vox::GridGeometry g;
  g.dims = {1 + data[0] % 8, 1 + data[1] % 8, 1 + data[2] % 8};
  const double length = 1.0 + data[3] % 4;
  vox::LabelGrid grid(g, 0);
  std::size_t next = 4;
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i, ++next)
        grid.at(i, j, k) = vox::Label(next < size ? data[next] % 4 : 0);
  try {
    const vox::TetMesh initial = vox::remesh::tetrahedralizeVoxelsAdaptive(grid, vox::remesh::adaptiveOptionsForTarget(g, length));
    const vox::remesh::RemeshOptions options = vox::fuzz::oneRemeshRound(length);
    const vox::TetMesh out = vox::remesh::remeshTetMesh(initial, options, nullptr, false, "grid");
    const auto differences = vox::remesh::compareTopology(vox::remesh::computeGridTopology(grid), vox::remesh::computeMeshTopology(out));
    if (!differences.empty()) {
      std::fprintf(stderr, "topology changed: %s\n", differences.front().c_str());
      std::abort();
    }
  } catch (const vox::InputError&) {
  }
  return 0;
}
