#include "geometry/deform/cage/cage_builder.h"

#include "geometry/skeleton/label_groups.h"
#include "geometry/distance_transform.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/organ_table.h"
#include "geometry/parallel.h"
#include "geometry/synth.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

namespace vox {
namespace {

// The stick figure at 96 voxels (2 mm): arms 10 mm wide touching the trunk
// along x = 33 mm between z = 80 and 150 mm.
LabelGrid stickGroups() {
  return labelGroupGrid(synthesize(SynthKind::StickFigure, 96), synthOrganTable(SynthKind::StickFigure));
}

CageOptions stickOptions() {
  CageOptions o;
  o.dilationMm = 4.0;
  o.facetSizeMm = 4.0;
  o.facetDistanceMm = 0.5;
  o.erosionMm = 3.0;
  return o;
}

void expectValidCage(const CageResult& r, int target) {
  const SurfaceCheck& c = r.report.check;
  EXPECT_TRUE(c.closedManifold());
  EXPECT_EQ(c.selfIntersections, 0u);
  EXPECT_EQ(c.degenerateFaces, 0u);
  EXPECT_GT(c.volume, 0.0);
  EXPECT_TRUE(c.validCage());
  EXPECT_EQ(c.components, 1u);
  EXPECT_LE(r.cage.vertexCount(), std::size_t(target));
  EXPECT_GE(r.cage.vertexCount(), std::size_t(0.9 * target));
  EXPECT_GT(r.report.meshedVertices, 3 * r.cage.vertexCount());
}

TEST(CageBuilder, StickFigureCage) {
  const LabelGrid groups = stickGroups();
  const CageResult r = buildCage(groups, stickOptions());
  expectValidCage(r, 300);
  EXPECT_EQ(r.report.erodedVoxels, 0);
  // QEM may cut a little into the model; most of it stays inside.
  std::int64_t foreground = 0;
  for (const Label l : groups.labels()) foreground += l != 0;
  EXPECT_LT(r.report.foregroundOutside, foreground / 100);
  EXPECT_EQ(r.report.foregroundOutside, countForegroundOutside(r.cage, groups));
}

TEST(CageBuilder, InsetCageSeparatesArmFromTrunk) {
  const LabelGrid groups = stickGroups();
  CageOptions o = stickOptions();
  const CageResult plain = buildCage(groups, o);
  // Separate the right arm from the trunk below z = 130 mm: the shoulder stays joined.
  const Eigen::AlignedBox3d region(Eigen::Vector3d(-1e3, -1e3, -1e3), Eigen::Vector3d(1e3, 1e3, 130.0));
  o.separations.push_back({Label(LabelGroup::RightArm), Label(LabelGroup::Trunk), region});
  const CageResult inset = buildCage(groups, o);
  expectValidCage(inset, 300);
  EXPECT_GT(inset.report.erodedVoxels, 0);
  // Eroded voxels end up outside the cage (the outliers of the propagation).
  EXPECT_GE(inset.report.foregroundOutside, inset.report.erodedVoxels / 2);

  // On the contact plane between right arm and trunk (x = 33 mm), inside
  // the region: inside the plain cage, outside the inset one. Above the
  // region the shoulder stays inside both.
  const SurfaceInsideTest plainInside(plain.cage), insetInside(inset.cage);
  for (double z = 90.0; z <= 120.0; z += 5.0) {
    const Eigen::Vector3d contact(33.0, 28.0, z);
    EXPECT_TRUE(plainInside.contains(contact)) << z;
    EXPECT_FALSE(insetInside.contains(contact)) << z;
    // The arm's and the trunk's cores stay inside.
    EXPECT_TRUE(insetInside.contains(Eigen::Vector3d(26.0, 28.0, z))) << z;
    EXPECT_TRUE(insetInside.contains(Eigen::Vector3d(44.0, 28.0, z))) << z;
  }
  EXPECT_TRUE(insetInside.contains(Eigen::Vector3d(33.0, 28.0, 146.0)));
  // The arm now hangs free below the shoulder: it leaves the trunk's cage
  // between them, so the cage's genus or shape changed there, not its count.
  EXPECT_EQ(inset.report.check.components, 1u);
}

TEST(CageBuilder, IsDeterministic) {
  const LabelGrid groups = stickGroups();
  const CageResult a = buildCage(groups, stickOptions());
  const CageResult b = buildCage(groups, stickOptions());
  EXPECT_EQ(a.cage.positions, b.cage.positions);
  EXPECT_EQ(a.cage.triangles, b.cage.triangles);
}

// The eroded voxels are those within the erosion depth of the other group
// by the distance transform of the whole grid (the builder transforms only
// the box around each side).
TEST(CageBuilder, ErosionIsTheWholeGridDistanceTransforms) {
  const LabelGrid groups = stickGroups();
  CageOptions o = stickOptions();
  const Eigen::AlignedBox3d region(Eigen::Vector3d(-1e3, -1e3, -1e3), Eigen::Vector3d(1e3, 1e3, 130.0));
  o.separations.push_back({Label(LabelGroup::RightArm), Label(LabelGroup::Trunk), region});
  const Label arm = Label(LabelGroup::RightArm), trunk = Label(LabelGroup::Trunk);
  const GridGeometry& g = groups.geometry();
  std::vector<std::uint8_t> armSeeds(groups.labels().size()), trunkSeeds(groups.labels().size());
  for (std::size_t v = 0; v < armSeeds.size(); ++v) armSeeds[v] = groups.labels()[v] == arm, trunkSeeds[v] = groups.labels()[v] == trunk;
  const ScalarGrid toArm = euclideanDistanceTransform(g, armSeeds).distance, toTrunk = euclideanDistanceTransform(g, trunkSeeds).distance;
  std::int64_t expected = 0;
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        if (!region.contains(g.voxelCenter(i, j, k))) continue;
        const Label l = groups.at(i, j, k);
        expected += (l == arm && toTrunk.at(i, j, k) <= o.erosionMm) || (l == trunk && toArm.at(i, j, k) <= o.erosionMm);
      }
  EXPECT_GT(expected, 100);
  EXPECT_EQ(buildCage(groups, o).report.erodedVoxels, expected);
}

// The distance transforms of the separations run at once on the parallel
// loop: two separations give the same cage on one thread and on three.
TEST(CageBuilder, InsetCageIsTheSameOnAnyThreadCount) {
  const LabelGrid groups = stickGroups();
  CageOptions o = stickOptions();
  const Eigen::AlignedBox3d region(Eigen::Vector3d(-1e3, -1e3, -1e3), Eigen::Vector3d(1e3, 1e3, 130.0));
  o.separations.push_back({Label(LabelGroup::RightArm), Label(LabelGroup::Trunk), region});
  o.separations.push_back({Label(LabelGroup::LeftArm), Label(LabelGroup::Trunk), std::nullopt});
  const auto onThreads = [&](int threads) {
    const ScopedWorkerThreads scope(threads);
    return buildCage(groups, o);
  };
  const CageResult one = onThreads(1), three = onThreads(3);
  EXPECT_GT(one.report.erodedVoxels, 0);
  EXPECT_EQ(one.report.erodedVoxels, three.report.erodedVoxels);
  EXPECT_EQ(one.report.foregroundOutside, three.report.foregroundOutside);
  EXPECT_EQ(one.cage.positions, three.cage.positions);
  EXPECT_EQ(one.cage.triangles, three.cage.triangles);
}

TEST(CageBuilder, BadRequests) {
  const LabelGrid groups = stickGroups();
  CageOptions o = stickOptions();
  o.separations.push_back({Label(LabelGroup::RightArm), Label(42), std::nullopt});
  try {
    buildCage(groups, o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("label group 42 has no voxels"), std::string::npos) << e.what();
  }
  GridGeometry g;
  g.dims = {5, 5, 5};
  EXPECT_THROW(buildCage(LabelGrid(g, 0)), InputError);
  o.separations.clear();
  o.targetVertices = 2;
  EXPECT_THROW(buildCage(groups, o), InputError);
}

// Midpoint of the background gap between the right arm and the trunk along
// the row (j, k), or nothing when they touch or the row misses one of them.
std::optional<Eigen::Vector3d> gapBetweenArmAndTrunk(const LabelGrid& groups, std::int64_t j, std::int64_t k) {
  const GridGeometry& g = groups.geometry();
  std::int64_t armEnd = -1;
  for (std::int64_t i = 0; i < g.dims[0]; ++i) {
    const Label s = groups.at(i, j, k);
    if (s == Label(LabelGroup::RightArm)) armEnd = i;
    if (s == Label(LabelGroup::Trunk) && armEnd >= 0) {
      if (i - armEnd < 3) return std::nullopt;
      return g.voxelCenter(armEnd, j, k) + 0.5 * (g.voxelCenter(i, j, k) - g.voxelCenter(armEnd, j, k));
    }
    if (s != 0 && s != Label(LabelGroup::RightArm)) armEnd = -1;
  }
  return std::nullopt;
}

TEST(CageBuilder, AdultMaleCages) {
  const LabelGrid grid = readGrid(test::assetPath("icrp110_am.nii.gz"));
  const LabelGrid groups = labelGroupGrid(grid, OrganTable::read(test::assetPath("icrp110_am_organs.dat")));
  const CageResult plain = buildCage(grid);
  expectValidCage(plain, 300);
  // The default 20 mm dilation keeps QEM's cuts out of the body almost
  // everywhere; the count is reported (outliers for the propagation).
  EXPECT_LT(plain.report.foregroundOutside, 1000);
  RecordProperty("cage_vertices", int(plain.cage.vertexCount()));
  RecordProperty("foreground_outside", int(plain.report.foregroundOutside));

  // Both arms separated from the trunk below the shoulders (they touch it
  // between z = 1270 and 1480 mm and hang 10-25 mm from it below).
  CageOptions options;
  const Eigen::AlignedBox3d belowShoulders(Eigen::Vector3d::Constant(-1e4), Eigen::Vector3d(1e4, 1e4, 1300.0));
  for (const auto arm : {LabelGroup::RightArm, LabelGroup::LeftArm})
    options.separations.push_back({Label(arm), Label(LabelGroup::Trunk), belowShoulders});
  const CageResult inset = buildCage(groups, options);
  expectValidCage(inset, 300);
  EXPECT_GT(inset.report.erodedVoxels, 0);
  EXPECT_GT(inset.report.check.genus, plain.report.check.genus);
  RecordProperty("inset_outside", int(inset.report.foregroundOutside));

  // Gaps between the right arm and the trunk: inside the plain cage (the
  // dilation bridges them), outside the inset one.
  const SurfaceInsideTest plainInside(plain.cage), insetInside(inset.cage);
  int gaps = 0, separated = 0;
  for (std::int64_t k = 110; k <= 155; k += 3)
    for (std::int64_t j = 30; j <= 100; j += 3)
      if (const auto gap = gapBetweenArmAndTrunk(groups, j, k)) {
        ++gaps;
        EXPECT_TRUE(plainInside.contains(*gap)) << gap->transpose();
        separated += !insetInside.contains(*gap);
      }
  RecordProperty("gaps", gaps);
  RecordProperty("gaps_outside_inset_cage", separated);
  ASSERT_GT(gaps, 30);
  EXPECT_GE(separated, gaps * 9 / 10);
}

}  // namespace
}  // namespace vox
