#pragma once
// Tetrahedral mesh formats: Medit .mesh (ASCII) and .meshb (binary), VTK
// .vtu (XML; ascii, binary base64 and zlib-compressed appended data as written
// by meshio/ParaView), Gmsh .msh 4.1 (ASCII and binary). Surface formats: OBJ,
// OFF, PLY.
//
// Labels: Medit tetrahedron reference, VTU cell data array "label" (or
// "medit:ref", "gmsh:physical" on read), Gmsh physical tag of the element's
// entity. Writers are atomic (AtomicFile). Readers validate indices and
// coordinates and throw InputError naming the file and the fault.

#include "geometry/tet_mesh.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vox {

// Feature lines of a tet mesh: edges between its vertices (0-based), each
// with the reference of its line (> 0). Written as the Medit `Edges` block
// (the reference as the edge's reference) and as Gmsh 2-node lines, one
// curve entity per reference with the reference as its physical tag
// (named "feature_<ref>").
struct MeshEdges {
  std::vector<std::array<std::int32_t, 2>> edges;
  std::vector<std::int32_t> refs;
  bool empty() const { return edges.empty(); }
};

enum class MeshFormat { Medit, Vtu, Gmsh };

// Throws InputError(path, "unknown mesh format ...") for other extensions.
MeshFormat meshFormatFromPath(const std::string& path);
bool hasTetMeshExtension(const std::string& path);

TetMesh readTetMesh(const std::string& path);
void writeTetMesh(const std::string& path, const TetMesh& mesh);
// With feature lines: .mesh, .meshb and .msh; a .vtu path is refused
// (InputError) unless `edges` is empty.
void writeTetMesh(const std::string& path, const TetMesh& mesh, const MeshEdges& edges);
// The feature lines of a .mesh (Edges) or .msh (2-node lines on curves).
MeshEdges readMeshEdges(const std::string& path);
// Throws InputError(path, ...) for an edge index out of `mesh`, an edge of
// one vertex, a reference not > 0, or refs and edges of different sizes.
void checkMeshEdges(const std::string& path, const TetMesh& mesh, const MeshEdges& edges);

// Polylines given to the remesher (`--features`), as segments in mm: a
// Medit .mesh with Vertices and Edges (tetrahedra optional, ignored), or a
// text file of one segment "x0 y0 z0 x1 y1 z1" per line ('#' starts a
// comment, blank lines are skipped). Throws InputError naming the file and
// the line or the edge at fault; an empty list is refused too.
std::vector<std::array<Eigen::Vector3d, 2>> readPolylineSegments(const std::string& path);

TetMesh readMedit(const std::string& path);
void writeMedit(const std::string& path, const TetMesh& mesh);
void writeMedit(const std::string& path, const TetMesh& mesh, const MeshEdges& edges);
// Vertices and Edges of an ASCII .mesh (tetrahedra optional): the edges and
// their references, with `positions` receiving the vertices.
MeshEdges readMeditEdges(const std::string& path, std::vector<Eigen::Vector3d>* positions = nullptr);
TetMesh readVtu(const std::string& path);
void writeVtu(const std::string& path, const TetMesh& mesh);
TetMesh readGmsh(const std::string& path);
void writeGmsh(const std::string& path, const TetMesh& mesh);
void writeGmsh(const std::string& path, const TetMesh& mesh, const MeshEdges& edges);
MeshEdges readGmshEdges(const std::string& path);

bool hasSurfaceExtension(const std::string& path);
TriMesh readSurface(const std::string& path);   // .obj, .off, .ply
void writeSurface(const std::string& path, const TriMesh& mesh);

}  // namespace vox
