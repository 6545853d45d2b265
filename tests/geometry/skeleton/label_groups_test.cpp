#include "geometry/skeleton/label_groups.h"

#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/synth.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <map>
#include <vector>

namespace vox {
namespace {

TEST(LabelGroups, ClassifiesIcrpOrganNames) {
  const struct {
    const char* name;
    OrganLabelGroup part;
  } cases[] = {
      {"Muscle, arms", {Limb::Arm, BodySide::Unknown}},
      {"Humeri, upper half, cortical", {Limb::Arm, BodySide::Unknown}},
      {"Ulnae and radii, medullary cavity", {Limb::Arm, BodySide::Unknown}},
      {"Wrists and hand bones, spongiosa", {Limb::Arm, BodySide::Unknown}},
      {"Skin, legs", {Limb::Leg, BodySide::Unknown}},
      {"Femora, lower half, spongiosa", {Limb::Leg, BodySide::Unknown}},
      {"Tibiae, fibulae and patellae, cortical", {Limb::Leg, BodySide::Unknown}},
      {"Ankles and foot bones, cortical", {Limb::Leg, BodySide::Unknown}},
      {"Brain", {Limb::Head, BodySide::Unknown}},
      {"Cranium, spongiosa", {Limb::Head, BodySide::Unknown}},
      {"Eye lense, left", {Limb::Head, BodySide::Left}},
      {"Teeth", {Limb::Head, BodySide::Unknown}},
      {"Salivary glands, right", {Limb::Head, BodySide::Right}},
      {"Liver", {Limb::Trunk, BodySide::Unknown}},
      {"Clavicles, cortical", {Limb::Trunk, BodySide::Unknown}},
      {"Breast, left, adipose tissue", {Limb::Trunk, BodySide::Left}},
      {"Cervical spine, cortical", {Limb::Trunk, BodySide::Unknown}},
      {"Muscle, arms, right", {Limb::Arm, BodySide::Right}},
      {"Humerus, left", {Limb::Arm, BodySide::Left}},
  };
  for (const auto& c : cases) EXPECT_EQ(classifyOrganName(c.name), c.part) << c.name;
}

TEST(LabelGroups, EveryIcrpLimbOrganFound) {
  // Counted from the organ tables: 17 arm and 17 leg structures (bones,
  // muscle, skin, vessels, nodes, cartilage, residual tissue), 25 of the head.
  for (const char* table : {"icrp110_am_organs.dat", "icrp110_af_organs.dat"}) {
    const OrganTable organs = OrganTable::read(test::assetPath(table));
    std::map<Limb, int> count;
    for (const auto& [id, o] : organs.organs()) ++count[classifyOrganName(o.name).limb];
    EXPECT_EQ(count[Limb::Arm], 17) << table;
    EXPECT_EQ(count[Limb::Leg], 17) << table;
    EXPECT_EQ(count[Limb::Head], 25) << table;
  }
}

TEST(LabelGroups, BodyPartNames) {
  for (int i = 1; i <= kLabelGroupCount; ++i) EXPECT_EQ(labelGroupFromName(labelGroupName(LabelGroup(i))), LabelGroup(i));
  EXPECT_EQ(labelGroupFromName("arm_right"), LabelGroup::RightArm);
  EXPECT_EQ(labelGroupFromName("Left-Leg"), LabelGroup::LeftLeg);
  try {
    labelGroupFromName("tail", "pose.json");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pose.json: unknown body part 'tail'"), std::string::npos) << e.what();
  }
}

TEST(LabelGroups, StickFigureFromNames) {
  const LabelGrid grid = synthesize(SynthKind::StickFigure, 64);
  const LabelGrid groups = labelGroupGrid(grid, synthOrganTable(SynthKind::StickFigure));
  const std::map<Label, LabelGroup> expected = {{1, LabelGroup::Trunk},    {2, LabelGroup::Head},     {3, LabelGroup::RightArm},
                                              {4, LabelGroup::LeftArm},  {5, LabelGroup::RightLeg}, {6, LabelGroup::LeftLeg},
                                              {7, LabelGroup::Trunk},    {8, LabelGroup::RightArm}, {9, LabelGroup::LeftArm}};
  for (std::size_t v = 0; v < grid.labels().size(); ++v) {
    const Label l = grid.labels()[v];
    ASSERT_EQ(groups.labels()[v], l == 0 ? Label(0) : Label(expected.at(l))) << v;
  }
  EXPECT_EQ(binaryGroupGrid(grid).maxLabel(), 1);
}

// Organ names without a side ("Muscle, arms"): the side comes from the
// midline, and matches what the sided names say.
TEST(LabelGroups, SidesFromGeometry) {
  const LabelGrid grid = synthesize(SynthKind::StickFigure, 64);
  const OrganTable sided = synthOrganTable(SynthKind::StickFigure);
  OrganTable unsided;
  for (const auto& [id, o] : sided.organs()) {
    Organ copy = o;
    for (const char* side : {", right", ", left"})
      if (const auto at = copy.name.find(side); at != std::string::npos) copy.name.erase(at);
    unsided.add(copy);
  }
  EXPECT_EQ(unsided.find(3)->name, "Muscle, arms");
  const LabelGrid fromNames = labelGroupGrid(grid, sided);
  const LabelGrid fromGeometry = labelGroupGrid(grid, unsided);
  EXPECT_EQ(fromGeometry.labels(), fromNames.labels());
  // Mirrored convention: the sides swap.
  const LabelGrid mirrored = labelGroupGrid(grid, unsided, {.rightSideAtLowX = false});
  for (std::size_t v = 0; v < grid.labels().size(); ++v) {
    if (fromNames.labels()[v] == Label(LabelGroup::RightArm)) {
      ASSERT_EQ(mirrored.labels()[v], Label(LabelGroup::LeftArm));
    }
  }
}

TEST(LabelGroups, NearestGroupIsTheNearestForegroundVoxel) {
  LabelGrid grid = synthesize(SynthKind::StickFigure, 40);
  grid.geometry().spacing = {1.5, 1.0, 4.0};
  grid.geometry().origin = {-7.0, 3.0, 11.0};
  const GridGeometry& g = grid.geometry();
  // Points inside, beside the figure and far off the grid, from a fixed
  // sequence.
  std::vector<Eigen::Vector3d> points;
  std::uint64_t state = 12345;
  const auto next = [&state] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) / double(1ull << 53);
  };
  const Eigen::Vector3d lo = g.boxMin(), size = g.boxMax() - g.boxMin();
  for (int n = 0; n < 400; ++n) {
    const double stretch = n < 300 ? 1.0 : 3.0;
    points.push_back(lo - 0.5 * (stretch - 1.0) * size + stretch * Eigen::Vector3d(next(), next(), next()).cwiseProduct(size));
  }
  const std::vector<Label> found = nearestGroups(points, grid);
  ASSERT_EQ(found.size(), points.size());
  for (std::size_t p = 0; p < points.size(); ++p) {
    double best = std::numeric_limits<double>::infinity();
    Label label = 0;
    for (std::int64_t v = 0; v < grid.voxelCount(); ++v) {
      if (grid.labels()[std::size_t(v)] == 0) continue;
      const Index3 ijk = g.ijk(v);
      const double d = (g.voxelCenter(ijk[0], ijk[1], ijk[2]) - points[p]).squaredNorm();
      if (d < best) {
        best = d;
        label = grid.labels()[std::size_t(v)];
      }
    }
    EXPECT_EQ(found[p], label) << "point " << p;
  }
  EXPECT_EQ(nearestGroups(points, LabelGrid(g, 0)), std::vector<Label>(points.size(), 0));
}

TEST(LabelGroups, AdultMalePhantom) {
  const LabelGrid grid = readGrid(test::assetPath("icrp110_am.nii.gz"));
  const LabelGrid groups = labelGroupGrid(grid, OrganTable::read(test::assetPath("icrp110_am_organs.dat")));
  const GridGeometry& g = grid.geometry();
  std::map<Label, std::int64_t> count;
  std::map<Label, double> meanX;
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
    const Label s = groups.labels()[v];
    ASSERT_EQ(s == 0, grid.labels()[v] == 0);
    ++count[s];
    meanX[s] += g.voxelCenter(g.ijk(v)[0], 0, 0).x();
  }
  for (int part = 1; part <= kLabelGroupCount; ++part) {
    EXPECT_GT(count[Label(part)], 50000) << labelGroupName(LabelGroup(part));
    meanX[Label(part)] /= double(count[Label(part)]);
  }
  // The phantom's i runs from the body's right to its left.
  EXPECT_LT(meanX[Label(LabelGroup::RightArm)], meanX[Label(LabelGroup::Trunk)] - 150.0);
  EXPECT_GT(meanX[Label(LabelGroup::LeftArm)], meanX[Label(LabelGroup::Trunk)] + 150.0);
  EXPECT_LT(meanX[Label(LabelGroup::RightLeg)], meanX[Label(LabelGroup::Trunk)]);
  EXPECT_GT(meanX[Label(LabelGroup::LeftLeg)], meanX[Label(LabelGroup::Trunk)]);
  // Arms and legs hold about the same number of voxels on both sides.
  EXPECT_NEAR(double(count[Label(LabelGroup::RightArm)]) / double(count[Label(LabelGroup::LeftArm)]), 1.0, 0.1);
  EXPECT_NEAR(double(count[Label(LabelGroup::RightLeg)]) / double(count[Label(LabelGroup::LeftLeg)]), 1.0, 0.1);
}

}  // namespace
}  // namespace vox
