#pragma once
// Tagged features (thesis 2.3.8): the sharp creases of the domain's outer
// boundary and the user's polylines, kept by the remesher as 1-junctions of
// their own. The label-set junctions stay implicit (element_classification.h);
// these edges are tagged explicitly, each with the line it belongs to, and
// the operations keep the tags (Table 2.4):
//  - a vertex with two tagged edges of one line is a feature vertex of that
//    line; with one, three or more, or edges of two lines (an end point, a
//    branching point, an intersection), a corner: it never moves; so is a
//    vertex where the input line turns by more than the feature angle;
//  - a feature vertex collapses only along its line, onto a vertex of the
//    same line; an untagged vertex may collapse onto a tagged one, never the
//    reverse; no collapse merges two tagged edges of a triangle;
//  - a split of a tagged edge makes two tagged edges;
//  - no flip removes a tagged edge, no Steiner point splits one;
//  - smoothing moves a feature vertex along its line: the mean of its two
//    neighbours on the line, onto the line's input geometry.
//
// Vertex ids are those of the RemeshComplex that owns the tags; it renumbers
// them with its vertices.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace vox::remesh {

class RemeshComplex;

// A tagged edge (a < b) and its line.
struct TaggedEdge {
  std::int32_t a = -1, b = -1;
  std::int32_t line = -1;
};

// A straight piece of a line's input geometry, in mm.
using FeatureSegment = std::array<Eigen::Vector3d, 2>;

class FeatureEdges {
public:
  bool empty() const { return lines_.empty(); }
  std::size_t edgeCount() const { return lines_.size(); }
  std::int32_t lineCount() const { return std::int32_t(geometry_.size()); }

  // A new line with this input geometry (the segments smoothing projects
  // onto); returns its id.
  std::int32_t addLine(std::vector<FeatureSegment> segments);
  // The line of edge (a, b), or -1 when it is not tagged.
  std::int32_t lineOf(std::int32_t a, std::int32_t b) const {
    if (degree(a) == 0 || degree(b) == 0) return -1;
    const auto it = lines_.find(key(a, b));
    return it == lines_.end() ? -1 : it->second;
  }
  // Tagged edges at v (saturating at 255).
  int degree(std::int32_t v) const { return std::size_t(v) < degree_.size() ? degree_[std::size_t(v)] : 0; }
  // A vertex where its line turns sharply: a corner, whatever its edges.
  bool isCorner(std::int32_t v) const { return std::size_t(v) < corner_.size() && corner_[std::size_t(v)] != 0; }
  void setCorner(std::int32_t v);
  // Marks as corners the vertices with two tagged edges of one line that
  // turn by more than `angleDeg`: smoothing would cut those kinks.
  void markKinks(const std::vector<Eigen::Vector3d>& positions, double angleDeg);

  void tag(std::int32_t a, std::int32_t b, std::int32_t line);
  void untag(std::int32_t a, std::int32_t b);
  // Edge (a, b) was split at m: (a, m) and (m, b) take its line.
  void split(std::int32_t a, std::int32_t b, std::int32_t m);
  // Vertex `removed` was merged into `kept` by a collapse: its tagged edges
  // now end at `kept`, and (removed, kept) is gone.
  void merge(std::int32_t removed, std::int32_t kept, const std::vector<std::int32_t>& removedNeighbors);
  // Vertex v is now vmap[v] (-1: removed).
  void renumber(const std::vector<std::int32_t>& vmap);

  // The point of line `line`'s input geometry closest to p.
  Eigen::Vector3d projectOnLine(std::int32_t line, const Eigen::Vector3d& p) const;
  const std::vector<FeatureSegment>& lineGeometry(std::int32_t line) const { return geometry_[std::size_t(line)]; }

  // Every tagged edge, sorted by line, then by end points.
  std::vector<TaggedEdge> list() const;

private:
  static std::uint64_t key(std::int32_t a, std::int32_t b) {
    if (a > b) std::swap(a, b);
    return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
  }
  void addDegree(std::int32_t v, int delta);

  std::unordered_map<std::uint64_t, std::int32_t> lines_;
  std::vector<std::uint8_t> degree_;
  std::vector<std::uint8_t> corner_;
  std::vector<std::vector<FeatureSegment>> geometry_;
};

// Closed sharp features of the outer boundary (2.3.8, "closed features"):
// the outer boundary facets (a domain tet against label 0) are clustered
// into patches of similar normals, grown across the edges where the normals
// of the two facets differ by less than `angleDeg`; the edges between two
// patches are tagged, one line per pair of patches. The patches are closed
// regions, so a crease that fades out inside one patch is not a feature.
// A patch smaller than `minPatchArea` (mm^2; the remesher passes l^2: no
// output facet fits in it) joins the neighbour it shares the longest
// boundary with, as the proxies of Variational Shape Approximation would
// absorb it. Where a line turns by more than `angleDeg`, its vertex is a
// corner. Returns the number of lines added.
std::size_t tagSharpFeatures(RemeshComplex& complex, double angleDeg, double minPatchArea = 0.0);

// User polylines (2.3.8, "marked features"): `segments` joined where they
// share an end point (same coordinates) into lines, one per connected set.
// Each segment's end points snap to the nearest vertex of a domain tet, and
// the path between them follows the mesh edges closest to the segment;
// where it strays from the segment (it crosses a 1-junction of the labels
// at a vertex, which would be a corner, or the mesh has no vertex nearer),
// the edges nearby are split at their points closest to the segment and
// the path is found again (inserted by splits, as the thesis says).
// Where a line turns by more than `angleDeg`, its vertex is a corner.
// Throws InputError(source, ...) for a point farther than `tolerance` from
// every domain vertex, leaving the complex as it was. Returns the number of
// lines added.
std::size_t tagPolylines(RemeshComplex& complex, const std::vector<FeatureSegment>& segments, double tolerance,
                         double angleDeg, const std::string& source);

// The largest distance from points along `from` (every `step` mm, ends
// included) to the nearest segment of `to`: one side of the Hausdorff
// distance between two sets of lines; infinity when `to` is empty and
// `from` is not.
double oneSidedLineDistance(const std::vector<FeatureSegment>& from, const std::vector<FeatureSegment>& to, double step);

}  // namespace vox::remesh
