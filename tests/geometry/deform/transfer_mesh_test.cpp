#include "geometry/deform/transfer_mesh.h"

#include "geometry/skeleton/label_groups.h"
#include "geometry/distance_transform.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/label_stats.h"
#include "geometry/synth.h"
#include "geometry/voxel_tetrahedralization.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

namespace vox {
namespace {

double foregroundVolume(const LabelGrid& grid) {
  std::int64_t n = 0;
  for (const Label l : grid.labels()) n += l != 0;
  return double(n) * grid.geometry().voxelVolume();
}

// Total volume; every tet positive.
double checkedVolume(const TetMesh& mesh) {
  double total = 0.0;
  for (const Tet& t : mesh.tets) {
    const double v = signedVolume(mesh.positions, t);
    EXPECT_GT(v, 0.0);
    total += v;
  }
  return total;
}

TEST(TransferMesh, SphereVolumeCoverageAndDeterminism) {
  LabelGrid grid = synthesize(SynthKind::NestedSpheres, 32);
  grid.geometry().spacing = {1.5, 1.5, 4.0};  // anisotropic, like the phantoms
  grid.geometry().origin = {3.0, -7.0, 11.0};
  const LabelGrid b = binaryGroupGrid(grid);
  const ScalarGrid sizing = defaultSizingField(grid.geometry());
  EXPECT_FLOAT_EQ(sizing.values.front(), float(0.05 * grid.geometry().diagonal()));
  const TetMesh tm = buildTransferMesh(b, sizing);
  ASSERT_GT(tm.tetCount(), 100u);
  EXPECT_NO_THROW(tm.validate("tm"));
  for (const std::int32_t l : tm.labels) EXPECT_EQ(l, 1);
  // The boundary offset (1.4 voxels) adds about area x 0.9 voxel: 10-15 %
  // on this small sphere, a few % on a body.
  EXPECT_GT(checkedVolume(tm), foregroundVolume(grid));
  EXPECT_LT(checkedVolume(tm), 1.2 * foregroundVolume(grid));
  EXPECT_EQ(countUncoveredVoxels(tm, grid), 0);

  // The coverage repair's own count, asked for, is countUncoveredVoxels'.
  std::int64_t uncovered = -1;
  const TetMesh again = buildTransferMesh(b, sizing, {}, {}, &uncovered);
  EXPECT_EQ(uncovered, countUncoveredVoxels(again, grid));
  EXPECT_EQ(again.positions, tm.positions);
  EXPECT_EQ(again.tets, tm.tets);
  EXPECT_EQ(again.labels, tm.labels);
}

// A constant sizing field is read without interpolation: the mesh is the
// one a field of that value interpolated everywhere gives, to the bit (the
// second field differs in one corner voxel, far outside the domain, so it is
// not constant and is sampled).
TEST(TransferMesh, ConstantSizingFieldMeshesAsTheInterpolatedOne) {
  LabelGrid grid = synthesize(SynthKind::NestedSpheres, 24);
  grid.geometry().spacing = {1.5, 1.5, 4.0};
  const LabelGrid b = binaryGroupGrid(grid);
  const GridGeometry wide = padGeometry(grid.geometry(), {12, 12, 12});
  const ScalarGrid constant = defaultSizingField(wide, 0.07);
  ScalarGrid sampled = constant;
  sampled.at(0, 0, 0) = 2.0f * constant.values.front();
  const TetMesh a = buildTransferMesh(b, constant), c = buildTransferMesh(b, sampled);
  ASSERT_GT(a.tetCount(), 100u);
  EXPECT_EQ(a.positions, c.positions);
  EXPECT_EQ(a.tets, c.tets);
  EXPECT_EQ(a.labels, c.labels);
}

TEST(TransferMesh, SizingFieldControlsResolution) {
  const LabelGrid b = binaryGroupGrid(synthesize(SynthKind::NestedSpheres, 24));
  const ScalarGrid coarse = defaultSizingField(b.geometry(), 0.2);
  const ScalarGrid fine = defaultSizingField(b.geometry(), 0.05);
  const TetMesh a = buildTransferMesh(b, coarse), c = buildTransferMesh(b, fine);
  EXPECT_GT(c.vertexCount(), a.vertexCount());
  // Refine only the upper half: more vertices there than in the lower half.
  ScalarGrid half = coarse;
  const GridGeometry& g = half.geometry;
  for (std::int64_t k = g.dims[2] / 2; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) half.at(i, j, k) = fine.at(i, j, k);
  const TetMesh h = buildTransferMesh(b, half);
  const double midZ = g.voxelCenter(0, 0, g.dims[2] / 2).z();
  std::size_t upper = 0;
  for (const Eigen::Vector3d& p : h.positions) upper += p.z() > midZ;
  EXPECT_GT(double(upper), 1.5 * double(h.vertexCount() - upper));
}

TEST(TransferMesh, MultiMaterialFromLabelGroups) {
  const LabelGrid grid = synthesize(SynthKind::StickFigure, 64);
  const LabelGrid groups = labelGroupGrid(grid, synthOrganTable(SynthKind::StickFigure));
  const TetMesh tm = buildTransferMesh(groups, defaultSizingField(grid.geometry()));
  checkedVolume(tm);
  EXPECT_EQ(countUncoveredVoxels(tm, grid), 0);
  std::set<std::int32_t> present(tm.labels.begin(), tm.labels.end());
  EXPECT_EQ(present.size(), std::size_t(kLabelGroupCount));
  EXPECT_GT(*present.begin(), 0);
  // Interfaces pass between voxel centres: a tet whose centroid lies in a
  // voxel whose 26 neighbours all share its group carries that group.
  const GridGeometry& g = groups.geometry();
  std::size_t checked = 0, wrong = 0;
  for (std::size_t t = 0; t < tm.tetCount(); ++t) {
    const Tet& q = tm.tets[t];
    Index3 c;
    if (!g.voxelAt((tm.positions[q[0]] + tm.positions[q[1]] + tm.positions[q[2]] + tm.positions[q[3]]) / 4.0, c)) continue;
    const Label s = groups.at(c[0], c[1], c[2]);
    bool uniform = s != 0;
    for (int dz = -1; dz <= 1 && uniform; ++dz)
      for (int dy = -1; dy <= 1 && uniform; ++dy)
        for (int dx = -1; dx <= 1 && uniform; ++dx) uniform = groups.atOr(c[0] + dx, c[1] + dy, c[2] + dz) == s;
    if (!uniform) continue;
    ++checked;
    wrong += tm.labels[t] != std::int32_t(s);
  }
  EXPECT_GT(checked, 200u);
  EXPECT_EQ(wrong, 0u);
}

// Faces shared between a tet of group a and one of group b, with centroids
// in `region` (all when empty).
std::size_t sharedFaces(const TetMesh& mesh, std::int32_t a, std::int32_t b, const std::optional<Eigen::AlignedBox3d>& region) {
  const auto nb = faceNeighbors(mesh);
  std::size_t shared = 0;
  for (std::size_t t = 0; t < mesh.tetCount(); ++t)
    for (int k = 0; k < 4; ++k) {
      const std::int32_t n = nb[t][k];
      if (n < 0 || mesh.labels[t] != a || mesh.labels[n] != b) continue;
      const Tri f = tetFace(mesh.tets[t], k);
      const Eigen::Vector3d c = (mesh.positions[f[0]] + mesh.positions[f[1]] + mesh.positions[f[2]]) / 3.0;
      shared += !region || region->contains(c);
    }
  return shared;
}

// Face-connected components of the tets of `labels`.
std::size_t components(const TetMesh& mesh, const std::set<std::int32_t>& labels) {
  const auto nb = faceNeighbors(mesh);
  std::vector<int> seen(mesh.tetCount(), 0);
  std::size_t count = 0;
  for (std::size_t s = 0; s < mesh.tetCount(); ++s) {
    if (seen[s] || !labels.count(mesh.labels[s])) continue;
    ++count;
    std::vector<std::size_t> stack{s};
    seen[s] = 1;
    while (!stack.empty()) {
      const std::size_t t = stack.back();
      stack.pop_back();
      for (const std::int32_t n : nb[t])
        if (n >= 0 && !seen[n] && labels.count(mesh.labels[n])) seen[n] = 1, stack.push_back(std::size_t(n));
    }
  }
  return count;
}

// Cutting on a voxel tet mesh: group 1 for x < 3, group 2 for x >= 3; cut
// in the region y < 2 only.
TEST(TransferMesh, CutOpensTheInterfaceInsideTheRegionOnly) {
  GridGeometry g;
  g.dims = {6, 4, 3};
  LabelGrid grid(g, 0);
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) grid.labels()[v] = g.ijk(v)[0] < 3 ? 1 : 2;
  TetMesh mesh = tetrahedralizeVoxels(grid, {.includeBackground = false});
  const Eigen::AlignedBox3d region(Eigen::Vector3d(-10, -10, -10), Eigen::Vector3d(10, 1.5, 10));
  const std::size_t before = sharedFaces(mesh, 2, 1, std::nullopt);
  const std::size_t inRegion = sharedFaces(mesh, 2, 1, region);
  ASSERT_GT(inRegion, 0u);
  ASSERT_GT(before, inRegion);
  std::vector<double> volumes;
  for (const Tet& t : mesh.tets) volumes.push_back(signedVolume(mesh.positions, t));
  const std::size_t vertices = mesh.vertexCount();

  const CutReport r = cutTransferMesh(mesh, 1, 2, region);
  EXPECT_EQ(r.cutFaces, inRegion);
  EXPECT_EQ(mesh.vertexCount(), vertices + r.duplicatedVertices);
  EXPECT_GT(r.duplicatedVertices, 0u);
  EXPECT_NO_THROW(mesh.validate("cut"));
  for (std::size_t t = 0; t < mesh.tetCount(); ++t) EXPECT_DOUBLE_EQ(signedVolume(mesh.positions, mesh.tets[t]), volumes[t]);
  EXPECT_EQ(sharedFaces(mesh, 2, 1, region), 0u);
  EXPECT_EQ(sharedFaces(mesh, 1, 2, region), 0u);
  // splitVertices: every copy, and each original it copies (same position).
  ASSERT_TRUE(std::is_sorted(r.splitVertices.begin(), r.splitVertices.end()));
  std::size_t copies = 0, originals = 0;
  for (const std::int32_t v : r.splitVertices) {
    if (std::size_t(v) >= vertices) {
      ++copies;
      continue;
    }
    ++originals;
    bool copied = false;
    for (std::size_t c = vertices; c < mesh.vertexCount(); ++c) copied = copied || mesh.positions[c] == mesh.positions[std::size_t(v)];
    EXPECT_TRUE(copied) << v;
  }
  EXPECT_EQ(copies, r.duplicatedVertices);
  EXPECT_GT(originals, 0u);
  EXPECT_LE(originals, copies);
  // Outside the region (away from its rim) the groups stay glued.
  EXPECT_EQ(sharedFaces(mesh, 2, 1, std::nullopt) + r.cutFaces + r.openedRimFaces, before);
  EXPECT_GT(sharedFaces(mesh, 2, 1, std::nullopt), 0u);
  EXPECT_EQ(components(mesh, {1, 2}), 1u);
}

TEST(TransferMesh, CutEverywhereSeparatesTheGroups) {
  GridGeometry g;
  g.dims = {6, 4, 3};
  LabelGrid grid(g, 0);
  // Group 2 wraps around a block of group 1 on three sides, and a group 3
  // touches both: the cut must not tear group 3 off.
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
    const Index3 c = g.ijk(v);
    grid.labels()[v] = c[2] == 2 ? 3 : (c[0] >= 2 && c[0] < 4 && c[1] < 3) ? 1 : 2;
  }
  TetMesh mesh = tetrahedralizeVoxels(grid, {.includeBackground = false});
  ASSERT_EQ(components(mesh, {1, 2}), 1u);
  const CutReport r = cutTransferMesh(mesh, 1, 2);
  EXPECT_GT(r.cutFaces, 0u);
  EXPECT_EQ(sharedFaces(mesh, 1, 2, std::nullopt), 0u);
  EXPECT_EQ(sharedFaces(mesh, 2, 1, std::nullopt), 0u);
  EXPECT_EQ(components(mesh, {1}), 1u);
  EXPECT_EQ(components(mesh, {2}), 1u);
  // 1 and 2 are only joined through group 3 now.
  EXPECT_EQ(components(mesh, {1, 2}), 2u);
  EXPECT_EQ(components(mesh, {1, 2, 3}), 1u);
  EXPECT_GT(sharedFaces(mesh, 3, 1, std::nullopt), 0u);
  EXPECT_GT(sharedFaces(mesh, 3, 2, std::nullopt), 0u);
}

TEST(TransferMesh, CutStickFigureArmFromTrunk) {
  const LabelGrid grid = synthesize(SynthKind::StickFigure, 64);
  const LabelGrid groups = labelGroupGrid(grid, synthOrganTable(SynthKind::StickFigure));
  TetMesh tm = buildTransferMesh(groups, defaultSizingField(grid.geometry()));
  const double volume = checkedVolume(tm);
  const auto arm = std::int32_t(LabelGroup::RightArm), trunk = std::int32_t(LabelGroup::Trunk);
  ASSERT_GT(sharedFaces(tm, arm, trunk, std::nullopt) + sharedFaces(tm, trunk, arm, std::nullopt), 0u);
  const CutReport r = cutTransferMesh(tm, trunk, arm);
  EXPECT_GT(r.cutFaces, 0u);
  EXPECT_GT(r.duplicatedVertices, 0u);
  EXPECT_EQ(sharedFaces(tm, arm, trunk, std::nullopt) + sharedFaces(tm, trunk, arm, std::nullopt), 0u);
  EXPECT_DOUBLE_EQ(checkedVolume(tm), volume);
  RecordProperty("cut_faces", int(r.cutFaces));
  RecordProperty("duplicated_vertices", int(r.duplicatedVertices));
}

TEST(TransferMesh, BadInput) {
  GridGeometry g;
  g.dims = {4, 4, 4};
  const LabelGrid empty(g, 0);
  EXPECT_THROW(buildTransferMesh(empty, defaultSizingField(g)), InputError);
  LabelGrid one(g, 0);
  one.at(1, 1, 1) = 1;
  EXPECT_THROW(buildTransferMesh(one, ScalarGrid(g, 0.0f)), InputError);
}

// A block of 4^3 voxels (i, j, k in [2, 5], spacing 1 mm) tetrahedralized,
// moved by `shift` (mm), as a transfer mesh.
TetMesh voxelBlock(const Eigen::Vector3d& shift) {
  GridGeometry g;
  g.dims = {8, 8, 8};
  LabelGrid grid(g, 0);
  for (std::int64_t k = 2; k <= 5; ++k)
    for (std::int64_t j = 2; j <= 5; ++j)
      for (std::int64_t i = 2; i <= 5; ++i) grid.at(i, j, k) = 1;
  VoxelTetrahedralizationOptions options;
  options.includeBackground = false;
  TetMesh mesh = tetrahedralizeVoxels(grid, options);
  for (Eigen::Vector3d& p : mesh.positions) p += shift;
  return mesh;
}

bool inTet(const TetMesh& mesh, const Tet& t, const Eigen::Vector3d& p) {
  Eigen::Matrix3d m;
  m << mesh.positions[std::size_t(t[1])] - mesh.positions[std::size_t(t[0])], mesh.positions[std::size_t(t[2])] - mesh.positions[std::size_t(t[0])],
      mesh.positions[std::size_t(t[3])] - mesh.positions[std::size_t(t[0])];
  const Eigen::Vector3d l = m.inverse() * (p - mesh.positions[std::size_t(t[0])]);
  return l.minCoeff() > 0.0 && l.sum() < 1.0;
}

TEST(TransferMesh, CapCoversACentreJustBeyondABoundaryFacet) {
  // The block's face at x = 5.5; a centre half a voxel beyond it, off the
  // faces' diagonals.
  GridGeometry g;
  g.dims = {8, 8, 8};
  g.origin = {0.0, 0.3, 0.2};
  const std::int64_t centre = g.index(6, 3, 3);
  const Eigen::Vector3d c = g.voxelCenter(6, 3, 3);

  TetMesh mesh = voxelBlock(Eigen::Vector3d::Zero());
  const std::size_t tets = mesh.tetCount();
  const std::vector<std::int64_t> one{centre};
  LabelGrid voxel(g, 0);
  voxel.labels()[std::size_t(centre)] = 1;
  EXPECT_TRUE(capUncoveredVoxels(mesh, voxel, one).empty());
  ASSERT_EQ(mesh.tetCount(), tets + 1);
  ASSERT_EQ(mesh.labels.size(), tets + 1);
  EXPECT_EQ(mesh.labels.back(), 1);
  EXPECT_GT(signedVolume(mesh.positions, mesh.tets.back()), 0.0);
  EXPECT_TRUE(inTet(mesh, mesh.tets.back(), c));
  EXPECT_EQ(countUncoveredVoxels(mesh, voxel), 0);
  // The cap rests on the block: its base is a boundary face, nothing else
  // of it is inside the block (x > 5.5 but the base).
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(mesh.positions[std::size_t(mesh.tets.back()[std::size_t(k)])].x(), 5.5, 1e-12);
  EXPECT_GT(mesh.positions[std::size_t(mesh.tets.back()[3])].x(), c.x());

}

TEST(TransferMesh, CapNeverEntersAnotherPartOfTheMesh) {
  // A second block whose face lies 0.35 mm beyond the centre (0.2 mm beyond
  // the first block's face): the best shaped caps on the first block would
  // reach into it, so a flatter one is taken, and no point of it lies in a
  // tet of either block.
  GridGeometry g;
  g.dims = {8, 8, 8};
  g.origin = {-0.3, 0.3, 0.2};
  const std::int64_t centre = g.index(6, 3, 3);
  const Eigen::Vector3d c = g.voxelCenter(6, 3, 3);
  TetMesh mesh = voxelBlock(Eigen::Vector3d::Zero());
  const TetMesh other = voxelBlock(Eigen::Vector3d(6.05 - 1.5, 0.0, 0.0));
  const std::int32_t offset = std::int32_t(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), other.positions.begin(), other.positions.end());
  for (Tet t : other.tets) {
    for (std::int32_t& v : t) v += offset;
    mesh.tets.push_back(t);
    mesh.labels.push_back(2);
  }
  const std::size_t tets = mesh.tetCount();
  const std::vector<std::int64_t> one{centre};
  LabelGrid voxel(g, 0);
  voxel.labels()[std::size_t(centre)] = 1;
  const TetMesh blocks = mesh;
  EXPECT_TRUE(capUncoveredVoxels(mesh, voxel, one).empty());
  ASSERT_EQ(mesh.tetCount(), tets + 1);
  const Tet cap = mesh.tets.back();
  EXPECT_EQ(mesh.labels.back(), 1);
  EXPECT_TRUE(inTet(mesh, cap, c));
  const double apex = mesh.positions[std::size_t(cap[3])].x();
  EXPECT_GT(apex, c.x());
  EXPECT_LT(apex, 6.05);
  // Points all through the cap lie in no other tet.
  int inside = 0;
  for (int a = 1; a < 8; ++a)
    for (int b = 1; a + b < 8; ++b)
      for (int d = 1; a + b + d < 8; ++d) {
        const Eigen::Vector3d p = (a * mesh.positions[std::size_t(cap[0])] + b * mesh.positions[std::size_t(cap[1])] +
                                   d * mesh.positions[std::size_t(cap[2])] + (8 - a - b - d) * mesh.positions[std::size_t(cap[3])]) / 8.0;
        for (std::size_t t = 0; t < tets; ++t) inside += inTet(mesh, mesh.tets[t], p);
      }
  EXPECT_EQ(inside, 0);

  // A centre of the second block's label takes a cap on that block, though
  // the first one's face is nearer.
  TetMesh other2 = blocks;
  voxel.labels()[std::size_t(centre)] = 2;
  EXPECT_TRUE(capUncoveredVoxels(other2, voxel, one).empty());
  ASSERT_EQ(other2.tetCount(), tets + 1);
  EXPECT_EQ(other2.labels.back(), 2);
  EXPECT_TRUE(inTet(other2, other2.tets.back(), c));
  EXPECT_LT(other2.positions[std::size_t(other2.tets.back()[3])].x(), c.x());
}

TEST(TransferMesh, CapLeavesACentreBeyondAnEdge) {
  // A centre beyond the block's edge (x and y past its faces) projects into
  // no boundary facet: no cap, the centre is returned, the mesh unchanged.
  GridGeometry g;
  g.dims = {8, 8, 8};
  g.origin = {0.0, 0.0, 0.2};
  const std::int64_t centre = g.index(6, 6, 3);
  TetMesh mesh = voxelBlock(Eigen::Vector3d::Zero());
  const TetMesh before = mesh;
  const std::vector<std::int64_t> one{centre};
  LabelGrid voxel(g, 0);
  voxel.labels()[std::size_t(centre)] = 1;
  EXPECT_EQ(capUncoveredVoxels(mesh, voxel, one), one);
  EXPECT_EQ(mesh.tets, before.tets);
  EXPECT_EQ(mesh.positions.size(), before.positions.size());
}

TEST(TransferMesh, AdultMalePhantom) {
  const LabelGrid grid = readGrid(test::assetPath("icrp110_am.nii.gz"));
  const TetMesh tm = buildTransferMesh(binaryGroupGrid(grid), defaultSizingField(grid.geometry()));
  const double volume = checkedVolume(tm);
  EXPECT_NEAR(volume, foregroundVolume(grid), 0.06 * foregroundVolume(grid));
  EXPECT_EQ(countUncoveredVoxels(tm, grid), 0);
  RecordProperty("tm_vertices", int(tm.vertexCount()));
  RecordProperty("tm_tets", int(tm.tetCount()));
}

}  // namespace
}  // namespace vox
