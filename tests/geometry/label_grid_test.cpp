// LabelGrid over borrowed labels: read in place, never written, kept alive,
// copied into a vector of its own.

#include "geometry/label_grid.h"

#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

namespace vox {
namespace {

GridGeometry geometry234() {
  GridGeometry g;
  g.dims = {2, 3, 4};
  return g;
}

std::shared_ptr<std::vector<Label>> ramp() {
  auto labels = std::make_shared<std::vector<Label>>(24);
  for (std::size_t v = 0; v < labels->size(); ++v) (*labels)[v] = Label(v);
  return labels;
}

TEST(LabelGridBorrowed, ReadsTheOwnersLabelsInPlace) {
  const auto owner = ramp();
  const LabelGrid grid(geometry234(), owner->data(), owner);
  EXPECT_TRUE(grid.borrowed());
  EXPECT_EQ(grid.data(), owner->data());
  EXPECT_EQ(grid.at(1, 2, 3), Label(1 + 2 * (2 + 3 * 3)));
  EXPECT_EQ(grid.atOr(2, 0, 0, 9), Label(9));
  EXPECT_EQ(grid.maxLabel(), Label(23));
  (*owner)[5] = 99;
  EXPECT_EQ(grid.at(1, 2, 0), Label(99));
  EXPECT_EQ(grid.maxLabel(), Label(99));
}

TEST(LabelGridBorrowed, KeepsItsOwnerAliveThroughMoves) {
  auto owner = ramp();
  const std::weak_ptr<std::vector<Label>> watch = owner;
  LabelGrid grid(geometry234(), owner->data(), owner);
  owner.reset();
  EXPECT_FALSE(watch.expired());
  LabelGrid moved = std::move(grid);
  EXPECT_TRUE(moved.borrowed());
  EXPECT_EQ(std::as_const(moved).at(1, 1, 1), Label(1 + 2 * (1 + 3)));
  LabelGrid assigned;
  assigned = std::move(moved);
  EXPECT_TRUE(assigned.borrowed());
  EXPECT_FALSE(watch.expired());
  assigned = LabelGrid();
  EXPECT_TRUE(watch.expired());
}

TEST(LabelGridBorrowed, RefusesWritesAndTheVector) {
  const auto owner = ramp();
  LabelGrid grid(geometry234(), owner->data(), owner);
  EXPECT_THROW((void)grid.labels(), std::logic_error);
  EXPECT_THROW((void)std::as_const(grid).labels(), std::logic_error);
  EXPECT_THROW((void)grid.data(), std::logic_error);
  EXPECT_THROW(grid.at(0, 0, 0) = 7, std::logic_error);
  EXPECT_EQ((*owner)[0], Label(0));
}

TEST(LabelGridBorrowed, ACopyOwnsItsLabels) {
  const auto owner = ramp();
  const LabelGrid grid(geometry234(), owner->data(), owner);
  LabelGrid copy = grid;
  EXPECT_FALSE(copy.borrowed());
  EXPECT_NE(copy.data(), owner->data());
  EXPECT_EQ(copy.labels(), *owner);
  copy.at(0, 0, 0) = 7;
  EXPECT_EQ((*owner)[0], Label(0));
  LabelGrid assigned(geometry234(), 3);
  assigned = grid;
  EXPECT_FALSE(assigned.borrowed());
  EXPECT_EQ(assigned.labels(), *owner);
  // An owned grid copies as before.
  const LabelGrid again = copy;
  EXPECT_EQ(again.labels(), copy.labels());
}

}  // namespace
}  // namespace vox
