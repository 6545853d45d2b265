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

#include <string>

namespace vox {

enum class MeshFormat { Medit, Vtu, Gmsh };

// Throws InputError(path, "unknown mesh format ...") for other extensions.
MeshFormat meshFormatFromPath(const std::string& path);
bool hasTetMeshExtension(const std::string& path);

TetMesh readTetMesh(const std::string& path);
void writeTetMesh(const std::string& path, const TetMesh& mesh);

TetMesh readMedit(const std::string& path);
void writeMedit(const std::string& path, const TetMesh& mesh);
TetMesh readVtu(const std::string& path);
void writeVtu(const std::string& path, const TetMesh& mesh);
TetMesh readGmsh(const std::string& path);
void writeGmsh(const std::string& path, const TetMesh& mesh);

bool hasSurfaceExtension(const std::string& path);
TriMesh readSurface(const std::string& path);   // .obj, .off, .ply
void writeSurface(const std::string& path, const TriMesh& mesh);

}  // namespace vox
