#include "geometry/voxel_tetrahedralization.h"

#include <array>

namespace vox {

TetMesh tetrahedralizeVoxels(const LabelGrid& grid, const VoxelTetrahedralizationOptions& options) {
  const GridGeometry& g = grid.geometry();
  const std::int64_t cx = g.dims[0] + 1, cy = g.dims[1] + 1, cz = g.dims[2] + 1;
  auto corner = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return i + cx * (j + cy * k); };

  // Kuhn decomposition: one tet per axis permutation, walking from corner
  // (0,0,0) to (1,1,1) one axis at a time.
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  std::array<std::array<std::array<int, 3>, 4>, 6> offsets{};
  for (int t = 0; t < 6; ++t) {
    std::array<int, 3> c{0, 0, 0};
    offsets[t][0] = c;
    for (int s = 0; s < 3; ++s) {
      c[kPerm[t][s]] = 1;
      offsets[t][s + 1] = c;
    }
  }
  // Odd permutations give negatively oriented tets: swap their last two vertices.
  for (int t : {1, 2, 5}) std::swap(offsets[t][2], offsets[t][3]);

  std::vector<std::int32_t> remap(std::size_t(cx * cy * cz), -1);
  TetMesh mesh;
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const Label l = grid.at(i, j, k);
        if (l == 0 && !options.includeBackground) continue;
        for (int t = 0; t < 6; ++t) {
          Tet tet;
          for (int v = 0; v < 4; ++v) {
            const auto& o = offsets[t][v];
            const std::int64_t c = corner(i + o[0], j + o[1], k + o[2]);
            tet[v] = std::int32_t(c);  // corner index for now, compacted below
            remap[std::size_t(c)] = 0;
          }
          mesh.tets.push_back(tet);
          mesh.labels.push_back(std::int32_t(l));
        }
      }
  std::int32_t next = 0;
  for (std::int64_t k = 0; k < cz; ++k)
    for (std::int64_t j = 0; j < cy; ++j)
      for (std::int64_t i = 0; i < cx; ++i) {
        auto& r = remap[std::size_t(corner(i, j, k))];
        if (r < 0) continue;
        r = next++;
        mesh.positions.push_back(g.origin + g.spacing.cwiseProduct(Eigen::Vector3d(double(i) - 0.5, double(j) - 0.5, double(k) - 0.5)));
      }
  for (Tet& t : mesh.tets)
    for (auto& v : t) v = remap[std::size_t(v)];
  return mesh;
}

}  // namespace vox
