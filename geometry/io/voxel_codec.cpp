#include "geometry/io/voxel_codec.h"

#include "geometry/error.h"

#include <algorithm>
#include <type_traits>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

namespace vox {

namespace {

constexpr double kMaxLabelValue = double(std::numeric_limits<Label>::max());

template <class T>
T loadSample(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

void swapBytes(char* raw, std::int64_t count, int size) {
  for (std::int64_t n = 0; n < count; ++n, raw += size) std::reverse(raw, raw + size);
}

std::string formatValue(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

[[noreturn]] void badVoxel(const std::string& source, const GridGeometry& g, std::int64_t index, const std::string& value,
                           const VoxelEncoding& encoding) {
  const Index3 ijk = g.ijk(index);
  std::string fault = "voxel " + std::to_string(index) + " (i " + std::to_string(ijk[0]) + ", j " + std::to_string(ijk[1]) +
                      ", k " + std::to_string(ijk[2]) + ") holds " + value;
  if (encoding.scaled()) fault += " after scaling by slope " + formatValue(encoding.slope) + " and intercept " + formatValue(encoding.intercept);
  fault += ", which is not a label (an integer in 0..65535)";
  throw InputError(source, fault);
}

// Integer samples without scaling: exact comparisons, no detour through double
// (64-bit values beyond 2^53 would round).
template <class T>
void decodeIntegers(const std::string& source, const GridGeometry& g, const VoxelEncoding& encoding, const char* raw,
                    std::int64_t count, std::int64_t firstVoxel, Label* out) {
  for (std::int64_t n = 0; n < count; ++n) {
    const T v = loadSample<T>(raw + n * std::int64_t(sizeof(T)));
    if constexpr (std::is_signed_v<T>) {
      if (v < 0 || std::int64_t(v) > std::int64_t(std::numeric_limits<Label>::max()))
        badVoxel(source, g, firstVoxel + n, std::to_string(v), encoding);
    } else {
      if (std::uint64_t(v) > std::uint64_t(std::numeric_limits<Label>::max()))
        badVoxel(source, g, firstVoxel + n, std::to_string(v), encoding);
    }
    out[n] = Label(v);
  }
}

template <class T>
void decodeReals(const std::string& source, const GridGeometry& g, const VoxelEncoding& encoding, const char* raw,
                 std::int64_t count, std::int64_t firstVoxel, Label* out) {
  for (std::int64_t n = 0; n < count; ++n) {
    const double v = double(loadSample<T>(raw + n * std::int64_t(sizeof(T)))) * encoding.slope + encoding.intercept;
    if (!(v >= 0.0 && v <= kMaxLabelValue) || v != std::floor(v)) badVoxel(source, g, firstVoxel + n, formatValue(v), encoding);
    out[n] = Label(v);
  }
}

template <class T>
void decodeRealValues(const VoxelEncoding& encoding, const char* raw, std::int64_t count, float* out) {
  constexpr double kMaxFloat = double(std::numeric_limits<float>::max());
  for (std::int64_t n = 0; n < count; ++n) {
    const double v = double(loadSample<T>(raw + n * std::int64_t(sizeof(T)))) * encoding.slope + encoding.intercept;
    constexpr float kInfinity = std::numeric_limits<float>::infinity();
    out[n] = std::abs(v) > kMaxFloat ? (v > 0.0 ? kInfinity : -kInfinity) : float(v);
  }
}

template <class T>
void decodeAs(const std::string& source, const GridGeometry& g, const VoxelEncoding& encoding, const char* raw,
              std::int64_t count, std::int64_t firstVoxel, Label* out) {
  if constexpr (std::is_integral_v<T>) {
    if (!encoding.scaled()) return decodeIntegers<T>(source, g, encoding, raw, count, firstVoxel, out);
  }
  decodeReals<T>(source, g, encoding, raw, count, firstVoxel, out);
}

}  // namespace

int voxelTypeSize(VoxelType type) {
  switch (type) {
    case VoxelType::UInt8:
    case VoxelType::Int8: return 1;
    case VoxelType::UInt16:
    case VoxelType::Int16: return 2;
    case VoxelType::UInt32:
    case VoxelType::Int32:
    case VoxelType::Float32: return 4;
    case VoxelType::UInt64:
    case VoxelType::Int64:
    case VoxelType::Float64: return 8;
  }
  return 1;
}

const char* voxelTypeName(VoxelType type) {
  switch (type) {
    case VoxelType::UInt8: return "uint8";
    case VoxelType::Int8: return "int8";
    case VoxelType::UInt16: return "uint16";
    case VoxelType::Int16: return "int16";
    case VoxelType::UInt32: return "uint32";
    case VoxelType::Int32: return "int32";
    case VoxelType::UInt64: return "uint64";
    case VoxelType::Int64: return "int64";
    case VoxelType::Float32: return "float32";
    case VoxelType::Float64: return "float64";
  }
  return "?";
}

void decodeLabels(const std::string& source, const GridGeometry& g, const VoxelEncoding& encoding, char* raw,
                  std::int64_t count, std::int64_t firstVoxel, Label* out) {
  const int size = voxelTypeSize(encoding.type);
  if (size > 1 && encoding.bigEndian != (std::endian::native == std::endian::big)) swapBytes(raw, count, size);
  switch (encoding.type) {
    case VoxelType::UInt8: return decodeAs<std::uint8_t>(source, g, encoding, raw, count, firstVoxel, out);
    case VoxelType::Int8: return decodeAs<std::int8_t>(source, g, encoding, raw, count, firstVoxel, out);
    case VoxelType::UInt16: return decodeAs<std::uint16_t>(source, g, encoding, raw, count, firstVoxel, out);
    case VoxelType::Int16: return decodeAs<std::int16_t>(source, g, encoding, raw, count, firstVoxel, out);
    case VoxelType::UInt32: return decodeAs<std::uint32_t>(source, g, encoding, raw, count, firstVoxel, out);
    case VoxelType::Int32: return decodeAs<std::int32_t>(source, g, encoding, raw, count, firstVoxel, out);
    case VoxelType::UInt64: return decodeAs<std::uint64_t>(source, g, encoding, raw, count, firstVoxel, out);
    case VoxelType::Int64: return decodeAs<std::int64_t>(source, g, encoding, raw, count, firstVoxel, out);
    case VoxelType::Float32: return decodeAs<float>(source, g, encoding, raw, count, firstVoxel, out);
    case VoxelType::Float64: return decodeAs<double>(source, g, encoding, raw, count, firstVoxel, out);
  }
}

void decodeValues(const VoxelEncoding& encoding, char* raw, std::int64_t count, float* out) {
  const int size = voxelTypeSize(encoding.type);
  if (size > 1 && encoding.bigEndian != (std::endian::native == std::endian::big)) swapBytes(raw, count, size);
  switch (encoding.type) {
    case VoxelType::UInt8: return decodeRealValues<std::uint8_t>(encoding, raw, count, out);
    case VoxelType::Int8: return decodeRealValues<std::int8_t>(encoding, raw, count, out);
    case VoxelType::UInt16: return decodeRealValues<std::uint16_t>(encoding, raw, count, out);
    case VoxelType::Int16: return decodeRealValues<std::int16_t>(encoding, raw, count, out);
    case VoxelType::UInt32: return decodeRealValues<std::uint32_t>(encoding, raw, count, out);
    case VoxelType::Int32: return decodeRealValues<std::int32_t>(encoding, raw, count, out);
    case VoxelType::UInt64: return decodeRealValues<std::uint64_t>(encoding, raw, count, out);
    case VoxelType::Int64: return decodeRealValues<std::int64_t>(encoding, raw, count, out);
    case VoxelType::Float32: return decodeRealValues<float>(encoding, raw, count, out);
    case VoxelType::Float64: return decodeRealValues<double>(encoding, raw, count, out);
  }
}

VoxelType storedLabelType(Label maxLabel) { return maxLabel <= 255 ? VoxelType::UInt8 : VoxelType::UInt16; }

bool encodeLabels(const Label* in, std::int64_t count, VoxelType type, char* out) {
  if (type == VoxelType::UInt8) {
    for (std::int64_t n = 0; n < count; ++n) {
      if (in[n] > 255) return false;
      out[n] = char(std::uint8_t(in[n]));
    }
    return true;
  }
  for (std::int64_t n = 0; n < count; ++n) {
    out[2 * n] = char(std::uint8_t(in[n] & 0xff));
    out[2 * n + 1] = char(std::uint8_t(in[n] >> 8));
  }
  return true;
}

}  // namespace vox
