// VTK XML UnstructuredGrid (.vtu), the ParaView format.
//
// Read: ascii, binary (base64, optionally zlib-compressed) and appended (raw
// or base64) data arrays, UInt32 or UInt64 block headers, either byte order,
// several pieces. Only VTK_TETRA cells become tets. Labels come from the cell
// data array "label", else "medit:ref", else "gmsh:physical", else the first
// single-component integer array, else 1.
// Write: appended raw data (what ParaView writes), UInt64 headers, Float64
// points, Int32 connectivity, Int64 offsets, UInt8 types, Int32 "label".
//
// Format: https://vtk.org/wp-content/uploads/2015/04/file-formats.pdf and
// vtkXMLDataParser (binary block layout, compressed block headers).
#include "geometry/error.h"
#include "geometry/atomic_file.h"
#include "geometry/io/mesh_io.h"
#include "geometry/io/text_scanner.h"

#include <tinyxml2.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>

namespace vox {

namespace {

constexpr std::int64_t kVtkTetra = 10;

enum class Scalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64 };

std::optional<Scalar> scalarFromName(std::string_view name) {
  static constexpr std::pair<std::string_view, Scalar> kNames[] = {
      {"Int8", Scalar::Int8},       {"UInt8", Scalar::UInt8},     {"Int16", Scalar::Int16},
      {"UInt16", Scalar::UInt16},   {"Int32", Scalar::Int32},     {"UInt32", Scalar::UInt32},
      {"Int64", Scalar::Int64},     {"UInt64", Scalar::UInt64},   {"Float32", Scalar::Float32},
      {"Float64", Scalar::Float64},
      // Legacy names some writers still use.
      {"Char", Scalar::Int8},       {"UChar", Scalar::UInt8},     {"Short", Scalar::Int16},
      {"UShort", Scalar::UInt16},   {"Int", Scalar::Int32},       {"UInt", Scalar::UInt32},
      {"Float", Scalar::Float32},   {"Double", Scalar::Float64}};
  for (const auto& [n, s] : kNames)
    if (n == name) return s;
  return std::nullopt;
}

std::size_t scalarSize(Scalar s) {
  switch (s) {
    case Scalar::Int8:
    case Scalar::UInt8: return 1;
    case Scalar::Int16:
    case Scalar::UInt16: return 2;
    case Scalar::Int32:
    case Scalar::UInt32:
    case Scalar::Float32: return 4;
    case Scalar::Int64:
    case Scalar::UInt64:
    case Scalar::Float64: return 8;
  }
  return 1;
}

bool isInteger(Scalar s) { return s != Scalar::Float32 && s != Scalar::Float64; }

template <class T>
T swapBytes(T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  std::reverse(b, b + sizeof(T));
  std::memcpy(&v, b, sizeof(T));
  return v;
}

// Base64 digit values; kSpace for whitespace, kPad for '=', kBad otherwise.
constexpr int kSpace = -2, kPad = -3, kBad = -1;
constexpr std::array<int, 256> makeBase64Table() {
  std::array<int, 256> t{};
  for (int& v : t) v = kBad;
  const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (int i = 0; i < 64; ++i) t[std::uint8_t(alphabet[i])] = i;
  for (char c : {' ', '\n', '\r', '\t', '\f', '\v'}) t[std::uint8_t(c)] = kSpace;
  t[std::uint8_t('=')] = kPad;
  return t;
}
constexpr std::array<int, 256> kTable = makeBase64Table();

// Base64 text to bytes. Whitespace is skipped, and decoding continues after
// '=' padding: VTK encodes a binary block's header and its data as separate
// base64 streams, one after the other.
class Base64Reader {
public:
  explicit Base64Reader(std::string_view text) : text_(text) {}

  // Decodes exactly `n` bytes into `out`; false when the text ends first or
  // holds a character outside the base64 alphabet.
  bool read(char* out, std::size_t n) {
    while (n > 0) {
      if (pendingAt_ < pendingSize_) {
        *out++ = pending_[pendingAt_++];
        --n;
        continue;
      }
      // Fast path: whole quanta without whitespace or padding.
      while (n >= 3 && pos_ + 4 <= text_.size()) {
        const int a = kTable[std::uint8_t(text_[pos_])], b = kTable[std::uint8_t(text_[pos_ + 1])];
        const int c = kTable[std::uint8_t(text_[pos_ + 2])], d = kTable[std::uint8_t(text_[pos_ + 3])];
        if ((a | b | c | d) < 0) break;
        const std::uint32_t v = std::uint32_t(a) << 18 | std::uint32_t(b) << 12 | std::uint32_t(c) << 6 | std::uint32_t(d);
        out[0] = char(v >> 16);
        out[1] = char(v >> 8);
        out[2] = char(v);
        out += 3;
        n -= 3;
        pos_ += 4;
      }
      if (n > 0 && !decodeQuantum()) return false;
    }
    return true;
  }
  // An upper bound on the bytes left, to check sizes before allocating.
  std::size_t maxRemaining() const { return (text_.size() - pos_) / 4 * 3 + (pendingSize_ - pendingAt_); }

private:

  bool decodeQuantum() {
    int v[4];
    int k = 0, pads = 0;
    while (k < 4) {
      if (pos_ >= text_.size()) return false;
      const int x = kTable[std::uint8_t(text_[pos_++])];
      if (x == kSpace) continue;
      if (x == kBad) return false;
      if (x == kPad) {
        if (k < 2) return false;
        ++pads;
        v[k++] = 0;
      } else {
        if (pads > 0) return false;
        v[k++] = x;
      }
    }
    const std::uint32_t bits = std::uint32_t(v[0]) << 18 | std::uint32_t(v[1]) << 12 | std::uint32_t(v[2]) << 6 | std::uint32_t(v[3]);
    pending_[0] = char(bits >> 16);
    pending_[1] = char(bits >> 8);
    pending_[2] = char(bits);
    pendingSize_ = std::size_t(3 - pads);
    pendingAt_ = 0;
    return true;
  }

  std::string_view text_;
  std::size_t pos_ = 0;
  char pending_[3] = {};
  std::size_t pendingSize_ = 0, pendingAt_ = 0;
};

// Bytes of a binary data array: raw appended bytes or base64 text.
class EncodedBytes {
public:
  EncodedBytes(std::string_view data, bool base64) : data_(data), base64_(base64), decoder_(data) {}
  bool read(char* out, std::size_t n) {
    if (base64_) return decoder_.read(out, n);
    if (n > data_.size() - pos_) return false;
    std::memcpy(out, data_.data() + pos_, n);
    pos_ += n;
    return true;
  }
  std::size_t maxRemaining() const { return base64_ ? decoder_.maxRemaining() : data_.size() - pos_; }

private:
  std::string_view data_;
  bool base64_;
  Base64Reader decoder_;
  std::size_t pos_ = 0;
};

// Inflates one zlib block of `compressedSize` bytes that must expand to
// exactly `expectedSize` bytes, appending to `out`. The output grows only as
// data really comes out of the stream, so a lying header cannot make us
// allocate more than the file's content expands to.
bool inflateBlock(const std::string& compressed, std::size_t expectedSize, std::string& out) {
  z_stream z{};
  if (inflateInit(&z) != Z_OK) return false;
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data()));
  z.avail_in = uInt(compressed.size());
  const std::size_t start = out.size();
  std::size_t produced = 0;
  int rc = Z_OK;
  while (rc == Z_OK) {
    // One extra byte of room detects a stream longer than announced.
    const std::size_t room = std::min<std::size_t>(expectedSize - produced + 1, std::size_t(1) << 22);
    out.resize(start + produced + room);
    z.next_out = reinterpret_cast<Bytef*>(out.data() + start + produced);
    z.avail_out = uInt(room);
    rc = inflate(&z, Z_NO_FLUSH);
    produced += room - z.avail_out;
    if (produced > expectedSize) rc = Z_DATA_ERROR;
  }
  inflateEnd(&z);
  out.resize(start + std::min(produced, expectedSize));
  return rc == Z_STREAM_END && produced == expectedSize;
}

struct VtuFile {
  std::string path;
  bool swapBytes = false;          // file byte order differs from ours
  std::size_t headerSize = 4;      // UInt32 or UInt64 block headers
  bool zlib = false;               // vtkZLibDataCompressor
  std::string_view appended;       // bytes after the '_' of <AppendedData>
  bool appendedBase64 = false;

  [[noreturn]] void fail(const tinyxml2::XMLElement* e, const std::string& fault) const {
    throw InputError(path, (e ? "line " + std::to_string(e->GetLineNum()) + ": " : std::string()) + fault);
  }
};

std::string arrayName(const tinyxml2::XMLElement* e) {
  const char* n = e->Attribute("Name");
  return n ? std::string("'") + n + "'" : std::string("(unnamed)");
}

std::uint64_t unsignedAttribute(const VtuFile& f, const tinyxml2::XMLElement* e, const char* name,
                                std::optional<std::uint64_t> fallback = std::nullopt) {
  const char* text = e->Attribute(name);
  if (!text) {
    if (fallback) return *fallback;
    f.fail(e, std::string("<") + e->Name() + "> has no " + name + " attribute");
  }
  std::uint64_t v = 0;
  const char* last = text + std::strlen(text);
  const auto [end, ec] = std::from_chars(text, last, v);
  if (ec != std::errc() || end != last || end == text)
    f.fail(e, std::string("<") + e->Name() + "> attribute " + name + "=\"" + text + "\" is not a non-negative integer");
  return v;
}

std::uint64_t readHeaderValue(const VtuFile& f, const tinyxml2::XMLElement* e, EncodedBytes& in) {
  char b[8];
  if (!in.read(b, f.headerSize)) f.fail(e, "data array " + arrayName(e) + " is truncated (block header)");
  if (f.swapBytes) std::reverse(b, b + f.headerSize);
  if (f.headerSize == 4) {
    std::uint32_t v;
    std::memcpy(&v, b, 4);
    return v;
  }
  std::uint64_t v;
  std::memcpy(&v, b, 8);
  return v;
}

// The bytes of a binary or appended array, in file byte order.
std::string binaryArrayBytes(const VtuFile& f, const tinyxml2::XMLElement* e, EncodedBytes in) {
  const std::string name = arrayName(e);
  std::string bytes;
  if (!f.zlib) {
    const std::uint64_t n = readHeaderValue(f, e, in);
    if (n > in.maxRemaining())
      f.fail(e, "data array " + name + " announces " + std::to_string(n) + " bytes but the file holds fewer (truncated?)");
    bytes.resize(std::size_t(n));
    if (!in.read(bytes.data(), bytes.size())) f.fail(e, "data array " + name + " is truncated or holds invalid base64");
    return bytes;
  }
  // Compressed: [#blocks, block size, last block size, compressed sizes...].
  const std::uint64_t blocks = readHeaderValue(f, e, in);
  const std::uint64_t blockSize = readHeaderValue(f, e, in);
  const std::uint64_t lastSize = readHeaderValue(f, e, in);
  if (blocks > in.maxRemaining() / f.headerSize)
    f.fail(e, "data array " + name + " announces " + std::to_string(blocks) + " compressed blocks; the file is too short");
  std::vector<std::uint64_t> sizes(blocks);
  std::uint64_t total = 0;
  for (auto& s : sizes) {
    s = readHeaderValue(f, e, in);
    total += std::min(s, std::uint64_t(in.maxRemaining()) + 1);
  }
  if (total > in.maxRemaining())
    f.fail(e, "data array " + name + " announces " + std::to_string(total) + " compressed bytes but the file holds fewer");
  std::string block;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint64_t raw = (b + 1 == blocks && lastSize != 0) ? lastSize : blockSize;
    if (sizes[b] > std::numeric_limits<std::uint32_t>::max() || raw > std::numeric_limits<std::uint32_t>::max())
      f.fail(e, "data array " + name + " has a compressed block over 4 GiB");
    block.resize(std::size_t(sizes[b]));
    if (!in.read(block.data(), block.size())) f.fail(e, "data array " + name + " is truncated or holds invalid base64");
    if (!inflateBlock(block, std::size_t(raw), bytes))
      f.fail(e, "data array " + name + ": compressed block " + std::to_string(b) + " is corrupt");
  }
  return bytes;
}

template <class Out, class In>
void convertBytes(const char* src, std::size_t count, bool swap, std::vector<Out>& out) {
  out.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    In v;
    std::memcpy(&v, src + i * sizeof(In), sizeof(In));
    if constexpr (sizeof(In) > 1)
      if (swap) v = swapBytes(v);
    out[i] = Out(v);
  }
}

template <class T>
bool fitsInt64(T v) {
  if constexpr (std::is_same_v<T, std::uint64_t>) return v <= std::uint64_t(std::numeric_limits<std::int64_t>::max());
  return true;
}

// Values of a data array as doubles (Out = double) or integers (Out =
// int64). `expected` is the number of values the array must hold.
template <class Out>
std::vector<Out> readDataArray(const VtuFile& f, const tinyxml2::XMLElement* e, std::size_t expected) {
  const std::string name = arrayName(e);
  const char* typeName = e->Attribute("type");
  const std::optional<Scalar> type = scalarFromName(typeName ? typeName : "");
  if (!type) f.fail(e, "data array " + name + " has unsupported type " + io::quoted(typeName ? typeName : ""));
  if (std::is_integral_v<Out> && !isInteger(*type))
    f.fail(e, "data array " + name + " has type " + typeName + "; integers are needed");
  const char* formatAttr = e->Attribute("format");
  const std::string_view format = formatAttr ? formatAttr : "ascii";

  std::vector<Out> values;
  if (format == "ascii") {
    const char* text = e->GetText();
    io::TextScanner in(text ? text : "", f.path, '\0', std::size_t(e->GetLineNum()));
    values.reserve(std::min(expected, in.remainingBytes() / 2 + 1));
    while (!in.atEnd()) {
      if (values.size() == expected) f.fail(e, "data array " + name + " holds more than " + std::to_string(expected) + " values");
      if constexpr (std::is_integral_v<Out>) {
        values.push_back(in.integer("an integer"));
      } else {
        values.push_back(in.real("a finite number"));
      }
    }
  } else if (format == "binary" || format == "appended") {
    std::string bytes;
    if (format == "binary") {
      const char* text = e->GetText();
      bytes = binaryArrayBytes(f, e, EncodedBytes(text ? text : "", true));
    } else {
      if (f.appended.data() == nullptr) f.fail(e, "data array " + name + " is appended but the file has no <AppendedData>");
      const std::uint64_t offset = unsignedAttribute(f, e, "offset");
      if (offset > f.appended.size()) f.fail(e, "data array " + name + " has offset " + std::to_string(offset) + " past the end of the appended data");
      bytes = binaryArrayBytes(f, e, EncodedBytes(f.appended.substr(std::size_t(offset)), f.appendedBase64));
    }
    const std::size_t size = scalarSize(*type);
    if (bytes.size() % size != 0)
      f.fail(e, "data array " + name + " holds " + std::to_string(bytes.size()) + " bytes, not a multiple of its " + typeName + " size");
    const std::size_t n = bytes.size() / size;
    if (n != expected) f.fail(e, "data array " + name + " holds " + std::to_string(n) + " values, expected " + std::to_string(expected));
    const char* p = bytes.data();
    const bool sw = f.swapBytes;
    switch (*type) {
      case Scalar::Int8: convertBytes<Out, std::int8_t>(p, expected, sw, values); break;
      case Scalar::UInt8: convertBytes<Out, std::uint8_t>(p, expected, sw, values); break;
      case Scalar::Int16: convertBytes<Out, std::int16_t>(p, expected, sw, values); break;
      case Scalar::UInt16: convertBytes<Out, std::uint16_t>(p, expected, sw, values); break;
      case Scalar::Int32: convertBytes<Out, std::int32_t>(p, expected, sw, values); break;
      case Scalar::UInt32: convertBytes<Out, std::uint32_t>(p, expected, sw, values); break;
      case Scalar::Int64: convertBytes<Out, std::int64_t>(p, expected, sw, values); break;
      case Scalar::UInt64: {
        for (std::size_t i = 0; i < expected; ++i) {
          std::uint64_t v;
          std::memcpy(&v, p + 8 * i, 8);
          if (sw) v = swapBytes(v);
          if (!fitsInt64(v)) f.fail(e, "data array " + name + " holds " + std::to_string(v) + ", out of range");
        }
        convertBytes<Out, std::uint64_t>(p, expected, sw, values);
        break;
      }
      case Scalar::Float32: {
        if constexpr (std::is_floating_point_v<Out>) {
          values.resize(expected);
          for (std::size_t i = 0; i < expected; ++i) {
            std::uint32_t bits;
            std::memcpy(&bits, p + 4 * i, 4);
            if (sw) bits = swapBytes(bits);
            values[i] = Out(std::bit_cast<float>(bits));
          }
        }
        break;
      }
      case Scalar::Float64: {
        if constexpr (std::is_floating_point_v<Out>) {
          values.resize(expected);
          for (std::size_t i = 0; i < expected; ++i) {
            std::uint64_t bits;
            std::memcpy(&bits, p + 8 * i, 8);
            if (sw) bits = swapBytes(bits);
            values[i] = std::bit_cast<double>(bits);
          }
        }
        break;
      }
    }
  } else {
    f.fail(e, "data array " + name + " has unknown format " + io::quoted(format));
  }
  if (values.size() != expected)
    f.fail(e, "data array " + name + " holds " + std::to_string(values.size()) + " values, expected " + std::to_string(expected));
  return values;
}

const tinyxml2::XMLElement* namedArray(const tinyxml2::XMLElement* parent, std::string_view name) {
  for (const auto* a = parent ? parent->FirstChildElement("DataArray") : nullptr; a; a = a->NextSiblingElement("DataArray")) {
    const char* n = a->Attribute("Name");
    if (n && name == n) return a;
  }
  return nullptr;
}

std::uint64_t componentCount(const VtuFile& f, const tinyxml2::XMLElement* a) {
  const char* nc = a->Attribute("NumberOfComponents");
  // Firedrake writes NumberOfComponents="".
  if (!nc || *nc == '\0') return 1;
  return unsignedAttribute(f, a, "NumberOfComponents");
}

// The cell data array that holds labels (see the file comment), or null.
const tinyxml2::XMLElement* labelArray(const VtuFile& f, const tinyxml2::XMLElement* cellData) {
  for (const char* preferred : {"label", "medit:ref", "gmsh:physical"})
    if (const auto* a = namedArray(cellData, preferred)) return a;
  for (const auto* a = cellData ? cellData->FirstChildElement("DataArray") : nullptr; a; a = a->NextSiblingElement("DataArray")) {
    const char* t = a->Attribute("type");
    const std::optional<Scalar> s = scalarFromName(t ? t : "");
    if (s && isInteger(*s) && componentCount(f, a) == 1) return a;
  }
  return nullptr;
}

// Field data arrays of two integers (label, 3), as writeVtu and meshio write
// names of volume groups, name labels the mesh holds; other arrays are not
// label names and are skipped.
void readLabelNames(const VtuFile& f, const tinyxml2::XMLElement* fieldData, TetMesh& mesh) {
  if (!fieldData) return;
  std::map<std::int32_t, std::string> names;
  for (const auto* a = fieldData->FirstChildElement("DataArray"); a; a = a->NextSiblingElement("DataArray")) {
    const char* name = a->Attribute("Name");
    const char* type = a->Attribute("type");
    const std::optional<Scalar> s = scalarFromName(type ? type : "");
    if (!name || !*name || !s || !isInteger(*s)) continue;
    const char* tuples = a->Attribute("NumberOfTuples");
    if (tuples && std::string_view(tuples) != "2") continue;
    std::vector<std::int64_t> v;
    try {
      v = readDataArray<std::int64_t>(f, a, 2);
    } catch (const InputError&) {
      continue;  // not a (label, dimension) pair
    }
    if (v[1] != 3 || v[0] < std::numeric_limits<std::int32_t>::min() || v[0] > std::numeric_limits<std::int32_t>::max()) continue;
    names[std::int32_t(v[0])] = name;
  }
  setLabelNames(mesh, names);
}

void readPiece(const VtuFile& f, const tinyxml2::XMLElement* piece, TetMesh& mesh) {
  const std::uint64_t np = unsignedAttribute(f, piece, "NumberOfPoints", 0);
  const std::uint64_t nc = unsignedAttribute(f, piece, "NumberOfCells", 0);
  // Vertex indices are 32-bit; this also keeps the products below in range.
  const std::uint64_t limit = std::uint64_t(std::numeric_limits<std::int32_t>::max());
  if (np > limit || nc > limit)
    f.fail(piece, "Piece announces " + std::to_string(np) + " points and " + std::to_string(nc) + " cells, more than supported");

  const auto* points = piece->FirstChildElement("Points");
  const auto* pointArray = points ? points->FirstChildElement("DataArray") : nullptr;
  if (np > 0 && !pointArray) f.fail(piece, "Piece has no <Points> data array");
  const std::size_t base = mesh.positions.size();
  if (pointArray) {
    if (componentCount(f, pointArray) != 3) f.fail(pointArray, "Points must have 3 components");
    const std::vector<double> xyz = readDataArray<double>(f, pointArray, std::size_t(3 * np));
    mesh.positions.resize(base + std::size_t(np));
    for (std::size_t i = 0; i < np; ++i) {
      const Eigen::Vector3d p(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
      if (!p.allFinite()) f.fail(pointArray, "point " + std::to_string(i) + " has a non-finite coordinate");
      mesh.positions[base + i] = p;
    }
  }
  if (base + np > std::size_t(std::numeric_limits<std::int32_t>::max()))
    f.fail(piece, "more than 2^31 - 1 points in all pieces");
  if (nc == 0) return;

  const auto* cells = piece->FirstChildElement("Cells");
  const auto* offsetArray = namedArray(cells, "offsets");
  const auto* typeArray = namedArray(cells, "types");
  const auto* connectivityArray = namedArray(cells, "connectivity");
  if (!offsetArray || !typeArray || !connectivityArray)
    f.fail(cells ? cells : piece, "Cells lacks a connectivity, offsets or types data array");
  const std::vector<std::int64_t> offsets = readDataArray<std::int64_t>(f, offsetArray, std::size_t(nc));
  const std::vector<std::int64_t> types = readDataArray<std::int64_t>(f, typeArray, std::size_t(nc));
  // Offsets are where each cell's point list ends.
  std::int64_t previous = 0;
  for (std::size_t c = 0; c < nc; ++c) {
    if (offsets[c] < previous) f.fail(offsetArray, "offsets decrease at cell " + std::to_string(c));
    previous = offsets[c];
  }
  const std::vector<std::int64_t> connectivity =
      readDataArray<std::int64_t>(f, connectivityArray, std::size_t(offsets.back()));

  std::vector<std::int64_t> cellLabels;
  const auto* cellData = piece->FirstChildElement("CellData");
  if (const auto* labels = labelArray(f, cellData)) {
    if (componentCount(f, labels) != 1) f.fail(labels, "label array " + arrayName(labels) + " must have one component");
    cellLabels = readDataArray<std::int64_t>(f, labels, std::size_t(nc));
  }

  for (std::size_t c = 0; c < nc; ++c) {
    if (types[c] != kVtkTetra) continue;
    const std::int64_t start = c == 0 ? 0 : offsets[c - 1];
    if (offsets[c] - start != 4)
      f.fail(connectivityArray, "cell " + std::to_string(c) + " is a VTK_TETRA with " + std::to_string(offsets[c] - start) + " points");
    Tet t;
    for (int k = 0; k < 4; ++k) {
      const std::int64_t v = connectivity[std::size_t(start + k)];
      if (v < 0 || std::uint64_t(v) >= np)
        f.fail(connectivityArray, "cell " + std::to_string(c) + " references point " + std::to_string(v) + " (the piece has " +
                                      std::to_string(np) + " points)");
      t[k] = std::int32_t(base + std::size_t(v));
    }
    std::int32_t label = 1;
    if (!cellLabels.empty()) {
      const std::int64_t l = cellLabels[c];
      if (l < std::numeric_limits<std::int32_t>::min() || l > std::numeric_limits<std::int32_t>::max())
        f.fail(cellData, "cell " + std::to_string(c) + " has label " + std::to_string(l) + ", out of the 32-bit range");
      label = std::int32_t(l);
    }
    mesh.tets.push_back(t);
    mesh.labels.push_back(label);
  }
}

}  // namespace

TetMesh readVtu(const std::string& path) {
  const std::string bytes = io::readWholeFile(path);
  VtuFile f;
  f.path = path;

  // Appended raw data is binary and cannot go through the XML parser: parse
  // the XML with the data cut out, and keep the data beside it.
  std::string_view xml = bytes;
  std::string xmlWithoutData;
  const std::size_t appendedTag = bytes.find("<AppendedData");
  if (appendedTag != std::string::npos) {
    const std::size_t tagEnd = bytes.find('>', appendedTag);
    if (tagEnd == std::string::npos) throw InputError(path, "truncated <AppendedData> tag");
    if (bytes[tagEnd - 1] != '/') {
      const std::size_t underscore = bytes.find_first_not_of(" \t\r\n", tagEnd + 1);
      const std::size_t close = bytes.rfind("</AppendedData>");
      if (close == std::string::npos || close < tagEnd) throw InputError(path, "<AppendedData> is not closed (truncated file?)");
      if (underscore == std::string::npos || underscore >= close || bytes[underscore] != '_')
        throw InputError(path, "<AppendedData> does not start with '_'");
      f.appended = std::string_view(bytes).substr(underscore + 1, close - underscore - 1);
      xmlWithoutData = bytes.substr(0, tagEnd + 1) + bytes.substr(close);
      xml = xmlWithoutData;
    }
  }

  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.data(), xml.size()) != tinyxml2::XML_SUCCESS)
    throw InputError(path, "not a valid XML file (line " + std::to_string(doc.ErrorLineNum()) + ": " + doc.ErrorName() + ")");
  const auto* root = doc.RootElement();
  if (!root || std::string_view(root->Name()) != "VTKFile") throw InputError(path, "not a VTK XML file (no <VTKFile> root)");
  const char* type = root->Attribute("type");
  if (!type || std::string_view(type) != "UnstructuredGrid")
    f.fail(root, std::string("VTK file of type ") + io::quoted(type ? type : "") + ", expected UnstructuredGrid");
  const char* order = root->Attribute("byte_order");
  const bool bigEndian = order && std::string_view(order) == "BigEndian";
  if (order && !bigEndian && std::string_view(order) != "LittleEndian") f.fail(root, std::string("unknown byte_order ") + io::quoted(order));
  f.swapBytes = bigEndian != (std::endian::native == std::endian::big);
  if (const char* h = root->Attribute("header_type")) {
    if (std::string_view(h) == "UInt64") f.headerSize = 8;
    else if (std::string_view(h) != "UInt32") f.fail(root, std::string("unsupported header_type ") + io::quoted(h));
  }
  if (const char* c = root->Attribute("compressor"); c && *c) {
    if (std::string_view(c) != "vtkZLibDataCompressor")
      f.fail(root, std::string("unsupported compressor ") + io::quoted(c) + " (zlib is supported)");
    f.zlib = true;
  }
  if (const auto* appended = root->FirstChildElement("AppendedData")) {
    const char* encoding = appended->Attribute("encoding");
    const std::string_view enc = encoding ? encoding : "";
    if (enc == "base64") f.appendedBase64 = true;
    else if (enc != "raw") f.fail(appended, "unknown AppendedData encoding " + io::quoted(enc));
  }

  const auto* grid = root->FirstChildElement("UnstructuredGrid");
  if (!grid) f.fail(root, "no <UnstructuredGrid> element");
  TetMesh mesh;
  bool anyPiece = false;
  for (const auto* piece = grid->FirstChildElement("Piece"); piece; piece = piece->NextSiblingElement("Piece")) {
    readPiece(f, piece, mesh);
    anyPiece = true;
  }
  if (!anyPiece) f.fail(grid, "no <Piece> element");
  if (mesh.tets.empty()) throw InputError(path, "no tetrahedra (no VTK_TETRA cells)");
  readLabelNames(f, grid->FirstChildElement("FieldData"), mesh);
  mesh.validate(path);
  return mesh;
}

namespace {

std::string xmlEscaped(std::string_view text) {
  std::string s;
  for (char c : text) {
    switch (c) {
      case '&': s += "&amp;"; break;
      case '<': s += "&lt;"; break;
      case '>': s += "&gt;"; break;
      case '"': s += "&quot;"; break;
      case '\n': case '\r': case '\t': s += ' '; break;
      default: s += c;
    }
  }
  return s;
}

// Label names as field data, one array per name holding (label, 3): meshio's
// field_data for physical groups (name -> [tag, dimension]), so a meshio
// conversion to .msh keeps them as physical names; ParaView lists them.
void writeLabelNames(io::TextOutput& out, const std::map<std::int32_t, std::string>& names) {
  if (names.empty()) return;
  out << "    <FieldData>\n";
  for (const auto& [label, name] : names)
    out << "      <DataArray type=\"Int32\" Name=\"" << xmlEscaped(name) << "\" NumberOfTuples=\"2\" format=\"ascii\">"
        << label << " 3</DataArray>\n";
  out << "    </FieldData>\n";
}

}  // namespace

void writeVtu(const std::string& path, const TetMesh& mesh) {
  mesh.validate(path);
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "points are written as one packed array");
  static_assert(sizeof(Tet) == 4 * sizeof(std::int32_t), "tets are written as one packed array");
  const std::uint64_t nv = mesh.vertexCount(), nt = mesh.tetCount();
  // Appended blocks: UInt64 byte count, then the values.
  const std::uint64_t pointBytes = 24 * nv, connectivityBytes = 16 * nt, offsetBytes = 8 * nt, typeBytes = nt, labelBytes = 4 * nt;
  const std::uint64_t pointAt = 0;
  const std::uint64_t connectivityAt = pointAt + 8 + pointBytes;
  const std::uint64_t offsetAt = connectivityAt + 8 + connectivityBytes;
  const std::uint64_t typeAt = offsetAt + 8 + offsetBytes;
  const std::uint64_t labelAt = typeAt + 8 + typeBytes;

  AtomicFile file(path);
  {
    io::TextOutput out(file.openStdio());
    const char* byteOrder = std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian";
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"" << byteOrder
        << "\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n";
    writeLabelNames(out, mesh.labelNames);
    out << "    <Piece NumberOfPoints=\"" << nv << "\" NumberOfCells=\"" << nt
        << "\">\n      <Points>\n        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\""
        << pointAt << "\"/>\n      </Points>\n      <Cells>\n"
        << "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" offset=\"" << connectivityAt << "\"/>\n"
        << "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"" << offsetAt << "\"/>\n"
        << "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"" << typeAt << "\"/>\n"
        << "      </Cells>\n      <CellData Scalars=\"label\">\n"
        << "        <DataArray type=\"Int32\" Name=\"label\" format=\"appended\" offset=\"" << labelAt << "\"/>\n"
        << "      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";
    out.write(&pointBytes, 8);
    out.write(mesh.positions.data(), std::size_t(pointBytes));
    out.write(&connectivityBytes, 8);
    out.write(mesh.tets.data(), std::size_t(connectivityBytes));
    out.write(&offsetBytes, 8);
    for (std::uint64_t t = 1; t <= nt; ++t) {
      const std::int64_t end = std::int64_t(4 * t);
      out.write(&end, 8);
    }
    out.write(&typeBytes, 8);
    for (std::uint64_t t = 0; t < nt; ++t) out << char(kVtkTetra);
    out.write(&labelBytes, 8);
    out.write(mesh.labels.data(), std::size_t(labelBytes));
    // meshio's raw reader expects a newline between the data and the tag.
    out << "\n  </AppendedData>\n</VTKFile>\n";
  }
  file.commit();
}

}  // namespace vox
