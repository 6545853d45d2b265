// Medit / Gamma Mesh Format: ASCII .mesh and binary .meshb, the tet mesh
// format of MMG, CGAL, TetGen and Gmsh. Keywords are followed by a count and
// that many records; indices are 1-based; the last integer of a record is its
// reference, which for tetrahedra is our label and for Edges (feature
// lines, MeshEdges) the line's reference.
// Spec: libMeshb (github.com/LoicMarechal/libMeshb).
#include "geometry/ascii_text.h"
#include "geometry/error.h"
#include "geometry/atomic_file.h"
#include "geometry/io/mesh_io.h"
#include "geometry/io/text_scanner.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <limits>

namespace vox {

namespace {

bool isKeyword(std::string_view w) { return !w.empty() && std::isalpha(static_cast<unsigned char>(w[0])); }

// Skips the records of a block we do not use (Triangles, Edges, Corners,
// Normals, ...): every record is numeric, so the block ends at the next word
// that starts with a letter. This also covers keywords we do not know.
void skipBlock(io::TextScanner& in) {
  for (std::string_view w = in.peekWord(); !w.empty() && !isKeyword(w); w = in.peekWord()) in.word();
}

std::int32_t toLabel(io::TextScanner& in, std::int64_t ref) {
  if (ref < std::numeric_limits<std::int32_t>::min() || ref > std::numeric_limits<std::int32_t>::max())
    in.fail("tetrahedron reference " + std::to_string(ref) + " does not fit a 32-bit label");
  return std::int32_t(ref);
}

bool isBinaryPath(const std::string& path) { return endsWithIgnoringCase(path, ".meshb"); }

// GMF binary keyword codes (libmeshb7.h).
constexpr std::int32_t kGmfDimension = 3, kGmfVertices = 4, kGmfEdges = 5, kGmfTetrahedra = 8, kGmfEnd = 54;

// Binary GMF: int32 magic 1 (byte order), int32 version, then keywords: int32
// code, position of the next keyword, and for blocks a count and records.
// Version 1: float32 reals; 2: float64; 3: 64-bit positions; 4: 64-bit ints.
class GmfReader {
public:
  GmfReader(const std::string& path, std::string_view bytes) : path_(path), bytes_(bytes) {}

  TetMesh read() {
    const std::int32_t magic = value<std::int32_t>("magic");
    if (magic != 1) {
      swap_ = true;
      if (swapped(magic) != 1) fail("not a binary Medit mesh (bad magic number)");
    }
    version_ = value<std::int32_t>("version");
    if (version_ < 1 || version_ > 4) fail("version " + std::to_string(version_) + " is not 1, 2, 3 or 4");
    TetMesh mesh;
    bool haveDimension = false, haveVertices = false, haveTetrahedra = false;
    while (pos_ < bytes_.size()) {
      const std::size_t keywordAt = pos_;
      const std::int32_t keyword = value<std::int32_t>("keyword");
      if (keyword == kGmfEnd) break;
      const std::uint64_t next = version_ >= 3 ? std::uint64_t(value<std::int64_t>("keyword position"))
                                               : std::uint64_t(std::uint32_t(value<std::int32_t>("keyword position")));
      if (keyword == kGmfDimension) {
        const std::int32_t d = value<std::int32_t>("dimension");
        if (d != 3) fail("dimension " + std::to_string(d) + " is not supported (tetrahedral meshes need 3)");
        haveDimension = true;
      } else if (keyword == kGmfVertices) {
        if (!haveDimension) fail("Vertices before Dimension");
        if (haveVertices) fail("a second Vertices block");
        haveVertices = true;
        const std::size_t n = count("vertex count", 3 * realSize() + intSize());
        mesh.positions.resize(n);
        for (std::size_t v = 0; v < n; ++v) {
          Eigen::Vector3d& p = mesh.positions[v];
          for (int c = 0; c < 3; ++c) p[c] = version_ == 1 ? double(value<float>("coordinate")) : value<double>("coordinate");
          if (!p.allFinite()) fail("vertex " + std::to_string(v + 1) + " has a non-finite coordinate");
          integer("vertex reference");
        }
      } else if (keyword == kGmfTetrahedra) {
        if (haveTetrahedra) fail("a second Tetrahedra block");
        haveTetrahedra = true;
        const std::size_t n = count("tetrahedron count", 5 * intSize());
        mesh.tets.resize(n);
        mesh.labels.resize(n);
        for (std::size_t t = 0; t < n; ++t) {
          for (int k = 0; k < 4; ++k) {
            const std::int64_t v = integer("vertex index");
            if (v < 1 || v > std::numeric_limits<std::int32_t>::max())
              fail("tetrahedron " + std::to_string(t + 1) + " references vertex " + std::to_string(v) + " (indices are 1-based)");
            mesh.tets[t][k] = std::int32_t(v - 1);
          }
          const std::int64_t ref = integer("tetrahedron reference");
          if (ref < std::numeric_limits<std::int32_t>::min() || ref > std::numeric_limits<std::int32_t>::max())
            fail("tetrahedron " + std::to_string(t + 1) + " has reference " + std::to_string(ref) + ", which does not fit a 32-bit label");
          mesh.labels[t] = std::int32_t(ref);
        }
      } else {
        // Blocks we do not use: jump to the next keyword.
        if (next <= keywordAt || next > bytes_.size())
          fail("keyword " + std::to_string(keyword) + " at byte " + std::to_string(keywordAt) + " points to byte " +
               std::to_string(next) + " for the next keyword");
        pos_ = std::size_t(next);
      }
    }
    if (!haveVertices) fail("no Vertices block");
    if (mesh.tets.empty()) fail("no tetrahedra (the Tetrahedra block is missing or empty)");
    mesh.validate(path_);
    return mesh;
  }

private:
  [[noreturn]] void fail(const std::string& fault) const { throw InputError(path_, fault); }
  std::size_t intSize() const { return version_ == 4 ? 8 : 4; }
  std::size_t realSize() const { return version_ == 1 ? 4 : 8; }
  template <class T>
  T swapped(T v) const {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    std::reverse(b, b + sizeof(T));
    std::memcpy(&v, b, sizeof(T));
    return v;
  }
  template <class T>
  T value(std::string_view what) {
    if (bytes_.size() - pos_ < sizeof(T)) fail("truncated at byte " + std::to_string(pos_) + " (reading " + std::string(what) + ")");
    T v;
    std::memcpy(&v, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return swap_ ? swapped(v) : v;
  }
  std::int64_t integer(std::string_view what) {
    return version_ == 4 ? value<std::int64_t>(what) : std::int64_t(value<std::int32_t>(what));
  }
  std::size_t count(std::string_view what, std::size_t recordBytes) {
    const std::int64_t n = integer(what);
    if (n < 0 || std::uint64_t(n) > (bytes_.size() - pos_) / recordBytes)
      fail(std::string(what) + " " + std::to_string(n) + " at byte " + std::to_string(pos_) +
           " is more than the rest of the file can hold (truncated or corrupt file)");
    return std::size_t(n);
  }

  const std::string& path_;
  std::string_view bytes_;
  std::size_t pos_ = 0;
  bool swap_ = false;
  std::int32_t version_ = 0;
};

// Binary GMF version 3: float64 coordinates, int32 indices, int64 positions.
void writeMeditBinary(const std::string& path, const TetMesh& mesh, const MeshEdges& edges) {
  AtomicFile file(path);
  {
    io::TextOutput out(file.openStdio());
    auto put = [&out](const auto& v) { out.write(&v, sizeof(v)); };
    const auto nv = std::int32_t(mesh.vertexCount()), nt = std::int32_t(mesh.tetCount());
    std::int64_t at = 8;  // magic and version
    put(std::int32_t(1));
    put(std::int32_t(3));
    at += 4 + 8 + 4;
    put(kGmfDimension), put(at), put(std::int32_t(3));
    at += 4 + 8 + 4 + std::int64_t(nv) * (3 * 8 + 4);
    put(kGmfVertices), put(at), put(nv);
    for (const Eigen::Vector3d& p : mesh.positions) put(p.x()), put(p.y()), put(p.z()), put(std::int32_t(0));
    at += 4 + 8 + 4 + std::int64_t(nt) * 5 * 4;
    put(kGmfTetrahedra), put(at), put(nt);
    for (std::size_t t = 0; t < mesh.tetCount(); ++t) {
      for (std::int32_t v : mesh.tets[t]) put(std::int32_t(v + 1));
      put(mesh.labels[t]);
    }
    if (!edges.empty()) {
      const auto ne = std::int32_t(edges.edges.size());
      at += 4 + 8 + 4 + std::int64_t(ne) * 3 * 4;
      put(kGmfEdges), put(at), put(ne);
      for (std::size_t e = 0; e < edges.edges.size(); ++e)
        put(std::int32_t(edges.edges[e][0] + 1)), put(std::int32_t(edges.edges[e][1] + 1)), put(edges.refs[e]);
    }
    put(kGmfEnd), put(std::int64_t(0));
  }
  file.commit();
}

// The mesh of an ASCII .mesh, and its Edges when `edges` is given (the
// tetrahedra are then optional).
TetMesh parseMeditText(const std::string& path, const std::string& bytes, MeshEdges* edges) {
  io::TextScanner in(bytes, path, '#');

  const std::string_view magic = in.word();
  if (magic != "MeshVersionFormatted")
    in.fail("not a Medit mesh: expected MeshVersionFormatted, found " + io::quoted(magic));
  const std::int64_t version = in.integer("MeshVersionFormatted version");
  if (version < 1 || version > 4) in.fail("MeshVersionFormatted " + std::to_string(version) + " is not 1, 2, 3 or 4");

  TetMesh mesh;
  bool haveDimension = false, haveVertices = false, haveTetrahedra = false;
  for (;;) {
    const std::string_view keyword = in.word();
    if (keyword.empty() || keyword == "End") break;
    if (keyword == "Dimension") {
      const std::int64_t d = in.integer("dimension");
      if (d != 3) in.fail("Dimension " + std::to_string(d) + " is not supported (tetrahedral meshes need 3)");
      haveDimension = true;
    } else if (keyword == "Vertices") {
      if (!haveDimension) in.fail("Vertices before Dimension");
      if (haveVertices) in.fail("a second Vertices block");
      haveVertices = true;
      // A record is at least 4 one-character tokens and their separators.
      const std::size_t n = in.count("vertex count", 8);
      mesh.positions.resize(n);
      for (Eigen::Vector3d& p : mesh.positions) {
        p.x() = in.real("x coordinate");
        p.y() = in.real("y coordinate");
        p.z() = in.real("z coordinate");
        in.integer("vertex reference");
      }
    } else if (keyword == "Tetrahedra") {
      if (haveTetrahedra) in.fail("a second Tetrahedra block");
      haveTetrahedra = true;
      const std::size_t n = in.count("tetrahedron count", 10);
      mesh.tets.resize(n);
      mesh.labels.resize(n);
      // Indices are checked here when the vertices came first (the usual
      // order), so the error names the line; TetMesh::validate catches the rest.
      const auto nv = std::int64_t(mesh.positions.size());
      for (std::size_t t = 0; t < n; ++t) {
        Tet& q = mesh.tets[t];
        for (int k = 0; k < 4; ++k) {
          const std::int64_t v = in.integer("vertex index");
          if (haveVertices && (v < 1 || v > nv))
            in.fail("tetrahedron " + std::to_string(t + 1) + " references vertex " + std::to_string(v) +
                    " (indices are 1-based; the file has " + std::to_string(nv) + " vertices)");
          if (v < 1 || v > std::numeric_limits<std::int32_t>::max())
            in.fail("tetrahedron " + std::to_string(t + 1) + " references vertex " + std::to_string(v));
          q[k] = std::int32_t(v - 1);
          for (int m = 0; m < k; ++m)
            if (q[m] == q[k]) in.fail("tetrahedron " + std::to_string(t + 1) + " repeats vertex " + std::to_string(v));
        }
        mesh.labels[t] = toLabel(in, in.integer("tetrahedron reference"));
      }
    } else if (keyword == "Edges" && edges) {
      if (!edges->edges.empty()) in.fail("a second Edges block");
      const std::size_t n = in.count("edge count", 6);
      const auto nv = std::int64_t(mesh.positions.size());
      for (std::size_t e = 0; e < n; ++e) {
        std::array<std::int32_t, 2> ends{};
        for (int k = 0; k < 2; ++k) {
          const std::int64_t v = in.integer("vertex index");
          if (!haveVertices || v < 1 || v > nv)
            in.fail("edge " + std::to_string(e + 1) + " references vertex " + std::to_string(v) + " (indices are 1-based; " +
                    (haveVertices ? "the file has " + std::to_string(nv) + " vertices)" : "no Vertices before Edges)"));
          ends[std::size_t(k)] = std::int32_t(v - 1);
        }
        if (ends[0] == ends[1]) in.fail("edge " + std::to_string(e + 1) + " joins vertex " + std::to_string(ends[0] + 1) + " to itself");
        edges->edges.push_back(ends);
        edges->refs.push_back(toLabel(in, in.integer("edge reference")));
      }
    } else if (keyword == "Identifier" || keyword == "Geometry") {
      in.skipLine();  // a free-form string
    } else if (isKeyword(keyword)) {
      skipBlock(in);
    } else {
      in.fail("expected a keyword, found " + io::quoted(keyword));
    }
  }
  if (!haveVertices) throw InputError(path, "no Vertices block");
  return mesh;
}

TetMesh readMeditText(const std::string& path, const std::string& bytes) {
  TetMesh mesh = parseMeditText(path, bytes, nullptr);
  if (mesh.tets.empty()) throw InputError(path, "no tetrahedra (the Tetrahedra block is missing or empty)");
  mesh.validate(path);
  return mesh;
}

void writeMeditText(const std::string& path, const TetMesh& mesh, const MeshEdges& edges) {
  AtomicFile file(path);
  {
    io::TextOutput out(file.openStdio());
    out << "MeshVersionFormatted 2\nDimension 3\n\nVertices\n" << mesh.vertexCount() << '\n';
    for (const Eigen::Vector3d& p : mesh.positions) out << p.x() << ' ' << p.y() << ' ' << p.z() << " 0\n";
    out << "\nTetrahedra\n" << mesh.tetCount() << '\n';
    for (std::size_t t = 0; t < mesh.tetCount(); ++t) {
      const Tet& q = mesh.tets[t];
      out << q[0] + 1 << ' ' << q[1] + 1 << ' ' << q[2] + 1 << ' ' << q[3] + 1 << ' ' << mesh.labels[t] << '\n';
    }
    if (!edges.empty()) {
      out << "\nEdges\n" << edges.edges.size() << '\n';
      for (std::size_t e = 0; e < edges.edges.size(); ++e)
        out << edges.edges[e][0] + 1 << ' ' << edges.edges[e][1] + 1 << ' ' << edges.refs[e] << '\n';
    }
    out << "\nEnd\n";
  }
  file.commit();
}

}  // namespace

TetMesh readMedit(const std::string& path) {
  const std::string bytes = io::readWholeFile(path);
  return isBinaryPath(path) ? GmfReader(path, bytes).read() : readMeditText(path, bytes);
}

void writeMedit(const std::string& path, const TetMesh& mesh) { writeMedit(path, mesh, MeshEdges{}); }

void writeMedit(const std::string& path, const TetMesh& mesh, const MeshEdges& edges) {
  mesh.validate(path);
  checkMeshEdges(path, mesh, edges);
  if (isBinaryPath(path)) writeMeditBinary(path, mesh, edges);
  else writeMeditText(path, mesh, edges);
}

MeshEdges readMeditEdges(const std::string& path, std::vector<Eigen::Vector3d>* positions) {
  if (isBinaryPath(path)) throw InputError(path, "Edges are read from ASCII .mesh files only");
  MeshEdges edges;
  TetMesh mesh = parseMeditText(path, io::readWholeFile(path), &edges);
  for (const Eigen::Vector3d& p : mesh.positions)
    if (!p.allFinite()) throw InputError(path, "a vertex has a coordinate that is not finite");
  if (positions) *positions = std::move(mesh.positions);
  return edges;
}

}  // namespace vox
