#include "geometry/io/mesh_io.h"

#include "geometry/ascii_text.h"
#include "geometry/error.h"


namespace vox {

bool hasTetMeshExtension(const std::string& path) {
  const std::string e = lowerExtension(path);
  return e == ".mesh" || e == ".meshb" || e == ".vtu" || e == ".msh";
}

MeshFormat meshFormatFromPath(const std::string& path) {
  const std::string e = lowerExtension(path);
  if (e == ".mesh" || e == ".meshb") return MeshFormat::Medit;
  if (e == ".vtu") return MeshFormat::Vtu;
  if (e == ".msh") return MeshFormat::Gmsh;
  throw InputError(path, "unknown mesh format (expected .mesh, .meshb, .vtu or .msh)");
}

TetMesh readTetMesh(const std::string& path) {
  switch (meshFormatFromPath(path)) {
    case MeshFormat::Medit: return readMedit(path);
    case MeshFormat::Vtu: return readVtu(path);
    case MeshFormat::Gmsh: return readGmsh(path);
  }
  throw InputError(path, "unknown mesh format");
}

void writeTetMesh(const std::string& path, const TetMesh& mesh) {
  switch (meshFormatFromPath(path)) {
    case MeshFormat::Medit: return writeMedit(path, mesh);
    case MeshFormat::Vtu: return writeVtu(path, mesh);
    case MeshFormat::Gmsh: return writeGmsh(path, mesh);
  }
}

bool hasSurfaceExtension(const std::string& path) {
  const std::string e = lowerExtension(path);
  return e == ".obj" || e == ".off" || e == ".ply";
}

}  // namespace vox
