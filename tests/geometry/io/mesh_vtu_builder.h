#pragma once
// Builds .vtu files in every encoding VTK defines (ascii; binary base64 inline;
// appended raw or base64; zlib-compressed or not; UInt32 or UInt64 block
// headers; either byte order), the way vtkXMLWriter lays them out.

#include "geometry/tet_mesh.h"

#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace vox::test {

struct VtuEncoding {
  enum Format { Ascii, Binary, AppendedRaw, AppendedBase64 } format = AppendedRaw;
  bool zlib = false;
  bool header64 = false;
  bool bigEndian = false;
  std::size_t blockSize = 4096;  // uncompressed bytes per zlib block
};

inline std::string base64Encode(const std::string& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 3; ++k) v = v << 8 | (k < n ? std::uint8_t(bytes[i + k]) : 0u);
    for (std::size_t k = 0; k < 4; ++k) out += k <= n ? kAlphabet[(v >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

// Values of one data array in the file's byte order.
template <class T>
std::string arrayBytes(const std::vector<T>& values, bool bigEndian) {
  std::string b(values.size() * sizeof(T), '\0');
  std::memcpy(b.data(), values.data(), b.size());
  if (bigEndian)
    for (std::size_t i = 0; i < b.size(); i += sizeof(T)) std::reverse(b.begin() + std::ptrdiff_t(i), b.begin() + std::ptrdiff_t(i + sizeof(T)));
  return b;
}

inline std::string headerBytes(const std::vector<std::uint64_t>& values, const VtuEncoding& e) {
  if (e.header64) return arrayBytes(values, e.bigEndian);
  return arrayBytes(std::vector<std::uint32_t>(values.begin(), values.end()), e.bigEndian);
}

// A binary block: its header and its data, kept apart because VTK base64-
// encodes them as two streams.
struct Block {
  std::string header, data;
};

inline Block encodeBlock(const std::string& raw, const VtuEncoding& e) {
  if (!e.zlib) return {headerBytes({raw.size()}, e), raw};
  std::vector<std::uint64_t> header;
  std::string data;
  const std::size_t blocks = (raw.size() + e.blockSize - 1) / e.blockSize;
  header = {blocks, e.blockSize, raw.size() % e.blockSize};
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t n = std::min(e.blockSize, raw.size() - b * e.blockSize);
    uLongf size = compressBound(uLong(n));
    std::string out(size, '\0');
    compress2(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(raw.data() + b * e.blockSize), uLong(n), 6);
    out.resize(size);
    header.push_back(size);
    data += out;
  }
  return {headerBytes(header, e), data};
}

template <class T>
std::string asciiValues(const std::vector<T>& values) {
  std::string s;
  for (const T& v : values) {
    if constexpr (std::is_floating_point_v<T>) {
      char text[40];
      std::snprintf(text, sizeof(text), "%.17g ", v);
      s += text;
    } else {
      s += std::to_string(v) + " ";
    }
  }
  return s;
}

inline std::string vtuFile(const TetMesh& mesh, const VtuEncoding& e) {
  std::vector<double> points;
  for (const auto& p : mesh.positions) points.insert(points.end(), {p.x(), p.y(), p.z()});
  std::vector<std::int64_t> connectivity;
  std::vector<std::uint32_t> offsets;
  for (const Tet& t : mesh.tets) {
    connectivity.insert(connectivity.end(), t.begin(), t.end());
    offsets.push_back(std::uint32_t(connectivity.size()));
  }
  const std::vector<std::uint8_t> types(mesh.tetCount(), 10);

  std::string appended;
  auto array = [&](const char* type, const char* name, const std::string& extra, const auto& values) {
    std::string tag = std::string("<DataArray type=\"") + type + "\" Name=\"" + name + "\"" + extra;
    if (e.format == VtuEncoding::Ascii) return tag + " format=\"ascii\">" + asciiValues(values) + "</DataArray>\n";
    const Block block = encodeBlock(arrayBytes(values, e.bigEndian), e);
    if (e.format == VtuEncoding::Binary)
      return tag + " format=\"binary\">\n" + base64Encode(block.header) + base64Encode(block.data) + "\n</DataArray>\n";
    tag += " format=\"appended\" offset=\"" + std::to_string(appended.size()) + "\"/>\n";
    appended += e.format == VtuEncoding::AppendedRaw ? block.header + block.data
                                                     : base64Encode(block.header) + base64Encode(block.data);
    return tag;
  };
  std::string xml = std::string("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"") +
                    (e.bigEndian ? "BigEndian" : "LittleEndian") + "\" header_type=\"" + (e.header64 ? "UInt64" : "UInt32") +
                    "\"" + (e.zlib ? " compressor=\"vtkZLibDataCompressor\"" : "") + ">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"" +
                    std::to_string(mesh.vertexCount()) + "\" NumberOfCells=\"" + std::to_string(mesh.tetCount()) + "\">\n<Points>\n";
  xml += array("Float64", "Points", " NumberOfComponents=\"3\"", points);
  xml += "</Points>\n<Cells>\n";
  xml += array("Int64", "connectivity", "", connectivity);
  xml += array("UInt32", "offsets", "", offsets);
  xml += array("UInt8", "types", "", types);
  xml += "</Cells>\n<CellData Scalars=\"label\">\n";
  xml += array("Int32", "label", "", mesh.labels);
  xml += "</CellData>\n</Piece>\n</UnstructuredGrid>\n";
  if (e.format == VtuEncoding::AppendedRaw || e.format == VtuEncoding::AppendedBase64)
    xml += std::string("<AppendedData encoding=\"") + (e.format == VtuEncoding::AppendedRaw ? "raw" : "base64") + "\">\n_" +
           appended + "\n</AppendedData>\n";
  return xml + "</VTKFile>\n";
}

}  // namespace vox::test
