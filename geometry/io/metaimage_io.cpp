// MetaImage (ITK's MetaIO): .mha with the samples after the header, or .mhd
// naming a separate data file; samples raw or zlib-compressed
// (CompressedData). ITK's world is LPS: directions are converted to RAS on
// reading and back on writing (see flipLpsRas).

#include "geometry/ascii_text.h"
#include "geometry/error.h"
#include "geometry/io/grid_stream.h"
#include "geometry/io/header_text.h"

#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>

namespace vox {

namespace {

constexpr std::size_t kMaxHeaderBytes = std::size_t(1) << 20;

bool metaVoxelType(const std::string& name, VoxelType& type) {
  static const std::map<std::string, VoxelType> types = {
      {"MET_UCHAR", VoxelType::UInt8},      {"MET_CHAR", VoxelType::Int8},        {"MET_USHORT", VoxelType::UInt16},
      {"MET_SHORT", VoxelType::Int16},      {"MET_UINT", VoxelType::UInt32},      {"MET_INT", VoxelType::Int32},
      {"MET_ULONG", VoxelType::UInt32},     {"MET_LONG", VoxelType::Int32},       {"MET_ULONG_LONG", VoxelType::UInt64},
      {"MET_LONG_LONG", VoxelType::Int64},  {"MET_FLOAT", VoxelType::Float32},    {"MET_DOUBLE", VoxelType::Float64},
  };
  const auto it = types.find(name);
  if (it == types.end()) return false;
  type = it->second;
  return true;
}

bool parseBool(const std::string& source, const std::string& field, std::string_view text) {
  const std::string v = toLowerAscii(trimText(text));
  if (v == "true" || v == "1") return true;
  if (v == "false" || v == "0") return false;
  throw InputError(source, field + ": \"" + std::string(trimText(text)) + "\" is not True or False");
}

struct MetaHeader {
  std::map<std::string, std::string> fields;  // lower-case key -> value
  std::string dataFile;
  std::uint64_t headerBytes = 0;  // where LOCAL samples start

  const std::string* find(std::initializer_list<const char*> keys) const {
    for (const char* k : keys) {
      const auto it = fields.find(k);
      if (it != fields.end()) return &it->second;
    }
    return nullptr;
  }
};

// "Key = Value" lines up to ElementDataFile, which ends the header.
MetaHeader parseMetaHeader(const std::string& path, const std::string& text) {
  MetaHeader h;
  std::size_t pos = 0;
  for (int line = 1;; ++line) {
    if (pos >= text.size()) {
      if (text.size() >= kMaxHeaderBytes) throw InputError(path, "MetaImage header has no ElementDataFile field in its first megabyte");
      throw InputError(path, "MetaImage header ends without an ElementDataFile field");
    }
    std::size_t end = text.find('\n', pos);
    const bool lastLine = end == std::string::npos;
    if (lastLine) end = text.size();
    const std::string_view raw(text.data() + pos, end - pos);
    pos = lastLine ? end : end + 1;
    const std::string_view content = trimText(raw);
    if (content.empty()) continue;
    const std::size_t eq = content.find('=');
    if (eq == std::string_view::npos || trimText(content.substr(0, eq)).empty())
      throw InputError(path, "line " + std::to_string(line) + " of the MetaImage header is not a \"Key = Value\" field");
    const std::string key = toLowerAscii(trimText(content.substr(0, eq)));
    const std::string value(trimText(content.substr(eq + 1)));
    if (key == "elementdatafile") {
      h.dataFile = value;
      h.headerBytes = pos;
      return h;
    }
    h.fields[key] = value;
  }
}

struct MetaLayout {
  GridGeometry geometry;
  VoxelEncoding encoding;
  bool compressed = false;
  std::int64_t headerSize = 0;  // HeaderSize: bytes to skip in the data file; -1: samples end the file
};

MetaLayout interpretMetaHeader(const std::string& path, const MetaHeader& h) {
  auto required = [&](const char* key, const char* name) -> const std::string& {
    const std::string* v = h.find({key});
    if (!v) throw InputError(path, std::string("MetaImage header has no ") + name + " field");
    return *v;
  };
  if (const std::string* v = h.find({"objecttype"}); v && toLowerAscii(*v) != "image")
    throw InputError(path, "ObjectType is \"" + *v + "\", not Image");
  if (parseInteger(path, "NDims", required("ndims", "NDims")) != 3)
    throw InputError(path, "NDims is " + required("ndims", "NDims") + ": only 3-D grids are supported");
  const Index3 dims = parseDims(path, "DimSize", required("dimsize", "DimSize"));
  checkGridDims(path, dims);

  MetaLayout layout;
  const std::string& typeName = required("elementtype", "ElementType");
  if (!metaVoxelType(typeName, layout.encoding.type))
    throw InputError(path, "ElementType " + typeName + " is not supported for labels (expected an integer or float type)");
  if (const std::string* v = h.find({"elementnumberofchannels"}); v && parseInteger(path, "ElementNumberOfChannels", *v) != 1)
    throw InputError(path, "ElementNumberOfChannels is " + *v + ": labels need 1 channel");
  if (const std::string* v = h.find({"binarydata"}); v && !parseBool(path, "BinaryData", *v))
    throw InputError(path, "ASCII element data (BinaryData = False) is not supported");
  if (const std::string* v = h.find({"binarydatabyteordermsb", "elementbyteordermsb"}))
    layout.encoding.bigEndian = parseBool(path, "BinaryDataByteOrderMSB", *v);
  if (const std::string* v = h.find({"compresseddata"})) layout.compressed = parseBool(path, "CompressedData", *v);
  if (const std::string* v = h.find({"headersize"})) {
    layout.headerSize = parseInteger(path, "HeaderSize", *v);
    if (layout.headerSize < -1) throw InputError(path, "HeaderSize " + *v + " is negative");
  }

  Eigen::Vector3d spacing(1, 1, 1);
  if (const std::string* v = h.find({"elementspacing", "elementsize"})) {
    const auto s = parseReals(path, "ElementSpacing", *v, 3);
    for (int a = 0; a < 3; ++a) {
      if (!(s[a] > 0.0))
        throw InputError(path, "ElementSpacing along axis " + std::to_string(a) + " is " + realText(s[a]) + " (must be positive)");
      spacing[a] = s[a];
    }
  }
  Eigen::Vector3d offset(0, 0, 0);
  if (const std::string* v = h.find({"offset", "origin", "position"})) {
    const auto o = parseReals(path, "Offset", *v, 3);
    offset = Eigen::Vector3d(o[0], o[1], o[2]);
  }
  // TransformMatrix lists the direction of each grid axis in turn (ITK's
  // MetaImageIO reads element [i*3 + j] as component j of axis i).
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();
  if (const std::string* v = h.find({"transformmatrix", "rotation", "orientation"})) {
    const auto m = parseReals(path, "TransformMatrix", *v, 9);
    for (int axis = 0; axis < 3; ++axis)
      for (int c = 0; c < 3; ++c) direction(c, axis) = m[std::size_t(axis * 3 + c)];
  }
  const Eigen::Matrix3d flip = Eigen::Vector3d(-1, -1, 1).asDiagonal();
  layout.geometry = geometryFromAffine(path, dims, flip * direction * spacing.asDiagonal(), flip * offset);
  return layout;
}

std::unique_ptr<GridSliceReader> openMetaImage(const std::string& path) {
  std::FILE* headerFile = openForReading(path, path);
  MetaHeader header;
  MetaLayout layout;
  try {
    header = parseMetaHeader(path, readPrefix(headerFile, kMaxHeaderBytes));
    layout = interpretMetaHeader(path, header);
  } catch (...) {
    std::fclose(headerFile);
    throw;
  }

  std::FILE* data = headerFile;
  std::uint64_t start = header.headerBytes;
  std::string source = path;
  if (toLowerAscii(header.dataFile) != "local") {
    std::fclose(headerFile);
    const auto words = splitWords(header.dataFile);
    if (words.empty()) throw InputError(path, "ElementDataFile is empty");
    if (words.size() > 1 || toLowerAscii(words[0]) == "list" || header.dataFile.find('%') != std::string::npos)
      throw InputError(path, "ElementDataFile \"" + header.dataFile + "\" (a list of slice files) is not supported");
    const std::string dataPath = siblingPath(path, header.dataFile);
    data = openForReading(dataPath, path);
    start = 0;
    source = path + " (data file " + dataPath + ")";
  }
  const std::int64_t sampleBytes = layout.geometry.voxelCount() * voxelTypeSize(layout.encoding.type);
  if (layout.headerSize == -1) {
    if (layout.compressed) {
      std::fclose(data);
      throw InputError(path, "HeaderSize = -1 cannot locate compressed data");
    }
    std::fseek(data, 0, SEEK_END);
    const std::int64_t fileSize = ::ftello(data);
    start = fileSize >= sampleBytes ? std::uint64_t(fileSize - sampleBytes) : 0;
  } else {
    start += std::uint64_t(layout.headerSize);
  }
  std::unique_ptr<ByteReader> in =
      layout.compressed ? inflateReader(data, start, source) : plainReader(data, start, source);
  return std::make_unique<StreamSliceReader>(source, layout.geometry, layout.encoding, std::move(in), 0);
}

std::string numbers(std::initializer_list<double> values) {
  std::string s;
  char buf[40];
  for (double v : values) {
    std::snprintf(buf, sizeof(buf), "%.17g", v + 0.0);  // + 0.0: no "-0"
    if (!s.empty()) s += ' ';
    s += buf;
  }
  return s;
}

std::string metaHeaderText(const GridGeometry& g, Label maxLabel, bool compressed, std::int64_t compressedBytes,
                           const std::string& dataFile) {
  const Eigen::Matrix3d d = flipLpsRas(g.direction);
  const Eigen::Vector3d offset = flipLpsRas(g.direction) * g.origin;
  std::string h;
  h += "ObjectType = Image\n";
  h += "NDims = 3\n";
  h += "BinaryData = True\n";
  h += "BinaryDataByteOrderMSB = False\n";
  h += std::string("CompressedData = ") + (compressed ? "True" : "False") + "\n";
  if (compressed) h += "CompressedDataSize = " + std::to_string(compressedBytes) + "\n";
  h += "TransformMatrix = " +
       numbers({d(0, 0), d(1, 0), d(2, 0), d(0, 1), d(1, 1), d(2, 1), d(0, 2), d(1, 2), d(2, 2)}) + "\n";
  h += "Offset = " + numbers({offset[0], offset[1], offset[2]}) + "\n";
  h += "ElementSpacing = " + numbers({g.spacing[0], g.spacing[1], g.spacing[2]}) + "\n";
  h += "DimSize = " + std::to_string(g.dims[0]) + " " + std::to_string(g.dims[1]) + " " + std::to_string(g.dims[2]) + "\n";
  h += std::string("ElementType = ") + (storedLabelType(maxLabel) == VoxelType::UInt8 ? "MET_UCHAR" : "MET_USHORT") + "\n";
  h += "ElementDataFile = " + dataFile + "\n";
  return h;
}

bool isDetachedHeader(const std::string& path) { return toLowerAscii(std::filesystem::path(path).extension().string()) == ".mhd"; }

// zlib-compressed samples gathered in memory: the header must state their size.
class CompressedSamples final : public EncodedSliceWriter {
public:
  CompressedSamples(const std::string& path, const GridGeometry& geometry, Label maxLabel)
      : EncodedSliceWriter(path, geometry, maxLabel), out_(stringWriter(bytes)), deflate_(deflateWriter(*out_, DeflateWrapper::Zlib, path)) {}
  std::string bytes;

private:
  ByteWriter& samples() override { return *deflate_; }
  void commitFiles() override { deflate_->finish(); }

  std::unique_ptr<ByteWriter> out_;
  std::unique_ptr<ByteWriter> deflate_;
};

}  // namespace

std::unique_ptr<GridSliceReader> openMetaImageSlices(const std::string& path) { return openMetaImage(path); }

std::unique_ptr<GridSliceWriter> createMetaImageSlices(const std::string& path, const GridGeometry& geometry, Label maxLabel) {
  if (!isDetachedHeader(path))
    return std::make_unique<TextHeaderSliceWriter>(path, geometry, maxLabel, metaHeaderText(geometry, maxLabel, false, 0, "LOCAL"),
                                                   std::string(), SampleCompression::None);
  const std::filesystem::path dataPath = std::filesystem::path(path).replace_extension(".raw");
  return std::make_unique<TextHeaderSliceWriter>(path, geometry, maxLabel,
                                                 metaHeaderText(geometry, maxLabel, false, 0, dataPath.filename().string()),
                                                 dataPath.string(), SampleCompression::None);
}

std::string metaImageDataFile(const std::string& path) {
  const MetaHeader header = parseMetaHeader(path, readFilePrefix(path, kMaxHeaderBytes));
  return toLowerAscii(header.dataFile) == "local" ? std::string() : siblingPath(path, header.dataFile);
}

LabelGrid readMetaImage(const std::string& path) {
  const auto reader = openMetaImage(path);
  return readAllSlices(*reader);
}

void writeMetaImage(const std::string& path, const LabelGrid& grid) {
  if (isDetachedHeader(path)) {
    const auto writer = createMetaImageSlices(path, grid.geometry(), grid.maxLabel());
    writeAllSlices(*writer, grid);
    return;
  }
  const Label maxLabel = grid.maxLabel();
  CompressedSamples samples(path, grid.geometry(), maxLabel);
  writeAllSlices(samples, grid);
  const std::string header = metaHeaderText(grid.geometry(), maxLabel, true, std::int64_t(samples.bytes.size()), "LOCAL");
  AtomicFile file(path);
  const auto out = stdioWriter(file.openStdio(), path);
  out->write(header.data(), header.size());
  out->write(samples.bytes.data(), samples.bytes.size());
  file.commit();
}

}  // namespace vox
