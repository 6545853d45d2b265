// Medit / Gamma Mesh Format, ASCII (.mesh): the tet mesh format of MMG, CGAL,
// TetGen and Gmsh. Keywords are followed by a count and that many records;
// indices are 1-based; the last integer of a record is its reference, which
// for tetrahedra is our label. Spec: libMeshb (github.com/LoicMarechal/libMeshb).
#include "geometry/error.h"
#include "geometry/io/atomic_file.h"
#include "geometry/io/mesh_io.h"
#include "geometry/io/text_scanner.h"

#include <cctype>
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

}  // namespace

TetMesh readMedit(const std::string& path) {
  const std::string bytes = io::readWholeFile(path);
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
    } else if (keyword == "Identifier" || keyword == "Geometry") {
      in.skipLine();  // a free-form string
    } else if (isKeyword(keyword)) {
      skipBlock(in);
    } else {
      in.fail("expected a keyword, found " + io::quoted(keyword));
    }
  }
  if (!haveVertices) throw InputError(path, "no Vertices block");
  if (mesh.tets.empty()) throw InputError(path, "no tetrahedra (the Tetrahedra block is missing or empty)");
  mesh.validate(path);
  return mesh;
}

void writeMedit(const std::string& path, const TetMesh& mesh) {
  mesh.validate(path);
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
    out << "\nEnd\n";
  }
  file.commit();
}

}  // namespace vox
