#include "geometry/io/grid_stream.h"

#include "geometry/error.h"
#include "geometry/progress.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace vox {

namespace {
// Samples converted per step: bounds the scratch buffer whatever the slice size.
constexpr std::int64_t kChunkSamples = std::int64_t(1) << 20;
}  // namespace

void checkGridDims(const std::string& source, const Index3& dims) {
  for (int a = 0; a < 3; ++a)
    if (dims[a] <= 0)
      throw InputError(source, "grid dimension " + std::to_string(a) + " is " + std::to_string(dims[a]) + " (must be positive)");
  std::int64_t n = 1;
  for (int a = 0; a < 3; ++a) {
    if (dims[a] > kMaxGridVoxels / n)
      throw InputError(source, "grid dimensions " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                                   std::to_string(dims[2]) + " exceed the largest supported grid (" +
                                   std::to_string(kMaxGridVoxels) + " voxels)");
    n *= dims[a];
  }
}

GridGeometry geometryFromAffine(const std::string& source, const Index3& dims, const Eigen::Matrix3d& linear,
                                const Eigen::Vector3d& translation) {
  if (!linear.allFinite() || !translation.allFinite()) throw InputError(source, "the voxel-to-world transform is not finite");
  GridGeometry g;
  g.dims = dims;
  Eigen::Matrix3d direction;
  for (int a = 0; a < 3; ++a) {
    g.spacing[a] = linear.col(a).norm();
    if (!(g.spacing[a] > 0.0) || !std::isfinite(g.spacing[a]))
      throw InputError(source, "voxel axis " + std::to_string(a) + " has zero length in the voxel-to-world transform");
    direction.col(a) = linear.col(a) / g.spacing[a];
  }
  const double offOrthonormal = (direction.transpose() * direction - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (offOrthonormal > 1e-4)
    throw InputError(source, "the voxel axes are not orthogonal (a sheared voxel-to-world transform cannot describe a label grid)");
  // Files store the affine in float or decimal text: snap to the nearest
  // orthonormal matrix (polar decomposition) so the error does not grow.
  if (offOrthonormal > 1e-12) {
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(direction, Eigen::ComputeFullU | Eigen::ComputeFullV);
    direction = svd.matrixU() * svd.matrixV().transpose();
  }
  g.direction = direction;
  g.origin = direction.transpose() * translation;
  g.validate(source);
  return g;
}

Eigen::Matrix3d flipLpsRas(const Eigen::Matrix3d& direction) {
  Eigen::Matrix3d d = direction;
  d.row(0) = -d.row(0);
  d.row(1) = -d.row(1);
  return d;
}

void checkSamplesFit(const std::string& source, const GridGeometry& geometry, VoxelType type, const ByteReader& data,
                     std::uint64_t dataOffset) {
  const std::int64_t needed = geometry.voxelCount() * voxelTypeSize(type);
  const std::int64_t size = data.size();
  if (size >= 0 && (std::uint64_t(size) < dataOffset || std::uint64_t(size) - dataOffset < std::uint64_t(needed))) {
    const std::int64_t present = std::uint64_t(size) > dataOffset ? size - std::int64_t(dataOffset) : 0;
    throw InputError(source, "voxel data is truncated: " + std::to_string(geometry.dims[0]) + " x " +
                                 std::to_string(geometry.dims[1]) + " x " + std::to_string(geometry.dims[2]) + " " +
                                 voxelTypeName(type) + " samples need " + std::to_string(needed) + " bytes from offset " +
                                 std::to_string(dataOffset) + ", the file holds " + std::to_string(present));
  }
  const std::int64_t bound = data.maxSize();
  if (size < 0 && (std::uint64_t(bound) < dataOffset || std::uint64_t(bound) - dataOffset < std::uint64_t(needed)))
    throw InputError(source, "voxel data is truncated: " + std::to_string(geometry.dims[0]) + " x " +
                                 std::to_string(geometry.dims[1]) + " x " + std::to_string(geometry.dims[2]) + " " +
                                 voxelTypeName(type) + " samples need " + std::to_string(needed) +
                                 " bytes, the compressed data can decode to at most " + std::to_string(bound) +
                                 " (deflate's largest ratio is 1032:1)");
}

StreamSliceReader::StreamSliceReader(std::string source, const GridGeometry& geometry, const VoxelEncoding& encoding,
                                     std::unique_ptr<ByteReader> data, std::uint64_t dataOffset)
    : source_(std::move(source)), geometry_(geometry), encoding_(encoding), data_(std::move(data)), dataOffset_(dataOffset) {
  geometry_.validate(source_);
  checkSamplesFit(source_, geometry_, encoding_.type, *data_, dataOffset_);
  data_->seek(dataOffset_);
}

void StreamSliceReader::readSlices(std::int64_t k0, std::int64_t count, Label* out) {
  const std::int64_t nz = geometry_.dims[2];
  if (k0 < 0 || count < 0 || k0 + count > nz)
    throw RuntimeFailure(source_ + ": slices " + std::to_string(k0) + ".." + std::to_string(k0 + count - 1) +
                         " requested from a grid of " + std::to_string(nz));
  const int size = voxelTypeSize(encoding_.type);
  const std::int64_t sliceVoxels = geometry_.sliceVoxels();
  if (k0 != nextSlice_) data_->seek(dataOffset_ + std::uint64_t(k0 * sliceVoxels * size));
  const std::int64_t first = k0 * sliceVoxels;
  const std::int64_t total = count * sliceVoxels;
  for (std::int64_t done = 0; done < total;) {
    const std::int64_t n = std::min(kChunkSamples, total - done);
    buffer_.resize(std::size_t(n * size));
    const std::size_t got = data_->read(buffer_.data(), buffer_.size());
    if (got != buffer_.size()) {
      const std::int64_t missing = first + done + std::int64_t(got) / size;
      throw InputError(source_, "voxel data is truncated: it ends at voxel " + std::to_string(missing) + " of " +
                                    std::to_string(geometry_.voxelCount()) + " (slice " + std::to_string(missing / sliceVoxels) +
                                    " of " + std::to_string(nz) + ")");
    }
    decodeLabels(source_, geometry_, encoding_, buffer_.data(), n, first + done, out + done);
    done += n;
  }
  nextSlice_ = k0 + count;
  if (nextSlice_ == nz) data_->checkEnd();
}

EncodedSliceWriter::EncodedSliceWriter(std::string target, const GridGeometry& geometry, Label maxLabel)
    : target_(std::move(target)), geometry_(geometry), type_(storedLabelType(maxLabel)), maxLabel_(maxLabel) {
  geometry_.validate(target_);
}

void EncodedSliceWriter::writeSlices(const Label* in, std::int64_t count) {
  if (count < 0 || slicesWritten_ + count > geometry_.dims[2])
    throw RuntimeFailure(target_ + ": " + std::to_string(slicesWritten_ + count) + " slices written to a grid of " +
                         std::to_string(geometry_.dims[2]));
  const int size = voxelTypeSize(type_);
  const std::int64_t total = count * geometry_.sliceVoxels();
  for (std::int64_t done = 0; done < total;) {
    const std::int64_t n = std::min(kChunkSamples, total - done);
    buffer_.resize(std::size_t(n * size));
    if (!encodeLabels(in + done, n, type_, buffer_.data())) {
      const Label* bad = std::find_if(in + done, in + done + n, [this](Label l) { return l > maxLabel_; });
      throw RuntimeFailure(target_ + ": label " + std::to_string(*bad) + " exceeds the declared maximum label " +
                           std::to_string(maxLabel_));
    }
    samples().write(buffer_.data(), buffer_.size());
    done += n;
  }
  slicesWritten_ += count;
}

void EncodedSliceWriter::commit() {
  if (slicesWritten_ != geometry_.dims[2])
    throw RuntimeFailure(target_ + ": only " + std::to_string(slicesWritten_) + " of " + std::to_string(geometry_.dims[2]) +
                         " slices were written");
  commitFiles();
}

TextHeaderSliceWriter::TextHeaderSliceWriter(const std::string& path, const GridGeometry& geometry, Label maxLabel,
                                             const std::string& header, const std::string& dataPath,
                                             SampleCompression compression)
    : EncodedSliceWriter(path, geometry, maxLabel), headerFile_(path) {
  headerOut_ = stdioWriter(headerFile_.openStdio(), path);
  if (compression == SampleCompression::GzipWholeFile) {
    deflate_ = deflateWriter(*headerOut_, DeflateWrapper::Gzip, path);
    deflate_->write(header.data(), header.size());
    sink_ = deflate_.get();
    return;
  }
  headerOut_->write(header.data(), header.size());
  ByteWriter* base = headerOut_.get();
  if (!dataPath.empty()) {
    dataFile_ = std::make_unique<AtomicFile>(dataPath);
    dataOut_ = stdioWriter(dataFile_->openStdio(), dataPath);
    base = dataOut_.get();
  }
  if (compression == SampleCompression::Gzip) {
    deflate_ = deflateWriter(*base, DeflateWrapper::Gzip, dataPath.empty() ? path : dataPath);
    base = deflate_.get();
  }
  sink_ = base;
}

void TextHeaderSliceWriter::commitFiles() {
  sink_->finish();
  if (!dataFile_) {
    headerFile_.commit();
    return;
  }
  dataFile_->commit();
  try {
    headerFile_.commit();
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(dataFile_->target(), ec);
    throw;
  }
}

LabelGrid readAllSlices(GridSliceReader& reader) {
  LabelGrid grid(reader.geometry());
  const std::int64_t nz = grid.dims()[2];
  const std::int64_t sliceVoxels = grid.geometry().sliceVoxels();
  ProgressCounter progress("read grid", double(nz));
  for (std::int64_t k = 0; k < nz; ++k) {
    reader.readSlices(k, 1, grid.data() + k * sliceVoxels);
    progress.advance();
  }
  progress.finish();
  return grid;
}

void writeAllSlices(GridSliceWriter& writer, const LabelGrid& grid) {
  const std::int64_t nz = grid.dims()[2];
  const std::int64_t sliceVoxels = grid.geometry().sliceVoxels();
  ProgressCounter progress("write grid", double(nz));
  for (std::int64_t k = 0; k < nz; ++k) {
    writer.writeSlices(grid.data() + k * sliceVoxels, 1);
    progress.advance();
  }
  writer.commit();
  progress.finish();
}

}  // namespace vox
