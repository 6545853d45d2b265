#pragma once
// Classification of vertices and edges from their incident label sets
// (thesis 2.2.3-2.2.4, Table 2.1) and the conditions that decide which
// vertices an operation may move (2.3.1, Tables 2.2-2.3). The feature
// complex stays implicit: every answer is read off the local label sets.

#include "geometry/remesh/label_set.h"
#include "geometry/remesh/remesh_complex.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace vox::remesh {

// A vertex's dimension in the feature complex (Table 2.1).
enum class VertexKind : std::uint8_t {
  Corner = 0,   // 0-junction: |S| > 2 and not two feature edges
  Feature = 1,  // inside a 1-junction: |S| > 2 and two feature edges
  Surface = 2,  // on a 2-junction: |S| = 2
  Inside = 3,   // |S| = 1
};

// Table 2.1, where a vertex with three or more labels is a feature vertex
// only inside a 1-junction (exactly two feature edges). The free end of a
// 1-junction (one feature edge), a branching point (three or more, also
// with |S| = 3) and a point where labels meet without a feature edge are
// junction points too: corners, which no operation moves or removes. So is
// a vertex whose two feature edges carry different label sets: one
// 1-junction ends there and another begins (meshes from other meshers have
// them where several organs meet).
VertexKind classifyVertex(int labelCount, int featureEdgeCount, bool featureEdgesAgree = true);

// Feature edges are boundary edges between three or more labels (2.2.4).
inline bool isFeatureEdge(const LabelSet& edgeLabels) { return edgeLabels.size() >= 3; }

// Everything an operation needs to know about one vertex: its tets T_1(v),
// S(v), its one-ring with the label set of each edge, and its kind.
struct VertexNeighborhood {
  std::int32_t vertex = -1;
  std::vector<std::int32_t> tets;
  LabelSet labels;
  std::vector<std::int32_t> neighbors;  // the one-ring (may hold the dummy vertex)
  std::vector<LabelSet> edgeLabels;     // S(vertex, neighbors[i])
  int featureEdges = 0;
  VertexKind kind = VertexKind::Inside;
  // Tagged features (feature_edges.h): the neighbours across tagged edges,
  // and for a feature vertex of a tagged line (two tagged edges of one line,
  // kind Feature) that line, else -1.
  std::vector<std::int32_t> tagged;
  std::int32_t featureLine = -1;
  bool taggedEdgeTo(std::int32_t u) const { return std::find(tagged.begin(), tagged.end(), u) != tagged.end(); }

  // Index of u in `neighbors`, or -1.
  int find(std::int32_t u) const {
    return std::size_t(u) < slotStamp.size() && slotStamp[std::size_t(u)] == stamp ? slotOf[std::size_t(u)] : -1;
  }
  bool onHull() const { return labels.contains(-1); }

  // Vertex-indexed slots of the current one-ring (valid where slotStamp
  // equals stamp): constant-time find without clearing between vertices.
  std::vector<std::uint32_t> slotStamp;
  std::vector<std::int32_t> slotOf;
  std::uint32_t stamp = 0;
};

// Fills `out` from the tets around v (walks the complex: single-threaded).
void gatherNeighborhood(const RemeshComplex& complex, std::int32_t v, VertexNeighborhood& out);
// Same from an explicit list of v's tets (thread-safe, read-only).
void classifyNeighborhood(const RemeshComplex& complex, std::int32_t v, VertexNeighborhood& out);

// The condition an edge (u, v) meets (Table 2.2) and what it allows (Table 2.3).
enum class EdgeCondition : std::uint8_t {
  Similarity,  // both vertices may move (mid-point collapse)
  Inclusion,   // only `moving` may move, towards the other vertex
  Exclusion,   // neither may move
};
struct EdgeRule {
  EdgeCondition condition = EdgeCondition::Exclusion;
  std::int32_t moving = -1;  // for Inclusion: the vertex of higher dimension in the feature complex
};

// Similarity: S(u) = S(v) = S(uv) and neither is a corner. Inclusion:
// S(uv) = S(moving) is a subset of the other vertex's set and `moving` has
// the higher dimension (fewer labels, or the other one is a corner); the
// moving vertex is never a corner. Everything else, edges to the dummy
// vertex and overflowing sets are Exclusion. With tagged features (Table
// 2.4) an untagged edge between two tagged vertices is Exclusion, and of an
// untagged edge with one tagged end only the untagged end may move.
EdgeRule edgeRule(const VertexNeighborhood& u, const VertexNeighborhood& v, const LabelSet& edgeLabels,
                  std::int32_t dummyVertex);

}  // namespace vox::remesh
