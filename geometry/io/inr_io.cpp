// INRIMAGE-4 (.inr, .inr.gz; the format CGAL's ImageIO and Mesh_3 read): a
// text header padded to a multiple of 256 bytes, then the samples; .inr.gz
// compresses the whole file. Geometry as CGAL's ImageIO writes it: VX/VY/VZ
// spacing, TX/TY/TZ the centre of voxel (0,0,0) in the grid frame and RX/RY/RZ
// the rotation (axis * angle) from the grid frame to the world. A mirrored
// direction, which no rotation can express, is kept in a "#voxmorph-direction"
// comment line that other readers skip.

#include "geometry/ascii_text.h"
#include "geometry/error.h"
#include "geometry/io/grid_stream.h"
#include "geometry/io/header_text.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <map>

namespace vox {

namespace {

constexpr char kMagic[] = "#INRIMAGE-4#{";
constexpr char kEnd[] = "##}";
constexpr char kDirectionComment[] = "#voxmorph-direction=";
constexpr std::size_t kBlock = 256;
constexpr std::size_t kMaxHeaderBlocks = 64;

struct InrHeader {
  std::map<std::string, std::string> fields;  // upper-case key -> value
  std::string direction;                      // the #voxmorph-direction line's value, if any
  std::uint64_t headerBytes = 0;
};

// Reads 256-byte blocks until the one holding the "##}" line.
InrHeader readInrHeader(const std::string& path, ByteReader& in) {
  std::string text;
  std::size_t endLine = std::string::npos;
  while (endLine == std::string::npos) {
    if (text.size() >= kMaxHeaderBlocks * kBlock) throw InputError(path, "INR header does not end (no \"##}\" line)");
    char block[kBlock];
    const std::size_t got = in.read(block, kBlock);
    text.append(block, got);
    const std::size_t magicBytes = std::min(text.size(), sizeof(kMagic) - 1);
    if (got == 0 && text.empty()) throw InputError(path, "the file is empty");
    if (text.compare(0, magicBytes, kMagic, magicBytes) != 0)
      throw InputError(path, "not an INR file (bad magic, expected \"#INRIMAGE-4#{\")");
    for (std::size_t pos = 0; pos < text.size();) {
      const std::size_t nl = text.find('\n', pos);
      if (nl == std::string::npos) break;
      if (text.compare(pos, 3, kEnd) == 0) {
        endLine = pos;
        break;
      }
      pos = nl + 1;
    }
    if (endLine == std::string::npos && got < kBlock)
      throw InputError(path, "INR header is truncated (" + std::to_string(text.size()) + " bytes, no \"##}\" line)");
  }
  InrHeader h;
  h.headerBytes = text.find('\n', endLine) + 1;
  std::size_t pos = text.find('\n') + 1;
  for (int line = 2; pos < endLine; ++line) {
    const std::size_t nl = text.find('\n', pos);
    const std::string_view content = trimText(std::string_view(text).substr(pos, nl - pos));
    pos = nl + 1;
    if (content.empty()) continue;
    if (content.substr(0, sizeof(kDirectionComment) - 1) == kDirectionComment) {
      h.direction = std::string(content.substr(sizeof(kDirectionComment) - 1));
      continue;
    }
    if (content.front() == '#') continue;
    const std::size_t eq = content.find('=');
    if (eq == std::string_view::npos)
      throw InputError(path, "line " + std::to_string(line) + " of the INR header is not a KEY=value field");
    std::string key(trimText(content.substr(0, eq)));
    for (char& c : key) c = char(std::toupper(static_cast<unsigned char>(c)));
    h.fields[key] = std::string(trimText(content.substr(eq + 1)));
  }
  return h;
}

struct InrLayout {
  GridGeometry geometry;
  VoxelEncoding encoding;
};

InrLayout interpretInrHeader(const std::string& path, const InrHeader& h) {
  auto field = [&](const char* key) -> const std::string* {
    const auto it = h.fields.find(key);
    return it == h.fields.end() ? nullptr : &it->second;
  };
  auto required = [&](const char* key) -> const std::string& {
    const std::string* v = field(key);
    if (!v) throw InputError(path, std::string("INR header has no ") + key + " field");
    return *v;
  };
  const Index3 dims{parseInteger(path, "XDIM", required("XDIM")), parseInteger(path, "YDIM", required("YDIM")),
                    parseInteger(path, "ZDIM", required("ZDIM"))};
  checkGridDims(path, dims);
  if (const std::string* v = field("VDIM"); v && parseInteger(path, "VDIM", *v) != 1)
    throw InputError(path, "VDIM is " + *v + ": labels need 1 value per voxel");

  InrLayout layout;
  const std::string type = toLowerAscii(required("TYPE"));
  const std::string& pixsize = required("PIXSIZE");
  const auto sizeWords = splitWords(pixsize);
  if (sizeWords.size() != 2 || sizeWords[1] != "bits") throw InputError(path, "PIXSIZE \"" + pixsize + "\" is not \"<n> bits\"");
  const std::int64_t bits = parseInteger(path, "PIXSIZE", sizeWords[0]);
  const std::map<std::pair<std::string, std::int64_t>, VoxelType> types = {
      {{"unsigned fixed", 8}, VoxelType::UInt8},  {{"unsigned fixed", 16}, VoxelType::UInt16},
      {{"unsigned fixed", 32}, VoxelType::UInt32}, {{"unsigned fixed", 64}, VoxelType::UInt64},
      {{"signed fixed", 8}, VoxelType::Int8},      {{"signed fixed", 16}, VoxelType::Int16},
      {{"signed fixed", 32}, VoxelType::Int32},    {{"signed fixed", 64}, VoxelType::Int64},
      {{"float", 32}, VoxelType::Float32},         {{"float", 64}, VoxelType::Float64},
  };
  const auto it = types.find({type, bits});
  if (it == types.end())
    throw InputError(path, "TYPE=" + required("TYPE") + " with PIXSIZE=" + pixsize + " is not supported for labels");
  layout.encoding.type = it->second;

  if (const std::string* v = field("CPU")) {
    const std::string cpu = toLowerAscii(*v);
    if (cpu == "decm" || cpu == "alpha" || cpu == "pc") layout.encoding.bigEndian = false;
    else if (cpu == "sun" || cpu == "sgi") layout.encoding.bigEndian = true;
    else throw InputError(path, "CPU=" + *v + " is not a known byte order (decm, alpha, pc, sun, sgi)");
  } else if (bits > 8) {
    throw InputError(path, "INR header has no CPU field (byte order) for multi-byte samples");
  }

  Eigen::Vector3d spacing(1, 1, 1), translation(0, 0, 0), rotation(0, 0, 0);
  const char* spacingKeys[] = {"VX", "VY", "VZ"};
  const char* translationKeys[] = {"TX", "TY", "TZ"};
  const char* rotationKeys[] = {"RX", "RY", "RZ"};
  for (int a = 0; a < 3; ++a) {
    if (const std::string* v = field(spacingKeys[a])) {
      spacing[a] = parseReal(path, spacingKeys[a], *v);
      if (!(spacing[a] > 0.0))
        throw InputError(path, std::string(spacingKeys[a]) + "=" + *v + ": voxel spacing must be positive");
    }
    if (const std::string* v = field(translationKeys[a])) translation[a] = parseReal(path, translationKeys[a], *v);
    if (const std::string* v = field(rotationKeys[a])) rotation[a] = parseReal(path, rotationKeys[a], *v);
  }
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();
  if (!h.direction.empty()) {
    const auto d = parseReals(path, "voxmorph-direction", h.direction, 9);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) direction(r, c) = d[std::size_t(r * 3 + c)];
  } else if (rotation.norm() > 0.0) {
    direction = Eigen::AngleAxisd(rotation.norm(), rotation.normalized()).toRotationMatrix();
  }
  layout.geometry = geometryFromAffine(path, dims, direction * spacing.asDiagonal(), direction * translation);
  return layout;
}

std::unique_ptr<GridSliceReader> openInr(const std::string& path) {
  std::FILE* file = openForReading(path, path);
  std::unique_ptr<ByteReader> in = isGzipFile(path) ? inflateReader(file, 0, path) : plainReader(file, 0, path);
  const InrHeader header = readInrHeader(path, *in);
  const InrLayout layout = interpretInrHeader(path, header);
  return std::make_unique<StreamSliceReader>(path, layout.geometry, layout.encoding, std::move(in), header.headerBytes);
}

std::string number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v + 0.0);  // + 0.0: no "-0"
  return buf;
}

std::string inrHeaderText(const GridGeometry& g, Label maxLabel) {
  const bool bytes = storedLabelType(maxLabel) == VoxelType::UInt8;
  std::string h = std::string(kMagic) + "\n";
  h += "XDIM=" + std::to_string(g.dims[0]) + "\n";
  h += "YDIM=" + std::to_string(g.dims[1]) + "\n";
  h += "ZDIM=" + std::to_string(g.dims[2]) + "\n";
  h += "VDIM=1\n";
  h += "TYPE=unsigned fixed\n";
  h += std::string("PIXSIZE=") + (bytes ? "8" : "16") + " bits\n";
  h += "SCALE=2**0\n";
  h += "CPU=decm\n";
  h += "VX=" + number(g.spacing[0]) + "\n";
  h += "VY=" + number(g.spacing[1]) + "\n";
  h += "VZ=" + number(g.spacing[2]) + "\n";
  h += "TX=" + number(g.origin[0]) + "\n";
  h += "TY=" + number(g.origin[1]) + "\n";
  h += "TZ=" + number(g.origin[2]) + "\n";
  if (g.direction.determinant() > 0.0) {
    const Eigen::AngleAxisd r(g.direction);
    const Eigen::Vector3d v = r.axis() * r.angle();
    if (r.angle() != 0.0) h += "RX=" + number(v[0]) + "\nRY=" + number(v[1]) + "\nRZ=" + number(v[2]) + "\n";
  } else {
    h += kDirectionComment;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) h += (r || c ? " " : "") + number(g.direction(r, c));
    h += "\n";
  }
  // Pad with newlines so that "##}\n" ends the header on a 256-byte boundary.
  const std::size_t tail = sizeof(kEnd) - 1 + 1;
  const std::size_t total = (h.size() + tail + kBlock - 1) / kBlock * kBlock;
  h.append(total - tail - h.size(), '\n');
  h += std::string(kEnd) + "\n";
  return h;
}

bool isGzipName(const std::string& path) {
  const std::string s = toLowerAscii(path);
  return s.size() >= 3 && s.compare(s.size() - 3, 3, ".gz") == 0;
}

}  // namespace

std::unique_ptr<GridSliceReader> openInrSlices(const std::string& path) { return openInr(path); }

std::unique_ptr<GridSliceWriter> createInrSlices(const std::string& path, const GridGeometry& geometry, Label maxLabel) {
  return std::make_unique<TextHeaderSliceWriter>(path, geometry, maxLabel, inrHeaderText(geometry, maxLabel), std::string(),
                                                 isGzipName(path) ? SampleCompression::GzipWholeFile : SampleCompression::None);
}

LabelGrid readInr(const std::string& path) {
  const auto reader = openInr(path);
  return readAllSlices(*reader);
}

void writeInr(const std::string& path, const LabelGrid& grid) {
  const auto writer = createInrSlices(path, grid.geometry(), grid.maxLabel());
  writeAllSlices(*writer, grid);
}

}  // namespace vox
