// Triangle surfaces (cages, envelopes): Wavefront OBJ and OFF, ASCII.
// Polygons are split into triangle fans (v0, v[i], v[i+1]), which keeps their
// orientation. OBJ: only `v` and `f` lines matter (texture and normal indices
// of `f a/b/c` are dropped, negative indices count back from the last vertex
// read). OFF: colours after the coordinates or the face indices are ignored.
#include "geometry/error.h"
#include "geometry/io/atomic_file.h"
#include "geometry/io/mesh_io.h"
#include "geometry/io/text_scanner.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <limits>

namespace vox {

namespace {

std::string lowerExtension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string e = path.substr(dot);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}

// Appends the fan of `polygon` (vertex indices) to `triangles`; `in` names
// the line on error, where vertices are numbered from `firstIndex` as in the file.
void addFan(const std::vector<std::int32_t>& polygon, std::vector<Tri>& triangles, io::TextScanner& in, int firstIndex) {
  if (polygon.size() < 3) in.fail("face has " + std::to_string(polygon.size()) + " vertices (at least 3 needed)");
  for (std::size_t i = 0; i < polygon.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (polygon[i] == polygon[j]) in.fail("face repeats vertex " + std::to_string(polygon[i] + firstIndex));
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i) triangles.push_back({polygon[0], polygon[i], polygon[i + 1]});
}

TriMesh readObj(const std::string& path) {
  const std::string bytes = io::readWholeFile(path);
  io::TextScanner file(bytes, path);
  TriMesh mesh;
  std::vector<std::int32_t> polygon;
  while (file.remainingBytes() > 0) {
    const std::size_t lineNo = file.line();
    const std::string_view text = file.restOfLine();
    io::TextScanner in(text, path, '#', lineNo);
    const std::string_view keyword = in.word();
    if (keyword == "v") {
      Eigen::Vector3d p;
      p.x() = in.real("x coordinate");
      p.y() = in.real("y coordinate");
      p.z() = in.real("z coordinate");
      if (mesh.positions.size() == std::size_t(std::numeric_limits<std::int32_t>::max())) in.fail("more than 2^31 - 1 vertices");
      mesh.positions.push_back(p);
    } else if (keyword == "f") {
      polygon.clear();
      const auto nv = std::int64_t(mesh.positions.size());
      for (std::string_view corner = in.word(); !corner.empty(); corner = in.word()) {
        // "v", "v/vt", "v//vn" or "v/vt/vn": the vertex index comes first.
        const std::string_view index = corner.substr(0, corner.find('/'));
        std::int64_t i = 0;
        const auto [end, ec] = std::from_chars(index.data(), index.data() + index.size(), i);
        if (index.empty() || ec != std::errc() || end != index.data() + index.size())
          in.fail("expected a vertex index, found " + io::quoted(corner));
        const std::int64_t v = i < 0 ? nv + i : i - 1;
        if (i == 0 || v < 0 || v >= nv)
          in.fail("face references vertex " + std::to_string(i) + " (" + std::to_string(nv) + " vertices defined so far)");
        polygon.push_back(std::int32_t(v));
      }
      addFan(polygon, mesh.triangles, in, 1);
    }
    // Other statements (vt, vn, g, o, s, usemtl, mtllib, l, ...) carry
    // nothing a surface needs.
  }
  if (mesh.triangles.empty()) throw InputError(path, "no faces");
  mesh.validate(path);
  return mesh;
}

// The next line that is neither blank nor a comment, as a scanner over it.
std::string_view nextDataLine(io::TextScanner& file, std::size_t& lineNo) {
  while (file.remainingBytes() > 0) {
    lineNo = file.line();
    const std::string_view line = file.restOfLine();
    const std::size_t first = line.find_first_not_of(" \t\r\f\v");
    if (first != std::string_view::npos && line[first] != '#') return line;
  }
  return {};
}

TriMesh readOff(const std::string& path) {
  const std::string bytes = io::readWholeFile(path);
  io::TextScanner file(bytes, path, '#');
  const std::string_view magic = file.word();
  // OFF with per-vertex extras (ST: texture, C: colour, N: normal) keeps x y z first.
  static constexpr std::string_view kMagic[] = {"OFF", "COFF", "NOFF", "CNOFF", "STOFF", "STCOFF", "STNOFF", "STCNOFF"};
  if (std::find(std::begin(kMagic), std::end(kMagic), magic) == std::end(kMagic))
    file.fail("not an OFF file: expected OFF, found " + io::quoted(magic));
  if (file.peekWord() == "BINARY") file.fail("binary OFF is not supported");
  const std::size_t nv = file.count("vertex count", 6);
  const std::size_t nf = file.count("face count", 8);
  file.integer("edge count");
  file.skipLine();

  TriMesh mesh;
  mesh.positions.resize(nv);
  std::size_t lineNo = file.line();
  for (std::size_t v = 0; v < nv; ++v) {
    const std::string_view line = nextDataLine(file, lineNo);
    io::TextScanner in(line, path, '#', lineNo);
    if (line.empty()) in.fail("file ends after " + std::to_string(v) + " of " + std::to_string(nv) + " vertices");
    Eigen::Vector3d& p = mesh.positions[v];
    p.x() = in.real("x coordinate");
    p.y() = in.real("y coordinate");
    p.z() = in.real("z coordinate");
  }
  std::vector<std::int32_t> polygon;
  for (std::size_t f = 0; f < nf; ++f) {
    const std::string_view line = nextDataLine(file, lineNo);
    io::TextScanner in(line, path, '#', lineNo);
    if (line.empty()) in.fail("file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
    const std::int64_t n = in.integer("face vertex count");
    if (n < 3 || n > std::int64_t(line.size())) in.fail("face vertex count " + std::to_string(n) + " is invalid");
    polygon.clear();
    for (std::int64_t k = 0; k < n; ++k) {
      const std::int64_t v = in.integer("vertex index");
      if (v < 0 || v >= std::int64_t(nv))
        in.fail("face references vertex " + std::to_string(v) + " (indices are 0-based; the file has " + std::to_string(nv) + " vertices)");
      polygon.push_back(std::int32_t(v));
    }
    addFan(polygon, mesh.triangles, in, 0);
  }
  if (mesh.triangles.empty()) throw InputError(path, "no faces");
  mesh.validate(path);
  return mesh;
}

void writeObj(const std::string& path, const TriMesh& mesh) {
  AtomicFile file(path);
  {
    io::TextOutput out(file.openStdio());
    for (const Eigen::Vector3d& p : mesh.positions) out << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    for (const Tri& t : mesh.triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  }
  file.commit();
}

void writeOff(const std::string& path, const TriMesh& mesh) {
  AtomicFile file(path);
  {
    io::TextOutput out(file.openStdio());
    out << "OFF\n" << mesh.vertexCount() << ' ' << mesh.faceCount() << " 0\n";
    for (const Eigen::Vector3d& p : mesh.positions) out << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    for (const Tri& t : mesh.triangles) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  }
  file.commit();
}

}  // namespace

TriMesh readSurface(const std::string& path) {
  const std::string e = lowerExtension(path);
  if (e == ".obj") return readObj(path);
  if (e == ".off") return readOff(path);
  throw InputError(path, "unknown surface format (expected .obj or .off)");
}

void writeSurface(const std::string& path, const TriMesh& mesh) {
  const std::string e = lowerExtension(path);
  if (e != ".obj" && e != ".off") throw InputError(path, "unknown surface format (expected .obj or .off)");
  mesh.validate(path);
  if (e == ".obj") writeObj(path, mesh);
  else writeOff(path, mesh);
}

}  // namespace vox
