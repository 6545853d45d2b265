#include "geometry/io/mesh_io.h"

#include "geometry/ascii_text.h"
#include "geometry/error.h"
#include "geometry/io/text_scanner.h"

#include <cmath>
#include <cstdlib>
#include <sstream>


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

void writeTetMesh(const std::string& path, const TetMesh& mesh, const MeshEdges& edges) {
  if (edges.empty()) return writeTetMesh(path, mesh);
  switch (meshFormatFromPath(path)) {
    case MeshFormat::Medit: return writeMedit(path, mesh, edges);
    case MeshFormat::Gmsh: return writeGmsh(path, mesh, edges);
    case MeshFormat::Vtu: break;
  }
  throw InputError(path, "feature lines are written to .mesh and .msh files only");
}

MeshEdges readMeshEdges(const std::string& path) {
  switch (meshFormatFromPath(path)) {
    case MeshFormat::Medit: return readMeditEdges(path);
    case MeshFormat::Gmsh: return readGmshEdges(path);
    case MeshFormat::Vtu: break;
  }
  throw InputError(path, "feature lines are read from .mesh and .msh files only");
}

void checkMeshEdges(const std::string& path, const TetMesh& mesh, const MeshEdges& edges) {
  if (edges.refs.size() != edges.edges.size())
    throw InputError(path, std::to_string(edges.edges.size()) + " feature edges but " + std::to_string(edges.refs.size()) +
                               " references");
  const auto nv = std::int64_t(mesh.vertexCount());
  for (std::size_t i = 0; i < edges.edges.size(); ++i) {
    const auto [a, b] = edges.edges[i];
    if (a < 0 || b < 0 || a >= nv || b >= nv || a == b || edges.refs[i] <= 0)
      throw InputError(path, "feature edge " + std::to_string(i + 1) + " (" + std::to_string(a) + ", " + std::to_string(b) +
                                 ", reference " + std::to_string(edges.refs[i]) + ") is not an edge of the mesh's vertices");
  }
}

std::vector<std::array<Eigen::Vector3d, 2>> readPolylineSegments(const std::string& path) {
  std::vector<std::array<Eigen::Vector3d, 2>> out;
  const std::string e = lowerExtension(path);
  if (e == ".mesh" || e == ".meshb") {
    std::vector<Eigen::Vector3d> positions;
    const MeshEdges edges = readMeditEdges(path, &positions);
    for (const auto& [a, b] : edges.edges) out.push_back({positions[std::size_t(a)], positions[std::size_t(b)]});
    if (out.empty()) throw InputError(path, "no Edges (the polylines to keep)");
    return out;
  }
  const std::string bytes = io::readWholeFile(path);
  std::size_t line = 0;
  for (std::size_t at = 0; at < bytes.size();) {
    std::size_t end = bytes.find('\n', at);
    if (end == std::string::npos) end = bytes.size();
    std::string text = bytes.substr(at, end - at);
    at = end + 1;
    ++line;
    if (const std::size_t hash = text.find('#'); hash != std::string::npos) text.resize(hash);
    std::istringstream in(text);
    std::vector<double> values;
    std::string word;
    while (in >> word) {
      char* stop = nullptr;
      const double v = std::strtod(word.c_str(), &stop);
      if (stop == word.c_str() || *stop != '\0' || !std::isfinite(v))
        throw InputError(path, "line " + std::to_string(line) + ": '" + word + "' is not a finite number");
      values.push_back(v);
    }
    if (values.empty()) continue;
    if (values.size() != 6)
      throw InputError(path, "line " + std::to_string(line) + ": " + std::to_string(values.size()) +
                                 " numbers, expected a segment x0 y0 z0 x1 y1 z1");
    const Eigen::Vector3d p(values[0], values[1], values[2]), q(values[3], values[4], values[5]);
    if (p == q) throw InputError(path, "line " + std::to_string(line) + ": the segment's two points are the same");
    out.push_back({p, q});
  }
  if (out.empty()) throw InputError(path, "no segments (one 'x0 y0 z0 x1 y1 z1' per line)");
  return out;
}

bool hasSurfaceExtension(const std::string& path) {
  const std::string e = lowerExtension(path);
  return e == ".obj" || e == ".off" || e == ".ply";
}

}  // namespace vox
