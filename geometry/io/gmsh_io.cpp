// Gmsh MSH 4.1 (.msh), ASCII and binary: the format of Gmsh and of the FEM
// codes that read it. Nodes and elements come in blocks, one per geometric
// entity; an element's label is the first physical tag of its volume entity
// ($Entities), or the entity tag when the entity has none. Feature lines
// (MeshEdges) are 2-node lines on curve entities, one per reference, the
// reference as the curve's physical tag.
// Spec: https://gmsh.info/doc/texinfo/gmsh.html#MSH-file-format
//
// Vertex order on read is ascending node tag, tet order ascending element
// tag; our writer numbers nodes and tets in mesh order, so a round trip keeps
// both orders even though it groups the tets by label.
#include "geometry/error.h"
#include "geometry/atomic_file.h"
#include "geometry/io/mesh_io.h"
#include "geometry/io/text_scanner.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <unordered_map>

namespace vox {

namespace {

constexpr int kTet4 = 4;
constexpr int kLine2 = 1;

// Nodes per element for the Gmsh element types (GmshDefines.h); 0 when unknown.
int nodesPerElement(int type) {
  static constexpr int kFirst[] = {0,  2,  3,  4,  4,  8,  6, 5, 3, 6, 9,  10, 27, 18, 14, 1,
                                   8,  20, 15, 13, 9,  10, 12, 15, 15, 21, 4, 5, 6,  20, 35, 56};
  if (type >= 1 && type < int(std::size(kFirst))) return kFirst[type];
  switch (type) {
    case 36: return 16;
    case 37: return 25;
    case 38: return 36;
    case 42: return 28;
    case 43: return 36;
    case 44: return 45;
    case 45: return 55;
    case 46: return 66;
    case 47: return 49;
    case 48: return 64;
    case 49: return 81;
    case 50: return 100;
    case 51: return 121;
    case 62: return 7;
    case 63: return 8;
    case 64: return 9;
    case 65: return 10;
    case 66: return 11;
    case 71: return 84;
    case 72: return 120;
    case 73: return 165;
    case 74: return 220;
    case 75: return 286;
    case 90: return 40;
    case 91: return 75;
    case 92: return 64;
    case 93: return 125;
    case 94: return 216;
    case 95: return 343;
    case 96: return 512;
    case 97: return 729;
    case 98: return 1000;
    default: return 0;
  }
}

class GmshReader {
public:
  GmshReader(const std::string& path, std::string_view bytes) : path_(path), in_(bytes, path) {}
  TetMesh read();

private:
  struct TetRecord {
    std::uint64_t tag;
    std::array<std::uint64_t, 4> nodes;
    std::int32_t entity;
  };

  [[noreturn]] void fail(const std::string& fault) {
    if (binary_) throw InputError(path_, "$" + section_ + ": " + fault);
    in_.fail("$" + section_ + ": " + fault);
  }
  void need(std::size_t bytes, std::string_view what) {
    if (in_.remainingBytes() < bytes) fail("truncated (reading " + std::string(what) + ")");
  }
  template <class T>
  T binaryValue(std::string_view what) {
    need(sizeof(T), what);
    T v;
    std::memcpy(&v, in_.text().data() + in_.position(), sizeof(T));
    in_.seek(in_.position() + sizeof(T));
    if (swap_) {
      char b[sizeof(T)];
      std::memcpy(b, &v, sizeof(T));
      std::reverse(b, b + sizeof(T));
      std::memcpy(&v, b, sizeof(T));
    }
    return v;
  }
  std::int32_t readInt(std::string_view what) {
    if (binary_) return binaryValue<std::int32_t>(what);
    const std::int64_t v = in_.integer(what);
    if (v < std::numeric_limits<std::int32_t>::min() || v > std::numeric_limits<std::int32_t>::max())
      fail(std::string(what) + " " + std::to_string(v) + " is out of the 32-bit range");
    return std::int32_t(v);
  }
  std::uint64_t readSize(std::string_view what) {
    if (binary_) return sizeT_ == 8 ? binaryValue<std::uint64_t>(what) : binaryValue<std::uint32_t>(what);
    const std::int64_t v = in_.integer(what);
    if (v < 0) fail(std::string(what) + " " + std::to_string(v) + " is negative");
    return std::uint64_t(v);
  }
  double readReal(std::string_view what) {
    if (!binary_) return in_.real(what);
    const double v = binaryValue<double>(what);
    if (!std::isfinite(v)) fail(std::string(what) + " is not finite");
    return v;
  }
  // Skips values we do not use (bounding boxes, parametric coordinates,
  // bounding entities) without judging them.
  void skipValues(std::size_t count, std::size_t binarySize, std::string_view what) {
    if (binary_) {
      if (count > in_.remainingBytes() / binarySize) fail("truncated (reading " + std::string(what) + ")");
      in_.seek(in_.position() + count * binarySize);
      return;
    }
    for (std::size_t i = 0; i < count; ++i)
      if (in_.word().empty()) fail("truncated (reading " + std::string(what) + ")");
  }
  // A count whose items need at least the given bytes each in this encoding.
  std::size_t readCount(std::string_view what, std::size_t asciiBytes, std::size_t binaryBytes) {
    const std::uint64_t n = readSize(what);
    const std::size_t per = binary_ ? binaryBytes : asciiBytes;
    if (n > (in_.remainingBytes() + 1) / per)
      fail(std::string(what) + " " + std::to_string(n) + " is more than the rest of the file can hold (truncated or corrupt)");
    return std::size_t(n);
  }
  // The line after a section keyword or an ASCII header line.
  void endLine() { in_.skipLine(); }
  void expectEnd() {
    const std::string end = "$End" + section_;
    const std::string_view w = in_.word();
    if (w != end) fail("expected " + end + ", found " + io::quoted(w) + " (wrong counts or truncated file)");
  }

  void readMeshFormat();
  void readEntities();
  void readNodes();
  void readElements();
  void readPhysicalNames();
  void skipSection();
  TetMesh assemble();

  std::string path_;
  io::TextScanner in_;
  std::string section_ = "MeshFormat";
  bool binary_ = false;
  bool swap_ = false;
  std::size_t sizeT_ = 8;
  bool haveNodes_ = false, haveElements_ = false;
  std::unordered_map<std::int32_t, std::int32_t> volumePhysical_;  // volume entity tag -> first physical tag
  std::unordered_map<std::int32_t, std::int32_t> curvePhysical_;   // curve entity tag -> first physical tag
  struct LineRecord {
    std::uint64_t tag = 0;
    std::uint64_t nodes[2] = {0, 0};
    std::int32_t entity = 0;
  };
  std::vector<LineRecord> lines_;
  MeshEdges edges_;

public:
  // The 2-node lines on curves, after read(): the feature lines of our writer.
  const MeshEdges& edges() const { return edges_; }

private:
  std::map<std::int32_t, std::string> volumeNames_;                // physical tag -> name (dimension 3)
  std::vector<std::uint64_t> nodeTags_;
  std::vector<Eigen::Vector3d> nodes_;
  std::vector<TetRecord> tets_;
};

void GmshReader::readMeshFormat() {
  const std::string_view version = in_.word();
  if (version != "4.1") {
    if (version.starts_with("2.") || version.starts_with("4.0") || version.starts_with("3."))
      fail("MSH version " + std::string(version) + " is not supported; re-export as MSH 4.1 (gmsh -format msh41)");
    fail("unknown MSH version " + io::quoted(version));
  }
  const std::int64_t fileType = in_.integer("file type");
  const std::int64_t dataSize = in_.integer("data size");
  if (fileType != 0 && fileType != 1) fail("file type " + std::to_string(fileType) + " is not 0 (ASCII) or 1 (binary)");
  if (dataSize != 4 && dataSize != 8) fail("data size " + std::to_string(dataSize) + " is not 4 or 8");
  sizeT_ = std::size_t(dataSize);
  endLine();
  if (fileType == 1) {
    // The integer 1 written in the file's byte order.
    binary_ = true;
    const std::int32_t one = binaryValue<std::int32_t>("byte order mark");
    if (one != 1) {
      char b[4];
      std::memcpy(b, &one, 4);
      std::reverse(b, b + 4);
      std::int32_t swapped;
      std::memcpy(&swapped, b, 4);
      if (swapped != 1) fail("bad byte order mark after the header");
      swap_ = true;
    }
  }
  expectEnd();
}

void GmshReader::readEntities() {
  endLine();
  std::size_t counts[4];
  for (std::size_t& c : counts) c = readCount("entity count", 10, 4 + 24 + sizeT_);
  for (int dim = 0; dim < 4; ++dim) {
    for (std::size_t e = 0; e < counts[dim]; ++e) {
      const std::int32_t tag = readInt("entity tag");
      skipValues(dim == 0 ? 3 : 6, 8, "bounding box");
      const std::size_t physicals = readCount("physical tag count", 2, 4);
      for (std::size_t p = 0; p < physicals; ++p) {
        const std::int32_t physical = readInt("physical tag");
        if (dim == 3 && p == 0) volumePhysical_[tag] = physical;
        if (dim == 1 && p == 0) curvePhysical_[tag] = physical;
      }
      if (dim > 0) skipValues(readCount("bounding entity count", 2, 4), 4, "bounding entities");
    }
  }
  expectEnd();
}

void GmshReader::readNodes() {
  if (haveNodes_) fail("a second $Nodes section");
  haveNodes_ = true;
  endLine();
  const std::size_t blocks = readCount("entity block count", 8, 12 + sizeT_);
  const std::size_t total = readCount("node count", 8, sizeT_ + 24);
  readSize("minimum node tag");
  readSize("maximum node tag");
  nodeTags_.reserve(total);
  nodes_.reserve(total);
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::int32_t dim = readInt("entity dimension");
    readInt("entity tag");
    const std::int32_t parametric = readInt("parametric flag");
    if (dim < 0 || dim > 3) fail("node block " + std::to_string(b) + " has entity dimension " + std::to_string(dim));
    const std::size_t extra = parametric ? std::size_t(dim) : 0;
    const std::size_t n = readCount("block node count", 8, sizeT_ + 24);
    if (nodeTags_.size() + n > total) fail("the node blocks hold more than the " + std::to_string(total) + " nodes announced");
    for (std::size_t i = 0; i < n; ++i) nodeTags_.push_back(readSize("node tag"));
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Vector3d p;
      p.x() = readReal("x coordinate");
      p.y() = readReal("y coordinate");
      p.z() = readReal("z coordinate");
      if (extra) skipValues(extra, 8, "parametric coordinates");
      nodes_.push_back(p);
    }
  }
  if (nodes_.size() != total)
    fail("the node blocks hold " + std::to_string(nodes_.size()) + " nodes, " + std::to_string(total) + " announced");
  expectEnd();
}

void GmshReader::readElements() {
  if (haveElements_) fail("a second $Elements section");
  haveElements_ = true;
  endLine();
  const std::size_t blocks = readCount("entity block count", 8, 12 + sizeT_);
  const std::size_t total = readCount("element count", 4, 2 * sizeT_);
  readSize("minimum element tag");
  readSize("maximum element tag");
  std::size_t seen = 0;
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::int32_t dim = readInt("entity dimension");
    const std::int32_t entity = readInt("entity tag");
    const std::int32_t type = readInt("element type");
    const int npe = nodesPerElement(type);
    const std::size_t perElementBytes = (npe > 0 ? std::size_t(npe) + 1 : 2);
    const std::size_t n = readCount("block element count", 2 * perElementBytes, sizeT_ * perElementBytes);
    seen += n;
    if (seen > total) fail("the element blocks hold more than the " + std::to_string(total) + " elements announced");
    if (type == kTet4) {
      if (dim != 3) fail("element block " + std::to_string(b) + " has tetrahedra on an entity of dimension " + std::to_string(dim));
      // `n` was checked against the file size; grow geometrically across blocks.
      if (tets_.capacity() < tets_.size() + n) tets_.reserve(std::max(2 * tets_.capacity(), tets_.size() + n));
      for (std::size_t i = 0; i < n; ++i) {
        TetRecord r;
        r.tag = readSize("element tag");
        for (std::uint64_t& v : r.nodes) v = readSize("node tag");
        r.entity = entity;
        tets_.push_back(r);
      }
    } else if (type == kLine2 && dim == 1) {
      for (std::size_t i = 0; i < n; ++i) {
        LineRecord r;
        r.tag = readSize("element tag");
        for (std::uint64_t& v : r.nodes) v = readSize("node tag");
        r.entity = entity;
        lines_.push_back(r);
      }
    } else if (npe > 0) {
      skipValues(n * (std::size_t(npe) + 1), sizeT_, "elements");
    } else if (!binary_) {
      // An element type we do not know: in ASCII, one element per line.
      endLine();
      for (std::size_t i = 0; i < n; ++i) {
        if (in_.remainingBytes() == 0) fail("truncated (reading elements of type " + std::to_string(type) + ")");
        in_.skipLine();
      }
    } else {
      fail("element block " + std::to_string(b) + " has unknown element type " + std::to_string(type));
    }
  }
  if (seen != total) fail("the element blocks hold " + std::to_string(seen) + " elements, " + std::to_string(total) + " announced");
  expectEnd();
}

// "dim tag \"name\"" lines, ASCII in binary files too; names of volume
// physical groups become label names, except our writer's "label_<tag>".
void GmshReader::readPhysicalNames() {
  endLine();
  const std::size_t n = in_.count("physical name count", 8);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t dim = in_.integer("physical name dimension");
    const std::int64_t tag = in_.integer("physical tag");
    std::string_view rest = in_.restOfLine();
    const std::size_t open = rest.find('"'), close = rest.rfind('"');
    if (open == std::string_view::npos || close == open)
      fail("physical name of tag " + std::to_string(tag) + " is not in double quotes");
    const std::string name(rest.substr(open + 1, close - open - 1));
    if (dim == 3 && tag >= std::numeric_limits<std::int32_t>::min() && tag <= std::numeric_limits<std::int32_t>::max() &&
        !name.empty() && name != "label_" + std::to_string(tag))
      volumeNames_[std::int32_t(tag)] = name;
  }
  expectEnd();
}

void GmshReader::skipSection() {
  // Sections we do not use ($PartitionedEntities, $Periodic,
  // $NodeData, $Comments, ...) end at their $End line.
  const std::string end = "$End" + section_;
  const std::size_t at = in_.text().find(end, in_.position());
  if (at == std::string_view::npos) fail("section is not closed by " + end + " (truncated file?)");
  if (binary_) in_.seek(at + end.size());
  else in_.advanceTo(at + end.size());
}

TetMesh GmshReader::read() {
  const std::string_view magic = in_.word();
  if (magic != "$MeshFormat") in_.fail("not a Gmsh mesh: expected $MeshFormat, found " + io::quoted(magic));
  readMeshFormat();
  for (std::string_view w = in_.word(); !w.empty(); w = in_.word()) {
    if (w[0] != '$') {
      const std::string fault = "expected a $Section line after $" + section_ + ", found " + io::quoted(w);
      if (binary_) throw InputError(path_, fault);
      in_.fail(fault);
    }
    section_ = std::string(w.substr(1));
    if (section_ == "Entities") readEntities();
    else if (section_ == "Nodes") readNodes();
    else if (section_ == "Elements") readElements();
    else if (section_ == "PhysicalNames") readPhysicalNames();
    else if (section_ == "MeshFormat") fail("a second $MeshFormat section");
    else skipSection();
  }
  return assemble();
}

TetMesh GmshReader::assemble() {
  if (!haveNodes_) throw InputError(path_, "no $Nodes section");
  if (tets_.empty()) throw InputError(path_, "no tetrahedra (no elements of type 4)");
  const std::size_t n = nodes_.size();
  if (n > std::size_t(std::numeric_limits<std::int32_t>::max())) throw InputError(path_, "more than 2^31 - 1 nodes");
  if (tets_.size() > std::size_t(std::numeric_limits<std::int32_t>::max())) throw InputError(path_, "more than 2^31 - 1 tetrahedra");

  TetMesh mesh;
  mesh.positions.resize(n);
  // Node tag -> vertex index, vertices in ascending tag order. Tags are
  // usually 1..n; otherwise they are sorted and searched.
  const auto [minIt, maxIt] = std::minmax_element(nodeTags_.begin(), nodeTags_.end());
  const std::uint64_t minTag = n ? *minIt : 0, maxTag = n ? *maxIt : 0;
  const bool dense = n > 0 && maxTag - minTag == n - 1;
  std::vector<std::uint64_t> sortedTags;
  if (dense) {
    std::vector<std::int32_t> slot(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
      std::int32_t& s = slot[std::size_t(nodeTags_[i] - minTag)];
      if (s >= 0) throw InputError(path_, "$Nodes: node tag " + std::to_string(nodeTags_[i]) + " is repeated");
      s = std::int32_t(i);
      mesh.positions[std::size_t(nodeTags_[i] - minTag)] = nodes_[i];
    }
  } else {
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return nodeTags_[a] < nodeTags_[b]; });
    sortedTags.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      sortedTags[i] = nodeTags_[order[i]];
      if (i > 0 && sortedTags[i] == sortedTags[i - 1])
        throw InputError(path_, "$Nodes: node tag " + std::to_string(sortedTags[i]) + " is repeated");
      mesh.positions[i] = nodes_[order[i]];
    }
  }
  auto vertexOf = [&](std::uint64_t tag, std::uint64_t element) -> std::int32_t {
    if (dense) {
      if (tag >= minTag && tag <= maxTag) return std::int32_t(tag - minTag);
    } else {
      const auto it = std::lower_bound(sortedTags.begin(), sortedTags.end(), tag);
      if (it != sortedTags.end() && *it == tag) return std::int32_t(it - sortedTags.begin());
    }
    throw InputError(path_, "$Elements: element " + std::to_string(element) + " references node " + std::to_string(tag) +
                                ", which is not in $Nodes");
  };

  // Tets in ascending element tag order. Tags are usually a permutation of
  // a range (our writer's are), which places each tet directly.
  const std::size_t nt = tets_.size();
  std::vector<std::uint32_t> order(nt);
  const auto [minTet, maxTet] = std::minmax_element(tets_.begin(), tets_.end(), [](const TetRecord& a, const TetRecord& b) { return a.tag < b.tag; });
  const std::uint64_t firstTag = minTet->tag;
  if (maxTet->tag - firstTag == nt - 1) {
    std::vector<bool> placed(nt, false);
    for (std::size_t t = 0; t < nt; ++t) {
      const auto at = std::size_t(tets_[t].tag - firstTag);
      if (placed[at]) throw InputError(path_, "$Elements: element tag " + std::to_string(tets_[t].tag) + " is repeated");
      placed[at] = true;
      order[at] = std::uint32_t(t);
    }
  } else {
    std::iota(order.begin(), order.end(), std::uint32_t(0));
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return tets_[a].tag < tets_[b].tag; });
    for (std::size_t i = 1; i < nt; ++i)
      if (tets_[order[i]].tag == tets_[order[i - 1]].tag)
        throw InputError(path_, "$Elements: element tag " + std::to_string(tets_[order[i]].tag) + " is repeated");
  }
  mesh.tets.resize(nt);
  mesh.labels.resize(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const TetRecord& r = tets_[order[t]];
    for (int k = 0; k < 4; ++k) {
      mesh.tets[t][k] = vertexOf(r.nodes[k], r.tag);
      for (int m = 0; m < k; ++m)
        if (mesh.tets[t][m] == mesh.tets[t][k])
          throw InputError(path_, "$Elements: element " + std::to_string(r.tag) + " repeats node " + std::to_string(r.nodes[k]));
    }
    const auto physical = volumePhysical_.find(r.entity);
    mesh.labels[t] = physical != volumePhysical_.end() ? physical->second : r.entity;
  }
  setLabelNames(mesh, volumeNames_);
  mesh.validate(path_);
  for (const LineRecord& r : lines_) {
    const std::int32_t a = vertexOf(r.nodes[0], r.tag), b = vertexOf(r.nodes[1], r.tag);
    const auto physical = curvePhysical_.find(r.entity);
    edges_.edges.push_back({a, b});
    edges_.refs.push_back(physical != curvePhysical_.end() ? physical->second : r.entity);
  }
  return mesh;
}

}  // namespace

TetMesh readGmsh(const std::string& path) {
  const std::string bytes = io::readWholeFile(path);
  return GmshReader(path, bytes).read();
}

MeshEdges readGmshEdges(const std::string& path) {
  const std::string bytes = io::readWholeFile(path);
  GmshReader reader(path, bytes);
  reader.read();
  return reader.edges();
}

void writeGmsh(const std::string& path, const TetMesh& mesh) { writeGmsh(path, mesh, MeshEdges{}); }

void writeGmsh(const std::string& path, const TetMesh& mesh, const MeshEdges& edges) {
  mesh.validate(path);
  checkMeshEdges(path, mesh, edges);
  // Feature lines: one curve entity per reference (tags 1..c in ascending
  // reference order), carrying the reference as its physical tag.
  std::vector<std::int32_t> refs(edges.refs);
  std::sort(refs.begin(), refs.end());
  refs.erase(std::unique(refs.begin(), refs.end()), refs.end());
  const std::size_t c = refs.size();
  std::vector<std::vector<std::size_t>> curveEdges(c);
  for (std::size_t i = 0; i < edges.edges.size(); ++i)
    curveEdges[std::size_t(std::lower_bound(refs.begin(), refs.end(), edges.refs[i]) - refs.begin())].push_back(i);
  // One volume entity per label (tags 1..k in ascending label order), each
  // carrying the label as its physical tag, named by mesh.labelNames or
  // "label_<n>".
  std::vector<std::int32_t> labels(mesh.labels);
  std::sort(labels.begin(), labels.end());
  labels.erase(std::unique(labels.begin(), labels.end()), labels.end());
  const std::size_t k = labels.size();
  std::vector<std::uint32_t> entityOf(mesh.tetCount());
  std::vector<std::size_t> perEntity(k, 0);
  std::vector<Eigen::Vector3d> lo(k, Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()));
  std::vector<Eigen::Vector3d> hi(k, Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity()));
  for (std::size_t t = 0; t < mesh.tetCount(); ++t) {
    const auto e = std::size_t(std::lower_bound(labels.begin(), labels.end(), mesh.labels[t]) - labels.begin());
    entityOf[t] = std::uint32_t(e);
    ++perEntity[e];
    for (std::int32_t v : mesh.tets[t]) {
      lo[e] = lo[e].cwiseMin(mesh.positions[std::size_t(v)]);
      hi[e] = hi[e].cwiseMax(mesh.positions[std::size_t(v)]);
    }
  }
  // Tets grouped by entity, mesh order within each group (counting sort).
  std::vector<std::size_t> start(k + 1, 0);
  for (std::size_t e = 0; e < k; ++e) start[e + 1] = start[e] + perEntity[e];
  std::vector<std::uint32_t> grouped(mesh.tetCount());
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t t = 0; t < mesh.tetCount(); ++t) grouped[fill[entityOf[t]]++] = std::uint32_t(t);
  }

  const std::size_t nv = mesh.vertexCount(), nt = mesh.tetCount();
  AtomicFile file(path);
  {
    io::TextOutput out(file.openStdio());
    out << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n" << k + c << '\n';
    for (std::int32_t l : labels) {
      const auto named = mesh.labelNames.find(l);
      std::string name = named != mesh.labelNames.end() ? named->second : "label_" + std::to_string(l);
      // A name is one quoted string on one line.
      std::replace_if(name.begin(), name.end(), [](char c) { return c == '"' || c == '\n' || c == '\r'; }, '\'');
      out << "3 " << l << " \"" << name << "\"\n";
    }
    for (std::int32_t r : refs) out << "1 " << r << " \"feature_" << r << "\"\n";
    out << "$EndPhysicalNames\n$Entities\n0 " << c << " 0 " << k << '\n';
    for (std::size_t e = 0; e < c; ++e) {
      Eigen::Vector3d clo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), chi = -clo;
      for (std::size_t i : curveEdges[e])
        for (std::int32_t v : edges.edges[i]) {
          clo = clo.cwiseMin(mesh.positions[std::size_t(v)]);
          chi = chi.cwiseMax(mesh.positions[std::size_t(v)]);
        }
      out << std::int64_t(e + 1);
      for (int d = 0; d < 3; ++d) out << ' ' << clo[d];
      for (int d = 0; d < 3; ++d) out << ' ' << chi[d];
      out << " 1 " << refs[e] << " 0\n";
    }
    for (std::size_t e = 0; e < k; ++e) {
      out << std::int64_t(e + 1);
      for (int c = 0; c < 3; ++c) out << ' ' << lo[e][c];
      for (int c = 0; c < 3; ++c) out << ' ' << hi[e][c];
      out << " 1 " << labels[e] << " 0\n";
    }
    // All nodes in one block on the first volume: Gmsh classifies a node on
    // one entity, and a node shared by several labels has no better home.
    out << "$EndEntities\n$Nodes\n" << std::size_t(nv ? 1 : 0) << ' ' << nv << " 1 " << nv << '\n';
    if (nv) {
      out << "3 1 0 " << nv << '\n';
      for (std::size_t v = 1; v <= nv; ++v) out << v << '\n';
      for (const Eigen::Vector3d& p : mesh.positions) out << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    }
    const std::size_t ne = nt + edges.edges.size();
    out << "$EndNodes\n$Elements\n" << k + c << ' ' << ne << " 1 " << ne << '\n';
    for (std::size_t e = 0; e < k; ++e) {
      out << "3 " << std::int64_t(e + 1) << " 4 " << perEntity[e] << '\n';
      for (std::size_t i = start[e]; i < start[e + 1]; ++i) {
        const std::uint32_t t = grouped[i];
        const Tet& q = mesh.tets[t];
        out << std::int64_t(t) + 1 << ' ' << q[0] + 1 << ' ' << q[1] + 1 << ' ' << q[2] + 1 << ' ' << q[3] + 1 << '\n';
      }
    }
    // Lines after the tets, numbered on from them in edge order.
    for (std::size_t e = 0; e < c; ++e) {
      out << "1 " << std::int64_t(e + 1) << " 1 " << curveEdges[e].size() << '\n';
      for (std::size_t i : curveEdges[e])
        out << std::int64_t(nt + i) + 1 << ' ' << edges.edges[i][0] + 1 << ' ' << edges.edges[i][1] + 1 << '\n';
    }
    out << "$EndElements\n";
  }
  file.commit();
}

}  // namespace vox
