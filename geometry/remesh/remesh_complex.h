#pragma once
// RemeshComplex: the extended complex the M-MAd operations edit in place
// (thesis 2.2.2, Figure 2.10). It holds the domain tets (label > 0), the
// imaginary tets (label 0) and one dummy vertex joined to every outer facet,
// so every facet has exactly two tets and the outer boundary is an interface
// like any other.
//
// Storage is a flat, cache-friendly tet array in the style of a
// triangulation data structure: per tet its 4 vertices, its label and its 4
// face neighbours (encoded 4 * tet + face); per vertex its position and one
// incident tet. Removed tets and vertices go to free lists and are reused
// last-in first-out, so the result never depends on anything but the order
// of the operations.

#include "geometry/remesh/face_adjacency.h"
#include "geometry/remesh/feature_edges.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vox::remesh {

// The tets around an edge (a, b) in circulation order, with the link
// vertices between them: tets[i] holds a, b, ring[i] and ring[(i+1) % n].
struct EdgeRing {
  std::int32_t a = -1, b = -1;
  std::vector<std::int32_t> tets;
  std::vector<std::int32_t> ring;
  std::size_t size() const { return tets.size(); }
};

class RemeshComplex;

// Throws InputError(source, "tet N has zero volume ...") for the first tet
// whose four vertices are coplanar (what RemeshComplex refuses), so a
// command can refuse it before any other work.
void checkNoFlatTets(const TetMesh& mesh, const std::string& source);
[[noreturn]] void throwFlatTet(const std::string& source, std::size_t tet);

// Breadth-first walks of vertex stars that mark tets with a stamp instead of
// clearing a set. Each walker has its own marks: one walker per thread lets
// several threads read the same complex at once.
class StarWalker {
public:
  // Tets incident to v, breadth first from anyTet(v) through the faces
  // containing v. Never called on the dummy vertex.
  void incidentTets(const RemeshComplex& complex, std::int32_t v, std::vector<std::int32_t>& out);
  // A tet containing both a and b, or -1 when (a, b) is not an edge.
  std::int32_t findEdgeTet(const RemeshComplex& complex, std::int32_t a, std::int32_t b);

private:
  std::uint32_t nextStamp(std::size_t tetSlots);
  std::vector<std::uint32_t> mark_;
  std::uint32_t stamp_ = 0;
  std::vector<std::int32_t> queue_;
};

class RemeshComplex {
public:
  RemeshComplex() = default;

  // Builds the extended complex of `mesh`. Its tets must be conforming (each
  // face shared by at most two tets; negatively oriented tets are turned
  // over, vertices no tet uses are dropped from the output); labels
  // are > 0 (domain) or 0 (imaginary). Each facet without a neighbour is
  // joined to the dummy vertex; the new dummy tet gets kDummyLabel behind an
  // imaginary tet and the outside label 0 behind a domain tet, so the domain
  // always meets "outside" through label 0. The outer boundary need not be
  // a manifold surface: parts touching at a vertex get copies of it (one
  // per group of face-connected tets, merged again by toTetMesh), and along
  // an edge met by 2m open facets the dummy tets are glued around the edge
  // by angle, as the outside turns. Such vertices, and those where the open
  // facets form several fans, are pinned. Throws InputError(source, ...) for
  // zero-volume tets, negative labels, faces shared by more than two tets,
  // tets that overlap around a face, an edge or a vertex
  // (checkLocalEmbedding), and edges whose tets form more than one cycle:
  // what the walks of the operations assume.
  explicit RemeshComplex(const TetMesh& mesh, const std::string& source = "mesh");

  // Live tets with label > 0 (and, with keepImaginary, the geometric tets of
  // label 0). Vertices are renumbered in increasing slot order; tets keep
  // their slot order, so the output depends only on the complex. `features`
  // receives the tagged edges in the output's vertex numbering.
  TetMesh toTetMesh(bool keepImaginary = false, std::vector<TaggedEdge>* features = nullptr) const;

  // Tagged feature edges (feature_edges.h), renumbered with the vertices.
  const FeatureEdges& features() const { return features_; }
  FeatureEdges& features() { return features_; }

  // --- Sizes and liveness (slots include removed elements).
  std::int32_t vertexSlots() const { return std::int32_t(positions_.size()); }
  std::int32_t tetSlots() const { return std::int32_t(tets_.size()); }
  std::size_t liveVertexCount() const { return positions_.size() - freeVertices_.size(); }
  std::size_t liveTetCount() const { return tets_.size() - freeTets_.size(); }
  bool vertexAlive(std::int32_t v) const { return vertexTet_[std::size_t(v)] >= 0; }
  bool tetAlive(std::int32_t t) const { return tets_[std::size_t(t)][0] >= 0; }

  std::int32_t dummyVertex() const { return dummy_; }
  // A pinned vertex is where the input's outer boundary is not a surface
  // (see the constructor): no operation moves or removes it (a corner), and
  // an outer-boundary edge between two pinned vertices is not split.
  bool isPinned(std::int32_t v) const { return std::size_t(v) < pinned_.size() && pinned_[std::size_t(v)] != 0; }
  // Where parts of the input touch at a vertex, the complex holds one copy of
  // it per part: the input's vertex for every copy (and for the vertex
  // itself), -1 elsewhere. An operation must not make a vertex adjacent to
  // two copies of one vertex (in the output they are one, and the parts would
  // touch along a new edge), so collapses and flips next to a copy, and
  // splits whose new vertex would see two copies, are not made.
  std::int32_t pinchOf(std::int32_t v) const { return std::size_t(v) < pinchOf_.size() ? pinchOf_[std::size_t(v)] : -1; }
  bool hasPinches() const { return hasPinches_; }
  // A tet containing the dummy vertex has no geometry.
  bool isDummyTet(std::int32_t t) const {
    const Tet& q = tets_[std::size_t(t)];
    return q[0] == dummy_ || q[1] == dummy_ || q[2] == dummy_ || q[3] == dummy_;
  }

  // --- Element data.
  const Eigen::Vector3d& position(std::int32_t v) const { return positions_[std::size_t(v)]; }
  void setPosition(std::int32_t v, const Eigen::Vector3d& p) { positions_[std::size_t(v)] = p; }
  const std::vector<Eigen::Vector3d>& positions() const { return positions_; }
  const Tet& tet(std::int32_t t) const { return tets_[std::size_t(t)]; }
  std::int32_t label(std::int32_t t) const { return labels_[std::size_t(t)]; }
  // Tet across face k of t, and that face's index in it.
  std::int32_t neighbor(std::int32_t t, int k) const { return neighbors_[std::size_t(t)][std::size_t(k)] >> 2; }
  int neighborFace(std::int32_t t, int k) const { return neighbors_[std::size_t(t)][std::size_t(k)] & 3; }
  std::int32_t anyTet(std::int32_t v) const { return vertexTet_[std::size_t(v)]; }
  // Local index (0..3) of vertex v in tet t, or -1.
  int localIndex(std::int32_t t, std::int32_t v) const {
    const Tet& q = tets_[std::size_t(t)];
    return q[0] == v ? 0 : q[1] == v ? 1 : q[2] == v ? 2 : q[3] == v ? 3 : -1;
  }
  // Signed volume of a geometric tet (dummy tets: undefined).
  double volume(std::int32_t t) const { return signedVolume(positions_, tets_[std::size_t(t)]); }

  // --- Queries (single-threaded: they share the complex's StarWalker).
  void incidentTets(std::int32_t v, std::vector<std::int32_t>& out) const { walker_.incidentTets(*this, v, out); }
  std::int32_t findEdgeTet(std::int32_t a, std::int32_t b) const { return walker_.findEdgeTet(*this, a, b); }
  // The vertices of `tets` other than `except` and the dummy vertex, sorted
  // and unique: with `tets` the star of `except`, its one-ring. Only those
  // above `above` when given (filtered before sorting). Thread-safe.
  void starVertices(const std::vector<std::int32_t>& tets, std::int32_t except, std::vector<std::int32_t>& out,
                    std::int32_t above = -1) const;
  // Circulates around edge (a, b) starting from tet t, which contains both.
  void edgeRing(std::int32_t a, std::int32_t b, std::int32_t t, EdgeRing& out) const;

  // --- Surgery, used by the operations, which keep the complex consistent.
  std::int32_t addVertex(const Eigen::Vector3d& p);
  void removeVertex(std::int32_t v);
  std::int32_t addTet(const Tet& q, std::int32_t label);
  void removeTet(std::int32_t t);
  void setTetVertex(std::int32_t t, int k, std::int32_t v) { tets_[std::size_t(t)][std::size_t(k)] = v; }
  void setAnyTet(std::int32_t v, std::int32_t t) { vertexTet_[std::size_t(v)] = t; }
  // Makes face k0 of t0 and face k1 of t1 neighbours.
  void glue(std::int32_t t0, int k0, std::int32_t t1, int k1) {
    neighbors_[std::size_t(t0)][std::size_t(k0)] = 4 * t1 + k1;
    neighbors_[std::size_t(t1)][std::size_t(k1)] = 4 * t0 + k0;
  }
  // Replaces the tets `removed` by `added` (with `addedLabels`), which must
  // fill the same cavity: every face of an added tet matches another added
  // tet or a face of the cavity's boundary. Returns the new tets' slots.
  void replaceTets(const std::vector<std::int32_t>& removed, const std::vector<Tet>& added,
                   const std::vector<std::int32_t>& addedLabels, std::vector<std::int32_t>& out);
  // Cosine of tet t's smallest dihedral angle (minDihedralCosine, tet_shape.h).
  double minDihedralCosineOf(std::int32_t t) const;
  // The largest of those over the geometric tets among `tets` (a star's
  // worst angle), -1 when there are none.
  double worstDihedralCosineOf(const std::vector<std::int32_t>& tets) const;
  std::int32_t encodedNeighbor(std::int32_t t, int k) const { return neighbors_[std::size_t(t)][std::size_t(k)]; }
  void setEncodedNeighbor(std::int32_t t, int k, std::int32_t code) { neighbors_[std::size_t(t)][std::size_t(k)] = code; }

  // Renumbers the live vertices along a Morton curve of their positions and
  // the live tets by their smallest vertex, dropping removed slots: the
  // stars the operations walk then lie close together in memory. The
  // complex is the same; only ids change (deterministically).
  void reorderForLocality();

  // Combinatorial consistency (symmetric adjacency on identical faces, every
  // live vertex's anyTet contains it, no live tet uses a removed vertex) and,
  // with `geometry`, a positive volume for every geometric tet. Returns an
  // empty string, or the first problem found. For tests and debugging.
  std::string checkConsistency(bool geometry) const;

private:
  std::vector<Eigen::Vector3d> positions_;
  std::vector<std::int32_t> vertexTet_;  // -1 for a removed vertex
  std::vector<Tet> tets_;                // {-1,-1,-1,-1} for a removed tet
  std::vector<std::int32_t> labels_;
  std::vector<std::array<std::int32_t, 4>> neighbors_;
  std::vector<std::int32_t> freeVertices_;
  std::vector<std::int32_t> freeTets_;
  std::int32_t dummy_ = -1;
  std::vector<std::uint8_t> pinned_;
  std::vector<std::int32_t> pinchOf_;  // see pinchOf(); set by splitPinchedVertices
  bool hasPinches_ = false;
  FeatureEdges features_;

  void splitPinchedVertices();
  // -1 when the walk around edge (a, b) from tet t closes up after exactly
  // `count` tets (all those of the edge); otherwise a tet of the edge that
  // the walk did not reach (or the tet where it stopped). `starOfA`: a's tets.
  std::int32_t tetOffEdgeCycle(std::int32_t a, std::int32_t b, std::int32_t t, std::size_t count,
                               const std::vector<std::int32_t>& starOfA) const;
  void glueCone(std::size_t domainTets, const std::string& source);

  mutable StarWalker walker_;
};

}  // namespace vox::remesh
