#pragma once
// What the grid formats share once a header is parsed: turning a file's
// affine into a GridGeometry, streaming samples slice by slice into labels,
// and encoding label slices into a format's output stream. Internal to
// geometry/io; each format file provides the open/create functions below.

#include "geometry/atomic_file.h"
#include "geometry/io/byte_stream.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/voxel_codec.h"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vox {

// Throws InputError(source, ...) unless every dimension is positive and their
// product is at most kMaxGridVoxels (checked without overflow). Call before
// anything is allocated from a header.
void checkGridDims(const std::string& source, const Index3& dims);

// Geometry of a grid whose voxel (i,j,k) sits at world = linear * (i,j,k) +
// translation: spacing = column norms of `linear`, direction = its normalized
// columns (made exactly orthonormal when rounding in the file left them
// slightly off), origin = direction^T * translation, so that indexToWorld()
// reproduces the affine. Throws InputError for degenerate or sheared affines.
GridGeometry geometryFromAffine(const std::string& source, const Index3& dims, const Eigen::Matrix3d& linear,
                                const Eigen::Vector3d& translation);

// ITK's MetaImage world is LPS, NIfTI's is RAS; GridGeometry::direction maps
// to RAS. Negating the first two rows of a direction converts between them
// (the grid-frame origin and spacing do not change).
Eigen::Matrix3d flipLpsRas(const Eigen::Matrix3d& direction);

// Throws InputError(source, "voxel data is truncated: ...") unless `data`
// can hold the samples of `geometry` from byte `dataOffset` on: a plain
// file's size, a compressed stream's maxSize(). Call before the samples are
// allocated.
void checkSamplesFit(const std::string& source, const GridGeometry& geometry, VoxelType type, const ByteReader& data,
                     std::uint64_t dataOffset);

// Reads samples from `data`, where voxel 0 starts at byte `dataOffset`, and
// converts them to labels. For plain files the length is checked up front.
class StreamSliceReader final : public GridSliceReader {
public:
  StreamSliceReader(std::string source, const GridGeometry& geometry, const VoxelEncoding& encoding,
                    std::unique_ptr<ByteReader> data, std::uint64_t dataOffset);
  const GridGeometry& geometry() const override { return geometry_; }
  void readSlices(std::int64_t k0, std::int64_t count, Label* out) override;

private:
  std::string source_;
  GridGeometry geometry_;
  VoxelEncoding encoding_;
  std::unique_ptr<ByteReader> data_;
  std::uint64_t dataOffset_;
  std::int64_t nextSlice_ = 0;
  std::vector<char> buffer_;
};

// Encodes label slices into the stream a format provides. Formats derive from
// it, write their header in the constructor and finish their files in
// commitFiles(); their AtomicFile members remove the temporaries otherwise.
class EncodedSliceWriter : public GridSliceWriter {
public:
  void writeSlices(const Label* in, std::int64_t count) final;
  void commit() final;

protected:
  EncodedSliceWriter(std::string target, const GridGeometry& geometry, Label maxLabel);
  VoxelType storedType() const { return type_; }
  std::int64_t sampleBytes() const { return geometry_.voxelCount() * voxelTypeSize(type_); }
  virtual ByteWriter& samples() = 0;
  virtual void commitFiles() = 0;

  const std::string target_;
  const GridGeometry geometry_;

private:
  VoxelType type_;
  Label maxLabel_;
  std::int64_t slicesWritten_ = 0;
  std::vector<char> buffer_;
};

// Formats whose header is text known before the samples (MetaImage, NRRD,
// INR): the header file, and the data file when samples live apart (.mhd +
// .raw, .nhdr + .raw.gz). Nothing appears under the final names before commit.
enum class SampleCompression {
  None,
  Gzip,           // the samples are one gzip stream
  GzipWholeFile,  // header and samples together (.inr.gz)
};
class TextHeaderSliceWriter final : public EncodedSliceWriter {
public:
  // `dataPath` empty: samples follow the header in the same file.
  TextHeaderSliceWriter(const std::string& path, const GridGeometry& geometry, Label maxLabel, const std::string& header,
                        const std::string& dataPath, SampleCompression compression);

private:
  ByteWriter& samples() override { return *sink_; }
  void commitFiles() override;

  AtomicFile headerFile_;
  std::unique_ptr<AtomicFile> dataFile_;
  std::unique_ptr<ByteWriter> headerOut_;
  std::unique_ptr<ByteWriter> dataOut_;
  std::unique_ptr<ByteWriter> deflate_;
  ByteWriter* sink_ = nullptr;
};

// The whole grid through a slice reader / writer (with progress).
LabelGrid readAllSlices(GridSliceReader& reader);
void writeAllSlices(GridSliceWriter& writer, const LabelGrid& grid);

// Per-format slice access, dispatched by openGridSlices / createGridSlices.
std::unique_ptr<GridSliceReader> openNiftiSlices(const std::string& path);
std::unique_ptr<GridSliceReader> openMetaImageSlices(const std::string& path);
std::unique_ptr<GridSliceReader> openNrrdSlices(const std::string& path);
std::unique_ptr<GridSliceReader> openInrSlices(const std::string& path);
std::unique_ptr<GridSliceWriter> createNiftiSlices(const std::string& path, const GridGeometry& geometry, Label maxLabel);
// .mha: uncompressed samples after the header; .mhd: header + .raw file.
std::unique_ptr<GridSliceWriter> createMetaImageSlices(const std::string& path, const GridGeometry& geometry, Label maxLabel);
std::unique_ptr<GridSliceWriter> createNrrdSlices(const std::string& path, const GridGeometry& geometry, Label maxLabel);
std::unique_ptr<GridSliceWriter> createInrSlices(const std::string& path, const GridGeometry& geometry, Label maxLabel);

// The detached data file a header names (.mhd's ElementDataFile, .nhdr's
// "data file"), resolved beside the header; "" when the samples follow the
// header in the same file.
std::string metaImageDataFile(const std::string& path);
std::string nrrdDataFile(const std::string& path);

}  // namespace vox
