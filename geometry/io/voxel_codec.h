#pragma once
// Sample types found in grid files and their conversion to and from labels.
// Internal to geometry/io.

#include "geometry/label_grid.h"

#include <cstdint>
#include <string>

namespace vox {

enum class VoxelType { UInt8, Int8, UInt16, Int16, UInt32, Int32, UInt64, Int64, Float32, Float64 };

int voxelTypeSize(VoxelType type);
const char* voxelTypeName(VoxelType type);

// How stored samples become labels: byte order, then the linear scaling
// label = slope * sample + intercept (NIfTI's scl_slope / scl_inter; identity
// for the other formats).
struct VoxelEncoding {
  VoxelType type = VoxelType::UInt8;
  bool bigEndian = false;
  double slope = 1.0;
  double intercept = 0.0;

  bool scaled() const { return slope != 1.0 || intercept != 0.0; }
};

// Converts `count` samples in file byte order (`raw`, count * voxelTypeSize
// bytes, byte-swapped in place when needed) into labels. `firstVoxel` is the
// linear index of raw's first sample in grid `g`. Every value must be an
// integer in 0..65535; the first one that is not throws
// InputError(source, "voxel <index> (i, j, k) holds <value> ...").
void decodeLabels(const std::string& source, const GridGeometry& g, const VoxelEncoding& encoding, char* raw,
                  std::int64_t count, std::int64_t firstVoxel, Label* out);

// Converts `count` samples in file byte order (byte-swapped in place when
// needed) into real values slope * sample + intercept. A value beyond
// float's range becomes an infinity of its sign (for the caller's checks to
// refuse), NaN stays NaN.
void decodeValues(const VoxelEncoding& encoding, char* raw, std::int64_t count, float* out);

// The type writers store: UInt8 when every label fits, UInt16 otherwise.
VoxelType storedLabelType(Label maxLabel);

// Writes `count` labels as little-endian UInt8 or UInt16 samples into out
// (count * voxelTypeSize(type) bytes). Returns false, writing nothing more,
// at the first label above 255 when type is UInt8.
bool encodeLabels(const Label* in, std::int64_t count, VoxelType type, char* out);

}  // namespace vox
