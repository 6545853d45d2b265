#include "geometry/remesh/element_classification.h"

#include <algorithm>

namespace vox::remesh {

VertexKind classifyVertex(int labelCount, int featureEdgeCount, bool featureEdgesAgree) {
  if (labelCount <= 1) return VertexKind::Inside;
  if (labelCount == 2) return VertexKind::Surface;
  if (featureEdgeCount == 2 && featureEdgesAgree) return VertexKind::Feature;
  return VertexKind::Corner;
}

void classifyNeighborhood(const RemeshComplex& complex, std::int32_t v, VertexNeighborhood& out) {
  out.vertex = v;
  out.labels = LabelSet();
  out.neighbors.clear();
  out.edgeLabels.clear();
  if (out.slotStamp.size() < std::size_t(complex.vertexSlots())) {
    out.slotStamp.resize(std::size_t(complex.vertexSlots()) + std::size_t(complex.vertexSlots()) / 4, 0);
    out.slotOf.resize(out.slotStamp.size(), -1);
  }
  if (++out.stamp == 0) {
    std::fill(out.slotStamp.begin(), out.slotStamp.end(), 0);
    out.stamp = 1;
  }
  for (std::int32_t t : out.tets) {
    const std::int32_t l = complex.label(t);
    out.labels.insert(l);
    for (std::int32_t u : complex.tet(t)) {
      if (u == v) continue;
      std::int32_t& slot = out.slotOf[std::size_t(u)];
      if (out.slotStamp[std::size_t(u)] != out.stamp) {
        out.slotStamp[std::size_t(u)] = out.stamp;
        slot = std::int32_t(out.neighbors.size());
        out.neighbors.push_back(u);
        out.edgeLabels.emplace_back();
      }
      out.edgeLabels[std::size_t(slot)].insert(l);
    }
  }
  out.featureEdges = 0;
  bool overflow = out.labels.overflow(), agree = true;
  const LabelSet* firstFeature = nullptr;
  for (const LabelSet& s : out.edgeLabels) {
    overflow = overflow || s.overflow();
    if (!isFeatureEdge(s)) continue;
    ++out.featureEdges;
    if (!firstFeature) firstFeature = &s;
    else agree = agree && *firstFeature == s;
  }
  out.kind = overflow || complex.isPinned(v) ? VertexKind::Corner
                                             : classifyVertex(out.labels.size(), out.featureEdges, agree);
  out.tagged.clear();
  out.featureLine = -1;
  const FeatureEdges& features = complex.features();
  if (features.degree(v) == 0) return;
  // Table 2.4: two tagged edges of one line make a feature vertex of that
  // line, anything else a corner; so does a tagged vertex on a 1-junction.
  std::int32_t line = -1;
  bool oneLine = true;
  for (std::int32_t u : out.neighbors) {
    const std::int32_t l = features.lineOf(v, u);
    if (l < 0) continue;
    out.tagged.push_back(u);
    oneLine = oneLine && (line < 0 || line == l);
    line = l;
  }
  if (out.tagged.empty()) return;
  if (out.kind != VertexKind::Corner && out.kind != VertexKind::Feature && out.tagged.size() == 2 && oneLine &&
      !features.isCorner(v)) {
    out.kind = VertexKind::Feature;
    out.featureLine = line;
  } else {
    out.kind = VertexKind::Corner;
  }
}

void gatherNeighborhood(const RemeshComplex& complex, std::int32_t v, VertexNeighborhood& out) {
  complex.incidentTets(v, out.tets);
  classifyNeighborhood(complex, v, out);
}

namespace {

// Table 2.3 from the label sets and kinds alone.
EdgeRule labelRule(const VertexNeighborhood& u, const VertexNeighborhood& v, const LabelSet& edgeLabels) {
  EdgeRule rule;
  const bool uCorner = u.kind == VertexKind::Corner, vCorner = v.kind == VertexKind::Corner;
  if (edgeLabels == u.labels && edgeLabels == v.labels) {
    if (!uCorner && !vCorner && u.kind == v.kind) {
      rule.condition = EdgeCondition::Similarity;
      return rule;
    }
    // Same labels, different dimensions: the higher-dimensional vertex is
    // included in the other one's junction.
    if (u.kind != v.kind) {
      rule.condition = EdgeCondition::Inclusion;
      rule.moving = u.kind > v.kind ? u.vertex : v.vertex;
    }
    return rule;
  }
  if (edgeLabels == u.labels && !uCorner && u.labels.subsetOf(v.labels)) {
    rule.condition = EdgeCondition::Inclusion;
    rule.moving = u.vertex;
  } else if (edgeLabels == v.labels && !vCorner && v.labels.subsetOf(u.labels)) {
    rule.condition = EdgeCondition::Inclusion;
    rule.moving = v.vertex;
  }
  return rule;
}

}  // namespace

EdgeRule edgeRule(const VertexNeighborhood& u, const VertexNeighborhood& v, const LabelSet& edgeLabels,
                  std::int32_t dummyVertex) {
  EdgeRule rule;
  if (u.vertex == dummyVertex || v.vertex == dummyVertex) return rule;
  if (u.labels.overflow() || v.labels.overflow() || edgeLabels.overflow()) return rule;
  if (u.tagged.empty() && v.tagged.empty()) return labelRule(u, v, edgeLabels);
  rule = labelRule(u, v, edgeLabels);
  if (u.taggedEdgeTo(v.vertex)) return rule;  // along a tagged line: its kinds decide
  if (!u.tagged.empty() && !v.tagged.empty()) return EdgeRule{};
  // One tagged end: only the other one may move, onto it.
  const std::int32_t free = u.tagged.empty() ? u.vertex : v.vertex;
  if (rule.condition == EdgeCondition::Similarity) return EdgeRule{EdgeCondition::Inclusion, free};
  if (rule.condition == EdgeCondition::Inclusion && rule.moving != free) return EdgeRule{};
  return rule;
}

}  // namespace vox::remesh
