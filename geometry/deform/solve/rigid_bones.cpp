#include "geometry/deform/solve/rigid_bones.h"

#include "geometry/deform/solve/deformation_metrics.h"
#include "geometry/error.h"
#include "geometry/parallel.h"
#include "geometry/raster/lattice_tets.h"
#include "geometry/skeleton/bones.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>

namespace vox {

LabelGrid boneKeyGrid(const LabelGrid& grid, const OrganTable& organs, const LabelGrid& parts) {
  if (parts.dims() != grid.dims()) throw InputError("body parts", "the body-part grid's dims differ from the grid's");
  const std::vector<skeleton::Bone> boneOf = skeleton::boneOfLabels(organs, grid.maxLabel());
  LabelGrid keys(grid.geometry(), 0);
  const std::vector<Label>& labels = grid.labels();
  const std::vector<Label>& part = parts.labels();
  std::vector<Label>& out = keys.labels();
  for (std::size_t v = 0; v < labels.size(); ++v) {
    const Label l = labels[v];
    if (l == 0 || l >= boneOf.size() || boneOf[l] == skeleton::Bone::None || part[v] == 0) continue;
    out[v] = Label(part[v] * kBoneKeyStride + Label(boneOf[l]));
  }
  return keys;
}

RigidBoneGroups rigidBoneGroups(const TetMesh& rest, const LabelGrid& boneKeys, int jointRings) {
  RigidBoneGroups out;
  const GridGeometry& lattice = boneKeys.geometry();
  out.voxelVolume = lattice.voxelVolume();
  const std::vector<Label>& keys = boneKeys.labels();
  // Each bone voxel's centre goes to the lowest-index tet holding it: on the
  // parallel loop by slabs of z, each slab's voxels taken by the tets that
  // reach it in tet order, so no two threads write one voxel.
  std::vector<std::int32_t> owner(keys.size(), -1);
  const std::vector<LatticeTet> tets = latticeTets(lattice, rest.positions, rest.tets);
  parallelRanges(lattice.dims[2], workerThreads(0), [&](std::int64_t k0, std::int64_t k1) {
    for (std::size_t t = 0; t < tets.size(); ++t) {
      const LatticeTet& lt = tets[t];
      if (lt.empty()) continue;
      const std::int32_t z0 = std::max(lt.lo[2], std::int32_t(k0)), z1 = std::min(lt.hi[2], std::int32_t(k1 - 1));
      for (std::int32_t z = z0; z <= z1; ++z)
        for (std::int32_t y = lt.lo[1]; y <= lt.hi[1]; ++y) {
          std::int32_t x0 = 0, x1 = -1;
          if (!rowSpan(lt, y, z, x0, x1)) continue;
          const std::int64_t row = lattice.index(0, y, z);
          for (std::int32_t x = x0; x <= x1; ++x) {
            const std::int64_t v = row + x;
            if (keys[std::size_t(v)] != 0 && owner[std::size_t(v)] < 0) owner[std::size_t(v)] = std::int32_t(t);
          }
        }
    }
  }, 8);
  // The held voxels' keys bucketed by tet, then each tet's counted by key:
  // (tet, key) in increasing order.
  std::vector<std::int64_t> start(tets.size() + 1, 0);
  for (std::size_t v = 0; v < keys.size(); ++v) {
    if (keys[v] == 0) continue;
    if (owner[v] < 0) ++out.uncoveredVoxels;
    else ++start[std::size_t(owner[v]) + 1];
  }
  for (std::size_t t = 0; t < tets.size(); ++t) start[t + 1] += start[t];
  std::vector<Label> held(std::size_t(start.back()));
  std::vector<std::int64_t> next(start.begin(), start.end() - 1);
  for (std::size_t v = 0; v < keys.size(); ++v)
    if (keys[v] != 0 && owner[v] >= 0) held[std::size_t(next[std::size_t(owner[v])]++)] = keys[v];
  for (std::size_t t = 0; t < tets.size(); ++t) {
    const auto first = held.begin() + start[t], last = held.begin() + start[t + 1];
    std::sort(first, last);
    for (auto k = first; k != last;) {
      const auto e = std::find_if(k, last, [&](Label key) { return key != *k; });
      out.tetVoxels.push_back({std::int32_t(t), *k, std::int32_t(e - k)});
      k = e;
    }
  }

  // Vertex -> part: 0 none, part, or kShared when two parts' bones meet.
  constexpr int kShared = -1;
  std::vector<int> vertexPart(rest.vertexCount(), 0);
  for (const RigidBoneGroups::TetVoxels& tv : out.tetVoxels) {
    const int part = int(tv.key / kBoneKeyStride);
    for (const std::int32_t v : rest.tets[std::size_t(tv.tet)]) {
      int& p = vertexPart[std::size_t(v)];
      p = p == 0 ? part : (p == part ? p : kShared);
    }
  }
  std::vector<std::int32_t> groupOfPart(256, -1);
  for (const int p : vertexPart)
    if (p > 0) groupOfPart[std::size_t(p)] = 0;
  for (std::size_t p = 0; p < groupOfPart.size(); ++p)
    if (groupOfPart[p] == 0) {
      groupOfPart[p] = std::int32_t(out.groupPart.size());
      out.groupPart.push_back(Label(p));
    }
  // The tissue of a joint: `jointRings` rings of tets around the shared
  // vertices are left free too, so that the bones on either side can turn
  // against each other without the tets between them folding.
  for (int r = 0; r < jointRings; ++r) {
    std::vector<std::uint8_t> near(rest.vertexCount(), 0);
    for (const Tet& t : rest.tets) {
      bool shared = false;
      for (const std::int32_t v : t) shared = shared || vertexPart[std::size_t(v)] == kShared;
      if (shared)
        for (const std::int32_t v : t) near[std::size_t(v)] = 1;
    }
    for (std::size_t v = 0; v < near.size(); ++v)
      if (near[v] && vertexPart[v] > 0) vertexPart[v] = kShared;
  }
  out.vertexGroup.assign(rest.vertexCount(), -1);
  for (std::size_t v = 0; v < vertexPart.size(); ++v) {
    if (vertexPart[v] == kShared) ++out.sharedVertices;
    if (vertexPart[v] > 0) out.vertexGroup[v] = groupOfPart[std::size_t(vertexPart[v])];
  }
  return out;
}

void RigidBoneFit::precompute(std::span<const std::int32_t> vertexGroup, std::span<const std::uint8_t> fitted,
                              std::span<const Eigen::Vector3d> rest) {
  groups_.clear();
  dropped_ = 0;
  rest_.assign(rest.begin(), rest.end());
  placed_.assign(rest.size(), 0);
  if (vertexGroup.size() != rest.size() || fitted.size() != rest.size()) return;
  std::int32_t count = 0;
  for (const std::int32_t g : vertexGroup) count = std::max(count, g + 1);
  std::vector<Group> groups(static_cast<std::size_t>(count));
  for (std::size_t v = 0; v < rest.size(); ++v) {
    const std::int32_t g = vertexGroup[v];
    if (g < 0) continue;
    groups[std::size_t(g)].members.push_back(std::int32_t(v));
    if (fitted[v]) groups[std::size_t(g)].sources.push_back(std::int32_t(v));
  }
  for (std::size_t id = 0; id < groups.size(); ++id) {
    Group& g = groups[id];
    g.id = std::int32_t(id);
    if (g.members.empty()) continue;
    if (g.sources.size() < 4) {
      ++dropped_;
      continue;
    }
    for (const std::int32_t v : g.sources) g.restCentroid += rest[std::size_t(v)];
    g.restCentroid /= double(g.sources.size());
    for (const std::int32_t v : g.members) placed_[std::size_t(v)] = 1;
    groups_.push_back(std::move(g));
  }
}

void RigidBoneFit::apply(std::span<Eigen::Vector3d> positions, std::span<const Eigen::Isometry3d> motions) const {
  for (const Group& g : groups_) {
    if (std::size_t(g.id) < motions.size()) {
      for (const std::int32_t v : g.members) positions[std::size_t(v)] = motions[std::size_t(g.id)] * rest_[std::size_t(v)];
      continue;
    }
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const std::int32_t v : g.sources) centroid += positions[std::size_t(v)];
    centroid /= double(g.sources.size());
    Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
    for (const std::int32_t v : g.sources)
      cross += (positions[std::size_t(v)] - centroid) * (rest_[std::size_t(v)] - g.restCentroid).transpose();
    const Eigen::Matrix3d rotation = svdRotation(cross);
    for (const std::int32_t v : g.members)
      positions[std::size_t(v)] = centroid + rotation * (rest_[std::size_t(v)] - g.restCentroid);
  }
}

std::vector<BoneRigidity> measureBoneRigidity(const RigidBoneGroups& groups, const TetMesh& rest,
                                              std::span<const Eigen::Vector3d> deformed) {
  std::map<Label, std::vector<const RigidBoneGroups::TetVoxels*>> byKey;
  for (const RigidBoneGroups::TetVoxels& tv : groups.tetVoxels) byKey[tv.key].push_back(&tv);
  std::vector<BoneRigidity> out;
  if (deformed.size() != rest.vertexCount()) return out;
  for (const auto& [key, entries] : byKey) {
    BoneRigidity b;
    b.key = key;
    std::vector<std::int32_t> vertices;
    std::vector<std::pair<std::int32_t, std::int32_t>> edges;
    const Label part = Label(key / kBoneKeyStride);
    for (const RigidBoneGroups::TetVoxels* tv : entries) {
      const Tet& t = rest.tets[std::size_t(tv->tet)];
      b.voxels += tv->voxels;
      const double restVolume = signedVolume(rest.positions, t);
      const double posedVolume = signedVolume(deformed[std::size_t(t[0])], deformed[std::size_t(t[1])],
                                              deformed[std::size_t(t[2])], deformed[std::size_t(t[3])]);
      b.restVolumeMm3 += double(tv->voxels) * groups.voxelVolume;
      if (restVolume > 0) b.posedVolumeMm3 += double(tv->voxels) * groups.voxelVolume * posedVolume / restVolume;
      for (int a = 0; a < 4; ++a) {
        vertices.push_back(t[std::size_t(a)]);
        for (int c = a + 1; c < 4; ++c)
          edges.emplace_back(std::min(t[std::size_t(a)], t[std::size_t(c)]), std::max(t[std::size_t(a)], t[std::size_t(c)]));
      }
    }
    b.tets = entries.size();
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    b.vertices = vertices.size();
    for (const std::int32_t v : vertices) {
      const std::int32_t g = groups.vertexGroup.empty() ? -1 : groups.vertexGroup[std::size_t(v)];
      if (g >= 0 && groups.groupPart[std::size_t(g)] == part) ++b.rigidVertices;
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    b.edges = edges.size();
    for (const auto& [u, v] : edges) {
      const double l0 = (rest.positions[std::size_t(u)] - rest.positions[std::size_t(v)]).norm();
      const double l1 = (deformed[std::size_t(u)] - deformed[std::size_t(v)]).norm();
      if (l0 > 0) b.maxStrain = std::max(b.maxStrain, std::abs(std::log(std::max(l1, 1e-12) / l0)));
    }
    out.push_back(b);
  }
  return out;
}

}  // namespace vox
