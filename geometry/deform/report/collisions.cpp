#include "geometry/deform/report/collisions.h"

#include "geometry/parallel.h"
#include "geometry/raster/lattice_tets.h"

#include <algorithm>
#include <array>
#include <mutex>

namespace vox {

Collisions findCollisions(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed, const LabelGrid& parts,
                          const GridGeometry& lattice, bool keepMask, int threads) {
  Collisions out;
  out.lattice = lattice;
  if (keepMask) out.mask = LabelGrid(lattice, 0);
  if (deformed.size() != rest.vertexCount() || lattice.voxelCount() == 0) return out;
  const std::vector<Eigen::Vector3d> posed(deformed.begin(), deformed.end());
  const std::vector<LatticeTet> tets = latticeTets(lattice, posed, rest.tets);
  const SlabTets slab = slabTets(tets, 0, std::int32_t(lattice.dims[2]));
  const GridGeometry& restGrid = parts.geometry();
  constexpr std::size_t kParts = 256;
  std::vector<std::int64_t> pairCounts(kParts * kParts, 0);
  std::mutex merge;
  const std::int64_t nx = lattice.dims[0], ny = lattice.dims[1];
  // Face areas of the lattice (mm^2): x faces, y faces, z faces.
  const Eigen::Vector3d faceArea(lattice.spacing[1] * lattice.spacing[2], lattice.spacing[0] * lattice.spacing[2],
                                 lattice.spacing[0] * lattice.spacing[1]);
  // Faces between two parts' points, counted per axis (exact sums in any
  // order of the ranges).
  std::vector<std::array<std::int64_t, 3>> contactFaces(kParts * kParts, {0, 0, 0});
  // Apart at rest: more than two of the rest grid's largest voxel sides.
  const float apart2 = float(4.0 * restGrid.spacing.maxCoeff() * restGrid.spacing.maxCoeff());
  parallelRanges(lattice.dims[2], workerThreads(threads), [&](std::int64_t z0, std::int64_t z1) {
    std::vector<Label> first(std::size_t(nx * ny)), below(std::size_t(nx * ny), Label(0));
    // Where the first tet's map puts each point at rest (grid frame).
    std::vector<Eigen::Vector3f> from(std::size_t(nx * ny)), fromBelow(std::size_t(nx * ny));
    std::vector<std::uint8_t> hit(std::size_t(nx * ny));
    std::vector<std::int64_t> localPairs(kParts * kParts, 0);
    std::vector<std::array<std::int64_t, 3>> localContacts(kParts * kParts, {0, 0, 0});
    std::int64_t body = 0, colliding = 0;
    // The part of every point of slice z (its first tet's), and the points
    // where a second tet brings another part.
    const auto fillSlice = [&](std::int64_t z, bool count) {
      std::fill(first.begin(), first.end(), Label(0));
      std::fill(hit.begin(), hit.end(), std::uint8_t(0));
      for (std::int64_t e = slab.sliceStart[std::size_t(z)]; e < slab.sliceStart[std::size_t(z) + 1]; ++e) {
        const std::int32_t t = slab.tets[std::size_t(slab.entries[std::size_t(e)])];
        const LatticeTet& lt = tets[std::size_t(t)];
        const Tet& tet = rest.tets[std::size_t(t)];
        for (std::int32_t y = lt.lo[1]; y <= lt.hi[1]; ++y) {
          std::int32_t x0 = 0, x1 = -1;
          if (!rowSpan(lt, y, std::int32_t(z), x0, x1)) continue;
          for (std::int32_t x = x0; x <= x1; ++x) {
            const Eigen::Vector4d w = lt.barycentric(x, y, std::int32_t(z));
            Eigen::Vector3d p = Eigen::Vector3d::Zero();
            for (int k = 0; k < 4; ++k) p += w[k] * rest.positions[std::size_t(tet[std::size_t(k)])];
            Index3 v;
            if (!restGrid.voxelAt(p, v)) continue;
            const Label part = parts.at(v[0], v[1], v[2]);
            if (part == 0 || part >= kParts) continue;
            const std::size_t i = std::size_t(x + nx * y);
            if (first[i] == 0) {
              first[i] = part;
              from[i] = p.cast<float>();
            } else if (first[i] != part && !hit[i]) {
              hit[i] = 1;
              const Label a = std::min(first[i], part), b = std::max(first[i], part);
              if (count) ++localPairs[std::size_t(a) * kParts + b];
            }
          }
        }
      }
    };
    // Neighbouring points of two parts that lay apart at rest meet on a
    // contact; those that were neighbours at rest (the joint's own
    // interface, however it turned) do not count.
    const auto touch = [&](Label a, Label b, const Eigen::Vector3f& pa, const Eigen::Vector3f& pb, int axis) {
      if (a != 0 && b != 0 && a != b && (pa - pb).squaredNorm() > apart2)
        ++localContacts[std::size_t(std::min(a, b)) * kParts + std::max(a, b)][std::size_t(axis)];
    };
    if (z0 > 0) {
      fillSlice(z0 - 1, false);
      below = first;
      fromBelow = from;
    }
    for (std::int64_t z = z0; z < z1; ++z) {
      fillSlice(z, true);
      for (std::size_t i = 0; i < first.size(); ++i) {
        body += first[i] != 0;
        colliding += hit[i];
      }
      for (std::int64_t y = 0; y < ny; ++y)
        for (std::int64_t x = 0; x < nx; ++x) {
          const std::size_t i = std::size_t(x + nx * y);
          if (first[i] == 0) continue;
          if (x + 1 < nx) touch(first[i], first[i + 1], from[i], from[i + 1], 0);
          if (y + 1 < ny) touch(first[i], first[i + std::size_t(nx)], from[i], from[i + std::size_t(nx)], 1);
          if (z > 0) touch(first[i], below[i], from[i], fromBelow[i], 2);
        }
      below = first;
      fromBelow = from;
      if (keepMask)
        for (std::size_t i = 0; i < hit.size(); ++i)
          if (hit[i]) out.mask.labels()[std::size_t(z * nx * ny) + i] = 1;
    }
    const std::lock_guard<std::mutex> lock(merge);
    out.bodyVoxels += body;
    out.voxels += colliding;
    for (std::size_t k = 0; k < localPairs.size(); ++k) pairCounts[k] += localPairs[k];
    for (std::size_t k = 0; k < localContacts.size(); ++k)
      for (int axis = 0; axis < 3; ++axis) contactFaces[k][std::size_t(axis)] += localContacts[k][std::size_t(axis)];
  }, 1);
  for (std::size_t a = 0; a < kParts; ++a)
    for (std::size_t b = a + 1; b < kParts; ++b)
      if (const std::size_t k = a * kParts + b; contactFaces[k][0] + contactFaces[k][1] + contactFaces[k][2] > 0)
        out.contacts.push_back({Label(a), Label(b),
                                double(contactFaces[k][0]) * faceArea[0] + double(contactFaces[k][1]) * faceArea[1] +
                                    double(contactFaces[k][2]) * faceArea[2]});
  std::sort(out.contacts.begin(), out.contacts.end(), [](const ContactPair& p, const ContactPair& q) {
    return p.areaMm2 != q.areaMm2 ? p.areaMm2 > q.areaMm2 : (p.partA != q.partA ? p.partA < q.partA : p.partB < q.partB);
  });
  for (std::size_t a = 0; a < kParts; ++a)
    for (std::size_t b = a + 1; b < kParts; ++b)
      if (const std::int64_t n = pairCounts[a * kParts + b]; n > 0) out.pairs.push_back({Label(a), Label(b), n});
  std::sort(out.pairs.begin(), out.pairs.end(), [](const CollisionPair& p, const CollisionPair& q) {
    return p.voxels != q.voxels ? p.voxels > q.voxels : (p.partA != q.partA ? p.partA < q.partA : p.partB < q.partB);
  });
  return out;
}

}  // namespace vox
