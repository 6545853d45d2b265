// Triangle surfaces (cages, envelopes): Wavefront OBJ and OFF (ASCII), PLY
// (ASCII and binary). Polygons are split into triangle fans (v0, v[i],
// v[i+1]), which keeps their orientation. OBJ: only `v` and `f` lines matter
// (texture and normal indices of `f a/b/c` are dropped, negative indices count
// back from the last vertex read). OFF: colours after the coordinates or the
// face indices are ignored. PLY: the x, y, z properties of `vertex` and the
// vertex_indices (or vertex_index) list of `face`; other elements and
// properties are skipped.
#include "geometry/ascii_text.h"
#include "geometry/error.h"
#include "geometry/atomic_file.h"
#include "geometry/io/mesh_io.h"
#include "geometry/io/text_scanner.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>

namespace vox {

namespace {

// Appends the fan of `polygon` (vertex indices) to `triangles`; `in` names
// the line on error, where vertices are numbered from `firstIndex` as in the file.
// A number as written by to_chars: 0.5, 1e+30, not 0.500000.
std::string shortest(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

// A vertex that `polygon` lists twice, if any. Sorting a copy keeps the
// check O(n log n) for faces of any size (a cage face may list every vertex).
std::optional<std::int32_t> repeatedVertex(const std::vector<std::int32_t>& polygon, std::vector<std::int32_t>& scratch) {
  scratch.assign(polygon.begin(), polygon.end());
  std::sort(scratch.begin(), scratch.end());
  const auto twice = std::adjacent_find(scratch.begin(), scratch.end());
  if (twice == scratch.end()) return std::nullopt;
  return *twice;
}

void addFan(const std::vector<std::int32_t>& polygon, std::vector<Tri>& triangles, io::TextScanner& in, int firstIndex) {
  if (polygon.size() < 3) in.fail("face has " + std::to_string(polygon.size()) + " vertices (at least 3 needed)");
  std::vector<std::int32_t> scratch;
  if (const auto v = repeatedVertex(polygon, scratch)) in.fail("face repeats vertex " + std::to_string(*v + firstIndex));
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


enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

std::optional<PlyType> plyType(std::string_view name) {
  static constexpr std::pair<std::string_view, PlyType> kNames[] = {
      {"char", PlyType::Int8},    {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},     {"uint8", PlyType::UInt8},
      {"short", PlyType::Int16},  {"int16", PlyType::Int16},     {"ushort", PlyType::UInt16},   {"uint16", PlyType::UInt16},
      {"int", PlyType::Int32},    {"int32", PlyType::Int32},     {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64}, {"float64", PlyType::Float64}};
  for (const auto& [n, t] : kNames)
    if (n == name) return t;
  return std::nullopt;
}

std::size_t plySize(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8: return 1;
    case PlyType::Int16:
    case PlyType::UInt16: return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 1;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;  // item type for lists
  bool list = false;
  PlyType countType = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
  std::size_t headerLine = 0;
};

class PlyReader {
public:
  PlyReader(const std::string& path, std::string_view bytes) : path_(path), in_(bytes, path) {}

  TriMesh read() {
    readHeader();
    TriMesh mesh;
    const PlyElement* vertices = nullptr;
    for (const PlyElement& e : elements_) {
      if (e.name == "vertex") vertices = &e;
      // The smallest record: one byte (binary) or two (ASCII) per value.
      std::size_t minBytes = 0;
      for (const PlyProperty& p : e.properties) minBytes += binary_ ? plySize(p.list ? p.countType : p.type) : 2;
      if (minBytes > 0 && e.count > (in_.remainingBytes() + 1) / minBytes)
        headerFail(e, "element " + e.name + " count " + std::to_string(e.count) + " is more than the rest of the file can hold");
    }
    if (!vertices) throw InputError(path_, "no vertex element");
    for (const PlyElement& e : elements_) {
      if (e.name == "vertex") readVertices(e, mesh);
      else if (e.name == "face") readFaces(e, vertices->count, mesh);
      else skipElement(e);
    }
    if (mesh.triangles.empty()) throw InputError(path_, "no faces");
    mesh.validate(path_);
    return mesh;
  }

private:
  [[noreturn]] void fail(const std::string& fault) {
    if (binary_) throw InputError(path_, fault);
    in_.fail(fault);
  }
  [[noreturn]] void headerFail(const PlyElement& e, const std::string& fault) {
    throw InputError(path_, "line " + std::to_string(e.headerLine) + ": " + fault);
  }

  void readHeader() {
    const std::size_t firstLine = in_.line();
    const std::string_view magic = in_.restOfLine();
    if (magic != "ply") throw InputError(path_, "line " + std::to_string(firstLine) + ": not a PLY file: expected 'ply', found " + io::quoted(magic));
    bool haveFormat = false;
    for (;;) {
      if (in_.remainingBytes() == 0) throw InputError(path_, "no end_header line (truncated header?)");
      const std::size_t lineNo = in_.line();
      io::TextScanner line(in_.restOfLine(), path_, '\0', lineNo);
      const std::string_view keyword = line.word();
      if (keyword == "end_header") break;
      if (keyword == "format") {
        const std::string_view format = line.word();
        if (format == "ascii") binary_ = false;
        else if (format == "binary_little_endian" || format == "binary_big_endian") {
          binary_ = true;
          swap_ = (format == "binary_big_endian") != (std::endian::native == std::endian::big);
        } else line.fail("unknown PLY format " + io::quoted(format));
        if (line.word() != "1.0") line.fail("PLY format version is not 1.0");
        haveFormat = true;
      } else if (keyword == "element") {
        PlyElement e;
        e.name = std::string(line.word());
        const std::int64_t n = line.integer("element count");
        if (n < 0) line.fail("negative element count");
        e.count = std::size_t(n);
        e.headerLine = lineNo;
        elements_.push_back(std::move(e));
      } else if (keyword == "property") {
        if (elements_.empty()) line.fail("property before any element");
        PlyProperty p;
        std::string_view type = line.word();
        if (type == "list") {
          p.list = true;
          const std::optional<PlyType> count = plyType(line.word());
          if (!count || *count == PlyType::Float32 || *count == PlyType::Float64) line.fail("list count type must be an integer type");
          p.countType = *count;
          type = line.word();
        }
        const std::optional<PlyType> t = plyType(type);
        if (!t) line.fail("unknown property type " + io::quoted(type));
        p.type = *t;
        p.name = std::string(line.word());
        elements_.back().properties.push_back(std::move(p));
      } else if (keyword != "comment" && keyword != "obj_info" && !keyword.empty()) {
        line.fail("unknown header line starting with " + io::quoted(keyword));
      }
    }
    if (!haveFormat) throw InputError(path_, "PLY header has no format line");
  }

  // One value of type `t` (ASCII token or binary bytes) as a double; every
  // PLY type converts exactly.
  double value(PlyType t, std::string_view what) {
    if (!binary_) {
      const std::string_view w = in_.word();
      const char* first = w.data() + (w.size() > 1 && w[0] == '+' && w[1] != '-');
      double v = 0;
      const auto [end, ec] = std::from_chars(first, w.data() + w.size(), v);
      if (w.empty() || ec != std::errc() || end != w.data() + w.size())
        in_.fail("expected " + std::string(what) + ", found " + io::quoted(w));
      return v;
    }
    const std::size_t size = plySize(t);
    if (in_.remainingBytes() < size) fail("truncated (reading " + std::string(what) + ")");
    unsigned char b[8];
    std::memcpy(b, in_.text().data() + in_.position(), size);
    in_.seek(in_.position() + size);
    if (swap_) std::reverse(b, b + size);
    auto as = [&b](auto v) {
      std::memcpy(&v, b, sizeof(v));
      return double(v);
    };
    switch (t) {
      case PlyType::Int8: return as(std::int8_t());
      case PlyType::UInt8: return as(std::uint8_t());
      case PlyType::Int16: return as(std::int16_t());
      case PlyType::UInt16: return as(std::uint16_t());
      case PlyType::Int32: return as(std::int32_t());
      case PlyType::UInt32: return as(std::uint32_t());
      case PlyType::Float32: return as(float());
      case PlyType::Float64: return as(double());
    }
    return 0;
  }

  std::int64_t listLength(const PlyProperty& p) {
    const double n = value(p.countType, "list length");
    if (n < 0 || n != std::floor(n) || n > double(in_.remainingBytes()))
      fail("list " + p.name + " has length " + std::to_string(n) + " (truncated or corrupt file)");
    return std::int64_t(n);
  }

  void skipProperty(const PlyProperty& p) {
    const std::int64_t n = p.list ? listLength(p) : 1;
    for (std::int64_t i = 0; i < n; ++i) value(p.type, p.name);
  }

  void skipElement(const PlyElement& e) {
    // Records without properties take no bytes, however many the header
    // declares: nothing to skip (and no file length to bound the count by).
    if (e.properties.empty()) return;
    for (std::size_t r = 0; r < e.count; ++r)
      for (const PlyProperty& p : e.properties) skipProperty(p);
  }

  void readVertices(const PlyElement& e, TriMesh& mesh) {
    if (e.count > std::size_t(std::numeric_limits<std::int32_t>::max())) headerFail(e, "more than 2^31 - 1 vertices");
    int axis[3] = {-1, -1, -1};
    for (std::size_t i = 0; i < e.properties.size(); ++i)
      for (int c = 0; c < 3; ++c)
        if (!e.properties[i].list && e.properties[i].name == std::string_view("xyz" + c, 1)) axis[c] = int(i);
    if (axis[0] < 0 || axis[1] < 0 || axis[2] < 0) headerFail(e, "vertex element lacks an x, y or z property");
    mesh.positions.resize(e.count);
    for (std::size_t v = 0; v < e.count; ++v) {
      for (std::size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        const int c = int(std::find(axis, axis + 3, int(i)) - axis);
        if (c == 3) {
          skipProperty(p);
          continue;
        }
        const double x = value(p.type, "coordinate");
        if (!std::isfinite(x)) fail("vertex " + std::to_string(v) + " has a non-finite coordinate");
        mesh.positions[v][c] = x;
      }
    }
  }

  void readFaces(const PlyElement& e, std::size_t vertexCount, TriMesh& mesh) {
    std::ptrdiff_t indices = -1;
    for (std::size_t i = 0; i < e.properties.size(); ++i)
      if (e.properties[i].list && (e.properties[i].name == "vertex_indices" || e.properties[i].name == "vertex_index"))
        indices = std::ptrdiff_t(i);
    if (indices < 0) headerFail(e, "face element lacks a vertex_indices list");
    std::vector<std::int32_t> polygon, scratch;
    for (std::size_t f = 0; f < e.count; ++f) {
      for (std::size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        if (std::ptrdiff_t(i) != indices) {
          skipProperty(p);
          continue;
        }
        const std::int64_t n = listLength(p);
        polygon.clear();
        for (std::int64_t k = 0; k < n; ++k) {
          const double v = value(p.type, "vertex index");
          if (v != std::floor(v)) fail("face " + std::to_string(f) + " has vertex index " + shortest(v) + ", not an integer");
          if (v < 0 || v >= double(vertexCount))
            fail("face " + std::to_string(f) + " references vertex " + shortest(v) + " (the file has " +
                 std::to_string(vertexCount) + " vertices)");
          polygon.push_back(std::int32_t(v));
        }
        if (polygon.size() < 3) fail("face " + std::to_string(f) + " has " + std::to_string(polygon.size()) + " vertices (at least 3 needed)");
        if (const auto twice = repeatedVertex(polygon, scratch))
          fail("face " + std::to_string(f) + " repeats vertex " + std::to_string(*twice));
        for (std::size_t k = 1; k + 1 < polygon.size(); ++k) mesh.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
      }
    }
  }

  const std::string& path_;
  io::TextScanner in_;
  bool binary_ = false;
  bool swap_ = false;
  std::vector<PlyElement> elements_;
};

TriMesh readPly(const std::string& path) {
  const std::string bytes = io::readWholeFile(path);
  return PlyReader(path, bytes).read();
}

// Binary PLY in our byte order: double coordinates (exact), int32 indices.
void writePly(const std::string& path, const TriMesh& mesh) {
  AtomicFile file(path);
  {
    io::TextOutput out(file.openStdio());
    out << "ply\nformat " << (std::endian::native == std::endian::little ? "binary_little_endian" : "binary_big_endian")
        << " 1.0\nelement vertex " << mesh.vertexCount()
        << "\nproperty double x\nproperty double y\nproperty double z\nelement face " << mesh.faceCount()
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "positions are written as one packed array");
    out.write(mesh.positions.data(), mesh.positions.size() * sizeof(Eigen::Vector3d));
    for (const Tri& t : mesh.triangles) {
      out << char(3);
      out.write(t.data(), sizeof(Tri));
    }
  }
  file.commit();
}

}  // namespace

TriMesh readSurface(const std::string& path) {
  const std::string e = lowerExtension(path);
  if (e == ".obj") return readObj(path);
  if (e == ".off") return readOff(path);
  if (e == ".ply") return readPly(path);
  throw InputError(path, "unknown surface format (expected .obj, .off or .ply)");
}

void writeSurface(const std::string& path, const TriMesh& mesh) {
  const std::string e = lowerExtension(path);
  if (e != ".obj" && e != ".off" && e != ".ply") throw InputError(path, "unknown surface format (expected .obj, .off or .ply)");
  mesh.validate(path);
  if (e == ".obj") writeObj(path, mesh);
  else if (e == ".off") writeOff(path, mesh);
  else writePly(path, mesh);
}

}  // namespace vox
