#pragma once
// TetMesh: labeled tetrahedral mesh. Connectivity and positions are separate
// arrays so a deformation replaces `positions` and nothing else.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace vox {

using Tet = std::array<std::int32_t, 4>;
using Tri = std::array<std::int32_t, 3>;

// Tet labels: > 0 a material (subdomain), 0 background / imaginary, -1 dummy.
inline constexpr std::int32_t kBackgroundLabel = 0;
inline constexpr std::int32_t kDummyLabel = -1;

struct TetMesh {
  std::vector<Eigen::Vector3d> positions;  // #V, mm
  std::vector<Tet> tets;                   // #T, indices into positions
  std::vector<std::int32_t> labels;        // #T, one per tet
  // Optional names of labels (an organ table's): written as Gmsh physical
  // names and VTU field data, read back from both.
  std::map<std::int32_t, std::string> labelNames;

  std::size_t vertexCount() const { return positions.size(); }
  std::size_t tetCount() const { return tets.size(); }

  // Throws InputError(source, ...) for out-of-range indices, repeated vertices
  // in a tet, non-finite coordinates, or a label array of the wrong size.
  void validate(const std::string& source) const;
};

// Sets mesh.labelNames to the entries of `names` whose label the mesh holds.
void setLabelNames(TetMesh& mesh, const std::map<std::int32_t, std::string>& names);

// Signed volume of (a,b,c,d): positive when d is on the side of (a,b,c)'s
// counter-clockwise normal, i.e. det(b-a, c-a, d-a) / 6.
double signedVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d);
double signedVolume(const std::vector<Eigen::Vector3d>& positions, const Tet& t);

// Face k of a tet is the face opposite vertex k, oriented so its normal points
// out of a positively oriented tet.
Tri tetFace(const Tet& t, int k);

// Face adjacency: neighbors[t][k] is the tet sharing face k of t (the face
// opposite vertex k), or -1 on the boundary. Faces shared by more than two
// tets are a topology error and throw InputError(source, ...).
std::vector<std::array<std::int32_t, 4>> faceNeighbors(const TetMesh& mesh, const std::string& source = "mesh");
std::vector<std::array<std::int32_t, 4>> faceNeighbors(std::span<const Tet> tets, const std::string& source = "mesh");

// Tets around each vertex (compressed rows): the tets holding vertex v are
// tets[start[v] .. start[v + 1]), in increasing order.
struct VertexTets {
  std::vector<std::int64_t> start;  // #V + 1
  std::vector<std::int32_t> tets;
  std::span<const std::int32_t> of(std::int32_t v) const {
    return {tets.data() + start[std::size_t(v)], tets.data() + start[std::size_t(v) + 1]};
  }
};
VertexTets vertexTets(std::span<const Tet> tets, std::size_t vertexCount);

// Swap two vertices of every negatively oriented tet. Returns how many flipped.
std::size_t orientPositively(TetMesh& mesh);

}  // namespace vox
