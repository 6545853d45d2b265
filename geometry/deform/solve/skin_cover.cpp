#include "geometry/deform/solve/skin_cover.h"

#include "geometry/parallel.h"
#include "geometry/raster/lattice_tets.h"
#include "geometry/raster/rasterize.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace vox {

namespace {

bool flagged(std::span<const std::uint8_t> flags, Label l) { return std::size_t(l) < flags.size() && flags[l] != 0; }

// The skin label most frequent in the smallest cube about (x, y, z) that
// holds skin, up to kSkinSearchVoxels away; 0 when none does.
Label nearestSkin(const LabelGrid& grid, std::span<const std::uint8_t> skin, std::int64_t x, std::int64_t y, std::int64_t z) {
  const auto& d = grid.dims();
  std::vector<std::uint32_t> count(skin.size(), 0);
  for (int r = 1; r <= kSkinSearchVoxels; ++r) {
    bool any = false;
    for (std::int64_t k = std::max<std::int64_t>(0, z - r); k <= std::min<std::int64_t>(d[2] - 1, z + r); ++k)
      for (std::int64_t j = std::max<std::int64_t>(0, y - r); j <= std::min<std::int64_t>(d[1] - 1, y + r); ++j)
        for (std::int64_t i = std::max<std::int64_t>(0, x - r); i <= std::min<std::int64_t>(d[0] - 1, x + r); ++i) {
          // The cube's shell only: the inner cube was counted at r - 1.
          if (std::abs(i - x) < r && std::abs(j - y) < r && std::abs(k - z) < r) continue;
          const Label l = grid.at(i, j, k);
          if (flagged(skin, l)) {
            ++count[l];
            any = true;
          }
        }
    if (any) return Label(std::max_element(count.begin(), count.end()) - count.begin());
  }
  return 0;
}

constexpr std::uint8_t kBare = 1, kBoneInAir = 2;

// Per voxel of `grid`: kBare for a bare voxel (skin_cover.h), kBoneInAir for
// a bone voxel that faces background (with `bone` empty: none), else 0.
std::vector<std::uint8_t> surfaceFlags(const LabelGrid& grid, std::span<const std::uint8_t> skin, std::span<const std::uint8_t> bone,
                                       int threads) {
  const std::int64_t nx = grid.dims()[0], ny = grid.dims()[1], nz = grid.dims()[2];
  const Label* labels = grid.data();
  std::vector<std::uint8_t> flags(std::size_t(grid.voxelCount()), 0);
  parallelFor(nz, threads, [&](std::int64_t z) {
    for (std::int64_t y = 0; y < ny; ++y)
      for (std::int64_t x = 0; x < nx; ++x) {
        const std::int64_t v = (z * ny + y) * nx + x;
        const Label l = labels[v];
        if (l == 0 || flagged(skin, l)) continue;
        const bool faces = x == 0 || x + 1 == nx || y == 0 || y + 1 == ny || z == 0 || z + 1 == nz || labels[v - 1] == 0 ||
                           labels[v + 1] == 0 || labels[v - nx] == 0 || labels[v + nx] == 0 || labels[v - nx * ny] == 0 ||
                           labels[v + nx * ny] == 0;
        if (!faces) continue;
        if (flagged(bone, l)) flags[std::size_t(v)] = kBoneInAir;
        bool nearSkin = false;
        for (std::int64_t k = std::max<std::int64_t>(0, z - 1); k <= std::min(nz - 1, z + 1) && !nearSkin; ++k)
          for (std::int64_t j = std::max<std::int64_t>(0, y - 1); j <= std::min(ny - 1, y + 1) && !nearSkin; ++j)
            for (std::int64_t i = std::max<std::int64_t>(0, x - 1); i <= std::min(nx - 1, x + 1); ++i)
              if (flagged(skin, labels[(k * ny + j) * nx + i])) {
                nearSkin = true;
                break;
              }
        if (!nearSkin) flags[std::size_t(v)] |= kBare;
      }
  });
  return flags;
}

}  // namespace

std::vector<std::uint8_t> bareVoxels(const LabelGrid& grid, std::span<const std::uint8_t> skin, int threads) {
  return surfaceFlags(grid, skin, {}, threads);  // without bone flags: kBare or 0
}

SkinCover coverBareTissue(LabelGrid& posed, const LabelGrid& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed,
                          std::span<const std::uint8_t> skin, std::span<const std::uint8_t> bone, int threads) {
  SkinCover result;
  if (std::find(skin.begin(), skin.end(), std::uint8_t(1)) == skin.end()) return result;
  const RasterizationPlan plan(source.geometry(), rest, deformed, 1);
  const GridGeometry& out = plan.output();
  requireOutputGrid(posed, out);

  // bare: the posed surface's flags, then per flagged voxel 1 (as at rest:
  // left) or 2 (to cover).
  std::vector<std::uint8_t> bare = surfaceFlags(posed, skin, bone, threads);
  if (std::all_of(bare.begin(), bare.end(), [](std::uint8_t f) { return f == 0; })) return result;
  const std::vector<std::uint8_t> atRest = surfaceFlags(source, skin, bone, threads);

  // Each flagged voxel through its tet to the source: a bare voxel whose
  // source voxel is bare too, a bone voxel in the air whose source voxel is
  // in the air too, stays (1); else it is covered (2), as is a voxel no tet
  // holds (a filled gap).
  const std::int64_t slice = out.sliceVoxels(), nx = out.dims[0], ny = out.dims[1];
  const std::int64_t slabSlices = slabSlicesHolding(kSlabPoints / 2, slice);
  const auto& sd = source.dims();
  forEachLocatedSlab(plan.tets(), plan.lattice(), slabSlices, threads, [&](const SlabTets& slab, const std::uint32_t* state) {
    parallelFor(std::int64_t(slab.z1 - slab.z0) * ny, threads, [&](std::int64_t r) {
      const std::int32_t y = std::int32_t(r % ny), z = std::int32_t(slab.z0 + r / ny);
      for (std::int32_t x = 0; x < nx; ++x) {
        const std::int64_t voxel = out.index(x, y, z);
        if (!bare[std::size_t(voxel)]) continue;
        const std::uint32_t s = state[r * nx + x];
        if (s == kNoTet) {
          bare[std::size_t(voxel)] = 2;
          continue;
        }
        const std::int32_t t = slab.tets[s];
        const Eigen::Vector4d lambda = plan.tets()[std::size_t(t)].barycentric(x, y, z);
        const auto c = plan.restCorners(t);
        const Eigen::Vector3d p = lambda[0] * c[0] + lambda[1] * c[1] + lambda[2] * c[2] + lambda[3] * c[3];
        // The 8 source voxels about p: a surface that the resampling
        // shifts by a voxel is still the one it was.
        std::uint8_t was = 0;
        const std::int64_t i0 = std::int64_t(std::floor(p.x())), j0 = std::int64_t(std::floor(p.y())), k0 = std::int64_t(std::floor(p.z()));
        for (int c = 0; c < 8; ++c) {
          const std::int64_t i = i0 + (c & 1), j = j0 + ((c >> 1) & 1), k = k0 + ((c >> 2) & 1);
          if (i >= 0 && i < sd[0] && j >= 0 && j < sd[1] && k >= 0 && k < sd[2]) was |= atRest[std::size_t(source.geometry().index(i, j, k))];
        }
        const std::uint8_t is = bare[std::size_t(voxel)];
        bare[std::size_t(voxel)] = (is & kBoneInAir ? was & kBoneInAir : was & kBare) ? 1 : 2;
      }
    });
  });

  // The cover, in voxel order; the skin label from G' before it.
  Label fallback = 0;
  {
    std::vector<std::uint64_t> count(skin.size(), 0);
    for (const Label l : posed.labels())
      if (flagged(skin, l)) ++count[l];
    fallback = Label(std::max_element(count.begin(), count.end()) - count.begin());
    if (count[fallback] == 0) return result;  // no skin to take a label from
  }
  // next: the skin label a covered voxel takes; a bare bone voxel's label
  // stays, and the background across its faces takes skin instead.
  std::vector<Label> next(bare.size(), 0);
  const std::int64_t nz = out.dims[2];
  parallelFor(nz, threads, [&](std::int64_t z) {
    for (std::int64_t y = 0; y < ny; ++y)
      for (std::int64_t x = 0; x < nx; ++x) {
        const std::int64_t v = (z * ny + y) * nx + x;
        if (bare[std::size_t(v)] != 2) continue;
        const Label l = nearestSkin(posed, skin, x, y, z);
        next[std::size_t(v)] = l != 0 ? l : fallback;
      }
  });
  Label maxLabel = 0;
  for (std::size_t v = 0; v < bare.size(); ++v)
    if (bare[v] != 0) maxLabel = std::max(maxLabel, posed.data()[v]);
  result.from.assign(std::max<std::size_t>(skin.size(), std::size_t(maxLabel) + 1), 0);
  result.to.assign(skin.size(), 0);
  Label* labels = posed.data();
  std::vector<std::pair<std::int64_t, Label>> overBone;
  for (std::size_t v = 0; v < bare.size(); ++v) {
    if (bare[v] == 0) continue;
    ++result.bareVoxels;
    if (bare[v] == 1) {
      ++result.bareAtRest;
      continue;
    }
    if (flagged(bone, labels[v])) {
      ++result.boneVoxels;
      const std::int64_t x = std::int64_t(v) % nx, y = (std::int64_t(v) / nx) % ny, z = std::int64_t(v) / slice;
      const std::array<std::array<std::int64_t, 3>, 6> across = {
          {{x - 1, y, z}, {x + 1, y, z}, {x, y - 1, z}, {x, y + 1, z}, {x, y, z - 1}, {x, y, z + 1}}};
      for (const auto& [i, j, k] : across)
        if (i >= 0 && i < nx && j >= 0 && j < ny && k >= 0 && k < nz && labels[out.index(i, j, k)] == 0)
          overBone.push_back({out.index(i, j, k), next[v]});
      continue;
    }
    ++result.from[labels[v]];
    ++result.to[next[v]];
    labels[v] = next[v];
    ++result.covered;
  }
  // Skin over the bare bone, once per background voxel (the first bone
  // voxel's label in voxel order).
  std::stable_sort(overBone.begin(), overBone.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t n = 0; n < overBone.size(); ++n) {
    if (n > 0 && overBone[n].first == overBone[n - 1].first) continue;
    labels[overBone[n].first] = overBone[n].second;
    ++result.to[overBone[n].second];
    ++result.overBone;
  }
  return result;
}

}  // namespace vox
