// Table 2.1 (vertex kinds) and Tables 2.2-2.3 (which vertex an edge lets
// move), on hand-made label sets.

#include "geometry/remesh/element_classification.h"

#include <gtest/gtest.h>

#include <initializer_list>

namespace vox::remesh {
namespace {

LabelSet labels(std::initializer_list<std::int32_t> ls) {
  LabelSet s;
  for (std::int32_t l : ls) s.insert(l);
  return s;
}

VertexNeighborhood vertex(std::int32_t id, std::initializer_list<std::int32_t> ls, int featureEdges) {
  VertexNeighborhood v;
  v.vertex = id;
  v.labels = labels(ls);
  v.featureEdges = featureEdges;
  v.kind = classifyVertex(v.labels.size(), featureEdges);
  return v;
}

TEST(ElementClassification, VertexKindsOfTable21) {
  EXPECT_EQ(classifyVertex(1, 0), VertexKind::Inside);
  EXPECT_EQ(classifyVertex(2, 0), VertexKind::Surface);
  EXPECT_EQ(classifyVertex(3, 2), VertexKind::Feature);
  EXPECT_EQ(classifyVertex(4, 2), VertexKind::Feature);
  EXPECT_EQ(classifyVertex(4, 3), VertexKind::Corner);
  // Junction points the table leaves out are corners too: a free end of a
  // 1-junction, a branching, labels meeting at a point only.
  EXPECT_EQ(classifyVertex(3, 1), VertexKind::Corner);
  EXPECT_EQ(classifyVertex(3, 3), VertexKind::Corner);
  EXPECT_EQ(classifyVertex(3, 0), VertexKind::Corner);
}

TEST(ElementClassification, ConditionsOfTables22And23) {
  const std::int32_t dummy = 99;
  const auto inside = vertex(1, {5}, 0), inside2 = vertex(2, {5}, 0);
  const auto surface = vertex(3, {5, 6}, 0), surface2 = vertex(4, {5, 6}, 0), otherSurface = vertex(5, {5, 7}, 0);
  const auto feature = vertex(6, {5, 6, 7}, 2), feature2 = vertex(7, {5, 6, 7}, 2);
  const auto corner = vertex(8, {5, 6, 7, 8}, 3), corner2 = vertex(9, {5, 6, 7, 8}, 4);

  // Similarity: both move.
  EXPECT_EQ(edgeRule(inside, inside2, labels({5}), dummy).condition, EdgeCondition::Similarity);
  EXPECT_EQ(edgeRule(surface, surface2, labels({5, 6}), dummy).condition, EdgeCondition::Similarity);
  EXPECT_EQ(edgeRule(feature, feature2, labels({5, 6, 7}), dummy).condition, EdgeCondition::Similarity);
  // Inclusion: the vertex of higher dimension moves onto the other.
  for (const auto& [moving, fixed, edge] :
       {std::tuple{inside, surface, labels({5})}, std::tuple{surface, feature, labels({5, 6})},
        std::tuple{feature, corner, labels({5, 6, 7})}, std::tuple{surface, corner, labels({5, 6})}}) {
    const EdgeRule r = edgeRule(fixed, moving, edge, dummy);
    EXPECT_EQ(r.condition, EdgeCondition::Inclusion);
    EXPECT_EQ(r.moving, moving.vertex);
  }
  // Exclusion: critical edges, different junctions, corners, the dummy.
  EXPECT_EQ(edgeRule(surface, surface2, labels({5}), dummy).condition, EdgeCondition::Exclusion);  // critical
  EXPECT_EQ(edgeRule(surface, otherSurface, labels({5}), dummy).condition, EdgeCondition::Exclusion);
  EXPECT_EQ(edgeRule(feature, feature2, labels({5, 6}), dummy).condition, EdgeCondition::Exclusion);  // not the 1-junction
  EXPECT_EQ(edgeRule(corner, corner2, labels({5, 6, 7, 8}), dummy).condition, EdgeCondition::Exclusion);
  EXPECT_EQ(edgeRule(inside, vertex(dummy, {0}, 0), labels({0}), dummy).condition, EdgeCondition::Exclusion);
}

TEST(ElementClassification, LabelSetsAreSortedSmallSets) {
  LabelSet s = labels({7, 3, 5, 3});
  ASSERT_EQ(s.size(), 3);
  EXPECT_EQ(s.toString(), "{3,5,7}");
  EXPECT_TRUE(labels({3, 7}).subsetOf(s));
  EXPECT_FALSE(labels({3, 4}).subsetOf(s));
  EXPECT_EQ(s.intersection(labels({5, 7, 9})).toString(), "{5,7}");
  LabelSet big;
  for (int l = 0; l < 20; ++l) big.insert(l);
  EXPECT_TRUE(big.overflow());
}

}  // namespace
}  // namespace vox::remesh
