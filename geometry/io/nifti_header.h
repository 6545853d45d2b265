#pragma once
// The NIfTI-1 header check that the label grid reader (nifti_io.cpp) and the
// remesher's sizing grid reader (sizing_grid_io.cpp) share: a single file
// (.nii, .nii.gz) opened as a byte stream, its 348-byte header checked
// completely (magic, 3-D dims within kMaxGridVoxels, sample type, spacing,
// data offset, scaling, the affine: sform, else qform, else pixdim) before
// anything is allocated from it. Internal to geometry/io.

#include "geometry/io/byte_stream.h"
#include "geometry/io/voxel_codec.h"
#include "geometry/label_grid.h"

#include <cstdint>
#include <memory>
#include <string>

namespace vox {

inline constexpr std::uint64_t kNiftiDataOffset = 352;  // 348-byte header + 4-byte extension flag

struct NiftiLayout {
  GridGeometry geometry;
  VoxelEncoding encoding;
  std::uint64_t dataOffset = kNiftiDataOffset;
};

// What a grid's samples are, in the header check's messages ("dim[0] is 2:
// a label grid needs 3 dimensions", "... is not supported for labels").
struct NiftiContent {
  const char* grid;
  const char* values;
};
inline constexpr NiftiContent kNiftiLabels{"label grid", "labels"};
inline constexpr NiftiContent kNiftiSizes{"size grid", "sizes"};

// The file's bytes, gunzipped on the fly when it starts with gzip's magic:
// size() for a plain file, maxSize() deflate's bound for a compressed one.
// Throws InputError(path, "cannot open the file ...").
std::unique_ptr<ByteReader> openNiftiBytes(const std::string& path);

// Reads and checks the header at the start of `in`; throws InputError(path,
// <fault>) for anything a reader cannot use. The caller checks that the
// stream can hold the samples (checkSamplesFit, grid_stream.h) before it
// allocates them.
NiftiLayout parseNiftiHeader(const std::string& path, ByteReader& in, const NiftiContent& content);

}  // namespace vox
