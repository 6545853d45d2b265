// NRRD (teem): .nrrd with the samples after the header, or .nhdr naming a
// separate data file; raw or gzip encoding. World coordinates are converted
// to RAS from the header's `space` (LPS, LAS or RAS); the writer uses RAS.

#include "geometry/ascii_text.h"
#include "geometry/error.h"
#include "geometry/io/grid_stream.h"
#include "geometry/io/header_text.h"

#include <filesystem>
#include <map>

namespace vox {

namespace {

constexpr std::size_t kMaxHeaderBytes = std::size_t(1) << 20;

bool nrrdVoxelType(const std::string& name, VoxelType& type) {
  static const std::map<std::string, VoxelType> types = {
      {"uchar", VoxelType::UInt8},
      {"unsigned char", VoxelType::UInt8},
      {"uint8", VoxelType::UInt8},
      {"uint8_t", VoxelType::UInt8},
      {"signed char", VoxelType::Int8},
      {"int8", VoxelType::Int8},
      {"int8_t", VoxelType::Int8},
      {"short", VoxelType::Int16},
      {"short int", VoxelType::Int16},
      {"signed short", VoxelType::Int16},
      {"signed short int", VoxelType::Int16},
      {"int16", VoxelType::Int16},
      {"int16_t", VoxelType::Int16},
      {"ushort", VoxelType::UInt16},
      {"unsigned short", VoxelType::UInt16},
      {"unsigned short int", VoxelType::UInt16},
      {"uint16", VoxelType::UInt16},
      {"uint16_t", VoxelType::UInt16},
      {"int", VoxelType::Int32},
      {"signed int", VoxelType::Int32},
      {"int32", VoxelType::Int32},
      {"int32_t", VoxelType::Int32},
      {"uint", VoxelType::UInt32},
      {"unsigned int", VoxelType::UInt32},
      {"uint32", VoxelType::UInt32},
      {"uint32_t", VoxelType::UInt32},
      {"longlong", VoxelType::Int64},
      {"long long", VoxelType::Int64},
      {"long long int", VoxelType::Int64},
      {"signed long long", VoxelType::Int64},
      {"signed long long int", VoxelType::Int64},
      {"int64", VoxelType::Int64},
      {"int64_t", VoxelType::Int64},
      {"ulonglong", VoxelType::UInt64},
      {"unsigned long long", VoxelType::UInt64},
      {"unsigned long long int", VoxelType::UInt64},
      {"uint64", VoxelType::UInt64},
      {"uint64_t", VoxelType::UInt64},
      {"float", VoxelType::Float32},
      {"double", VoxelType::Float64},
  };
  const auto it = types.find(name);
  if (it == types.end()) return false;
  type = it->second;
  return true;
}

struct NrrdHeader {
  std::map<std::string, std::string> fields;  // lower-case field name -> value
  std::uint64_t headerBytes = 0;              // where attached samples start

  const std::string* find(std::initializer_list<const char*> keys) const {
    for (const char* k : keys) {
      const auto it = fields.find(k);
      if (it != fields.end()) return &it->second;
    }
    return nullptr;
  }
};

// Magic line, then "field: value" lines up to a blank line (attached data
// follows it) or the end of a detached header. "key:=value" pairs and
// comments are skipped.
NrrdHeader parseNrrdHeader(const std::string& path, const std::string& text) {
  if (text.size() < 8 || text.compare(0, 7, "NRRD000") != 0 || text[7] < '1' || text[7] > '9')
    throw InputError(path, "not a NRRD file (bad magic, expected \"NRRD000X\")");
  NrrdHeader h;
  std::size_t pos = text.find('\n');
  if (pos == std::string::npos) throw InputError(path, "NRRD header is truncated after its magic line");
  ++pos;
  for (int line = 2;; ++line) {
    if (pos >= text.size()) {
      if (text.size() >= kMaxHeaderBytes) throw InputError(path, "NRRD header does not end within its first megabyte");
      h.headerBytes = text.size();
      return h;
    }
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view content(text.data() + pos, end - pos);
    pos = std::min(end + 1, text.size());
    if (!content.empty() && content.back() == '\r') content.remove_suffix(1);
    if (content.empty()) {
      h.headerBytes = pos;
      return h;
    }
    if (content.front() == '#') continue;
    if (content.find(":=") != std::string_view::npos) continue;
    const std::size_t colon = content.find(": ");
    if (colon == std::string_view::npos)
      throw InputError(path, "line " + std::to_string(line) + " of the NRRD header is not a \"field: value\" line");
    h.fields[toLowerAscii(trimText(content.substr(0, colon)))] = std::string(trimText(content.substr(colon + 2)));
  }
}

// "(x,y,z)" groups: NRRD's vectors.
std::vector<Eigen::Vector3d> parseVectors(const std::string& path, const std::string& field, const std::string& text) {
  std::vector<Eigen::Vector3d> vectors;
  std::size_t pos = 0;
  while (true) {
    const std::size_t open = text.find_first_not_of(" \t", pos);
    if (open == std::string::npos) break;
    if (text.compare(open, 4, "none") == 0)
      throw InputError(path, field + ": an axis without a direction (\"none\") is not supported for a 3-D grid");
    const std::size_t close = text.find(')', open);
    if (text[open] != '(' || close == std::string::npos) throw InputError(path, field + ": expected vectors like (x,y,z)");
    std::string inner = text.substr(open + 1, close - open - 1);
    for (char& c : inner)
      if (c == ',') c = ' ';
    const auto v = parseReals(path, field, inner, 3);
    vectors.emplace_back(v[0], v[1], v[2]);
    pos = close + 1;
  }
  return vectors;
}

// The map from the header's space to RAS.
Eigen::Matrix3d spaceToRas(const std::string& path, const std::string& space) {
  const std::string s = toLowerAscii(space);
  if (s == "right-anterior-superior" || s == "ras" || s == "scanner-xyz" || s == "3d-right-handed" || s == "3d-left-handed")
    return Eigen::Matrix3d::Identity();
  if (s == "left-posterior-superior" || s == "lps") return Eigen::Vector3d(-1, -1, 1).asDiagonal();
  if (s == "left-anterior-superior" || s == "las") return Eigen::Vector3d(-1, 1, 1).asDiagonal();
  throw InputError(path, "space \"" + space + "\" is not supported (expected a 3-D space such as left-posterior-superior)");
}

struct NrrdLayout {
  GridGeometry geometry;
  VoxelEncoding encoding;
  bool gzip = false;
  std::int64_t lineSkip = 0;
  std::int64_t byteSkip = 0;
};

NrrdLayout interpretNrrdHeader(const std::string& path, const NrrdHeader& h) {
  auto required = [&](const char* key) -> const std::string& {
    const std::string* v = h.find({key});
    if (!v) throw InputError(path, std::string("NRRD header has no \"") + key + "\" field");
    return *v;
  };
  NrrdLayout layout;
  const std::string& type = required("type");
  if (!nrrdVoxelType(toLowerAscii(type), layout.encoding.type))
    throw InputError(path, "type \"" + type + "\" is not supported for labels (expected an integer or float type)");
  if (parseInteger(path, "dimension", required("dimension")) != 3)
    throw InputError(path, "dimension is " + required("dimension") + ": only 3-D grids are supported");
  const Index3 dims = parseDims(path, "sizes", required("sizes"));
  checkGridDims(path, dims);

  const std::string encoding = toLowerAscii(required("encoding"));
  if (encoding == "gzip" || encoding == "gz") layout.gzip = true;
  else if (encoding != "raw")
    throw InputError(path, "encoding \"" + encoding + "\" is not supported (expected raw or gzip)");
  if (const std::string* v = h.find({"endian"})) {
    const std::string e = toLowerAscii(*v);
    if (e != "little" && e != "big") throw InputError(path, "endian \"" + *v + "\" is neither little nor big");
    layout.encoding.bigEndian = e == "big";
  } else if (voxelTypeSize(layout.encoding.type) > 1) {
    throw InputError(path, "NRRD header has no \"endian\" field for multi-byte samples");
  }
  if (const std::string* v = h.find({"line skip", "lineskip"})) {
    layout.lineSkip = parseInteger(path, "line skip", *v);
    if (layout.lineSkip < 0) throw InputError(path, "line skip " + *v + " is negative");
  }
  if (const std::string* v = h.find({"byte skip", "byteskip"})) {
    layout.byteSkip = parseInteger(path, "byte skip", *v);
    if (layout.byteSkip < -1 || (layout.byteSkip == -1 && layout.gzip))
      throw InputError(path, "byte skip " + *v + " is not valid for " + encoding + " encoding");
  }

  Eigen::Matrix3d linear = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Matrix3d toRas = Eigen::Matrix3d::Identity();
  if (const std::string* v = h.find({"space"})) toRas = spaceToRas(path, *v);
  else if (const std::string* d = h.find({"space dimension"}); d && parseInteger(path, "space dimension", *d) != 3)
    throw InputError(path, "space dimension is " + *d + ": only 3-D spaces are supported");
  if (const std::string* v = h.find({"space directions"})) {
    const auto axes = parseVectors(path, "space directions", *v);
    if (axes.size() != 3)
      throw InputError(path, "space directions: expected 3 vectors, found " + std::to_string(axes.size()));
    for (int a = 0; a < 3; ++a) linear.col(a) = axes[std::size_t(a)];
  } else if (const std::string* v = h.find({"spacings"})) {
    const auto s = parseReals(path, "spacings", *v, 3);
    for (int a = 0; a < 3; ++a) {
      if (!(s[a] > 0.0))
        throw InputError(path, "spacings: spacing along axis " + std::to_string(a) + " is " + realText(s[a]) + " (must be positive)");
      linear(a, a) = s[a];
    }
  }
  if (const std::string* v = h.find({"space origin"})) {
    const auto o = parseVectors(path, "space origin", *v);
    if (o.size() != 1) throw InputError(path, "space origin: expected one vector (x,y,z)");
    translation = o[0];
  }
  layout.geometry = geometryFromAffine(path, dims, toRas * linear, toRas * translation);
  return layout;
}

// Byte offset just after `lines` newlines of `file` (NRRD's "line skip").
std::uint64_t skipLines(std::FILE* file, std::uint64_t start, std::int64_t lines, const std::string& source) {
  std::fseek(file, long(start), SEEK_SET);
  std::uint64_t offset = start;
  for (std::int64_t n = 0; n < lines;) {
    const int c = std::fgetc(file);
    if (c == EOF) throw InputError(source, "the data file ends within the lines to skip (line skip)");
    ++offset;
    if (c == '\n') ++n;
  }
  return offset;
}

std::unique_ptr<GridSliceReader> openNrrd(const std::string& path) {
  std::FILE* headerFile = openForReading(path, path);
  NrrdHeader header;
  NrrdLayout layout;
  try {
    header = parseNrrdHeader(path, readPrefix(headerFile, kMaxHeaderBytes));
    layout = interpretNrrdHeader(path, header);
  } catch (...) {
    std::fclose(headerFile);
    throw;
  }
  std::FILE* data = headerFile;
  std::uint64_t start = header.headerBytes;
  std::string source = path;
  if (const std::string* name = header.find({"data file", "datafile"})) {
    std::fclose(headerFile);
    const auto words = splitWords(*name);
    if (words.size() != 1 || toLowerAscii(words[0]) == "list" || name->find('%') != std::string::npos)
      throw InputError(path, "data file \"" + *name + "\" (a list of files) is not supported");
    const std::string dataPath = siblingPath(path, *name);
    data = openForReading(dataPath, path);
    start = 0;
    source = path + " (data file " + dataPath + ")";
  } else if (toLowerAscii(std::filesystem::path(path).extension().string()) == ".nhdr") {
    std::fclose(headerFile);
    throw InputError(path, "detached NRRD header has no \"data file\" field");
  }
  try {
    start = skipLines(data, start, layout.lineSkip, source);
    std::uint64_t sampleOffset = 0;
    if (layout.byteSkip == -1) {
      // The samples end the file.
      std::fseek(data, 0, SEEK_END);
      const std::int64_t fileSize = ::ftello(data);
      const std::int64_t sampleBytes = layout.geometry.voxelCount() * voxelTypeSize(layout.encoding.type);
      start = fileSize >= sampleBytes ? std::uint64_t(fileSize - sampleBytes) : start;
    } else if (layout.gzip) {
      sampleOffset = std::uint64_t(layout.byteSkip);  // skipped after decompression
    } else {
      start += std::uint64_t(layout.byteSkip);
    }
    std::FILE* owned = data;
    data = nullptr;
    std::unique_ptr<ByteReader> in = layout.gzip ? inflateReader(owned, start, source) : plainReader(owned, start, source);
    return std::make_unique<StreamSliceReader>(source, layout.geometry, layout.encoding, std::move(in), sampleOffset);
  } catch (...) {
    if (data) std::fclose(data);
    throw;
  }
}

std::string vectorText(const Eigen::Vector3d& v) {
  char buf[128];
  std::snprintf(buf, sizeof(buf), "(%.17g,%.17g,%.17g)", v[0] + 0.0, v[1] + 0.0, v[2] + 0.0);  // + 0.0: no "-0"
  return buf;
}

std::string nrrdHeaderText(const GridGeometry& g, Label maxLabel, const std::string& dataFile) {
  const Eigen::Matrix3d axes = g.direction * g.spacing.asDiagonal();
  std::string h = "NRRD0004\n";
  h += "# Complete NRRD file format specification at:\n";
  h += "# http://teem.sourceforge.net/nrrd/format.html\n";
  h += std::string("type: ") + (storedLabelType(maxLabel) == VoxelType::UInt8 ? "uint8" : "uint16") + "\n";
  h += "dimension: 3\n";
  h += "space: right-anterior-superior\n";
  h += "sizes: " + std::to_string(g.dims[0]) + " " + std::to_string(g.dims[1]) + " " + std::to_string(g.dims[2]) + "\n";
  h += "space directions: " + vectorText(axes.col(0)) + " " + vectorText(axes.col(1)) + " " + vectorText(axes.col(2)) + "\n";
  h += "kinds: domain domain domain\n";
  h += "endian: little\n";
  h += "encoding: gzip\n";
  h += "space origin: " + vectorText(g.direction * g.origin) + "\n";
  if (!dataFile.empty()) h += "data file: " + dataFile + "\n";
  h += "\n";
  return h;
}

}  // namespace

std::unique_ptr<GridSliceReader> openNrrdSlices(const std::string& path) { return openNrrd(path); }

std::unique_ptr<GridSliceWriter> createNrrdSlices(const std::string& path, const GridGeometry& geometry, Label maxLabel) {
  if (toLowerAscii(std::filesystem::path(path).extension().string()) != ".nhdr")
    return std::make_unique<TextHeaderSliceWriter>(path, geometry, maxLabel, nrrdHeaderText(geometry, maxLabel, ""), std::string(),
                                                   SampleCompression::Gzip);
  const std::filesystem::path dataPath = std::filesystem::path(path).replace_extension(".raw.gz");
  return std::make_unique<TextHeaderSliceWriter>(path, geometry, maxLabel,
                                                 nrrdHeaderText(geometry, maxLabel, dataPath.filename().string()),
                                                 dataPath.string(), SampleCompression::Gzip);
}

std::string nrrdDataFile(const std::string& path) {
  const NrrdHeader header = parseNrrdHeader(path, readFilePrefix(path, kMaxHeaderBytes));
  const std::string* name = header.find({"data file", "datafile"});
  return name ? siblingPath(path, *name) : std::string();
}

LabelGrid readNrrd(const std::string& path) {
  const auto reader = openNrrd(path);
  return readAllSlices(*reader);
}

void writeNrrd(const std::string& path, const LabelGrid& grid) {
  const auto writer = createNrrdSlices(path, grid.geometry(), grid.maxLabel());
  writeAllSlices(*writer, grid);
}

}  // namespace vox
