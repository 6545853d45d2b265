// NIfTI-1 single files (.nii, .nii.gz) through Debian's niftilib: znzlib for
// plain and gzip I/O, nifti1_io for header byte swapping and the quaternion
// (qform) conversions. The header is validated completely before any voxel
// memory is allocated, and samples are streamed slice by slice.

// niftilib is built with zlib; declaring it exposes znzptr::zfptr, whose
// gzerror() tells a truncated archive from a corrupt one.
#ifndef HAVE_ZLIB
#define HAVE_ZLIB 1
#endif
#include <nifti1_io.h>
#include <znzlib.h>

#include "geometry/error.h"
#include "geometry/atomic_file.h"
#include "geometry/io/grid_stream.h"
#include "geometry/io/nifti_header.h"

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

namespace vox {

namespace {

static_assert(sizeof(nifti_1_header) == 348, "NIfTI-1 header layout");
// Headers are written in native order and samples in little-endian order.
static_assert(std::endian::native == std::endian::little, "NIfTI writer assumes a little-endian host");

// niftilib reports problems on stderr at its default debug level; errors here
// are reported once, as exceptions.
void quietNiftilib() {
  static std::once_flag once;
  std::call_once(once, [] { nifti_set_debug_level(0); });
}

struct ZnzCloser {
  void operator()(znzptr* f) const { Xznzclose(&f); }
};
using ZnzHandle = std::unique_ptr<znzptr, ZnzCloser>;

// zlib's state of a gzip stream: Z_OK, Z_BUF_ERROR (it ended early) or an
// error, with zlib's message stripped of the "<path>: " it starts with.
int gzipState(znzFile f, const std::string& path, std::string& message) {
  if (!f || !f->withz || !f->zfptr) return Z_OK;
  int code = Z_OK;
  const char* msg = gzerror(f->zfptr, &code);
  message = msg ? msg : "";
  if (message.compare(0, path.size() + 2, path + ": ") == 0) message.erase(0, path.size() + 2);
  return code;
}

class ZnzReader final : public ByteReader {
public:
  ZnzReader(const std::string& path, bool gzip) : path_(path), gzip_(gzip) {
    std::fclose(openForReading(path, path));
    file_.reset(znzopen(path.c_str(), "rb", gzip ? 1 : 0));
    if (!file_) throw InputError(path, std::string("cannot open the file (") + std::strerror(errno) + ")");
    const auto fileBytes = std::int64_t(std::filesystem::file_size(path));
    if (!gzip) size_ = fileBytes;
    // Deflate's largest ratio is 1032:1 (see ByteReader::maxSize).
    maxSize_ = gzip ? (fileBytes + 1) * 1032 : fileBytes;
  }

  std::size_t read(void* dst, std::size_t n) override {
    const std::size_t got = znzread(dst, 1, n, file_.get());
    if (got > n || (got < n && gzip_)) throwIfCorrupt();
    // A short read of a truncated archive is reported by the caller, which
    // knows what was being read.
    return got > n ? 0 : got;
  }
  void seek(std::uint64_t offset) override {
    if (znzseek(file_.get(), znz_off_t(offset), SEEK_SET) < 0) {
      if (gzip_) throwIfCorrupt();
      throw InputError(path_, "voxel data is truncated: the file ends before the voxel data offset " + std::to_string(offset));
    }
  }
  std::int64_t size() const override { return size_; }
  std::int64_t maxSize() const override { return maxSize_; }
  void checkEnd() override {
    if (!gzip_) return;
    // Decode to the end so that zlib verifies the gzip trailer (CRC and length).
    std::vector<char> scratch(std::size_t(1) << 16);
    std::size_t got;
    while ((got = znzread(scratch.data(), 1, scratch.size(), file_.get())) == scratch.size()) {
    }
    std::string message;
    const int state = gzipState(file_.get(), path_, message);
    if (state == Z_BUF_ERROR) throw InputError(path_, "gzip data is truncated (" + message + ")");
    if (state != Z_OK || got > scratch.size()) throwIfCorrupt();
  }

private:
  void throwIfCorrupt() const {
    std::string message;
    const int state = gzipState(file_.get(), path_, message);
    if (state != Z_OK && state != Z_BUF_ERROR) throw InputError(path_, "corrupt gzip data (" + message + ")");
  }

  std::string path_;
  bool gzip_;
  ZnzHandle file_;
  std::int64_t size_ = -1;
  std::int64_t maxSize_ = 0;
};

std::uint32_t swapped32(std::int32_t v) {
  const auto u = std::uint32_t(v);
  return (u >> 24) | ((u >> 8) & 0xff00u) | ((u << 8) & 0xff0000u) | (u << 24);
}

bool niftiVoxelType(short datatype, VoxelType& type) {
  switch (datatype) {
    case DT_UINT8: type = VoxelType::UInt8; return true;
    case DT_INT8: type = VoxelType::Int8; return true;
    case DT_UINT16: type = VoxelType::UInt16; return true;
    case DT_INT16: type = VoxelType::Int16; return true;
    case DT_UINT32: type = VoxelType::UInt32; return true;
    case DT_INT32: type = VoxelType::Int32; return true;
    case DT_UINT64: type = VoxelType::UInt64; return true;
    case DT_INT64: type = VoxelType::Int64; return true;
    case DT_FLOAT32: type = VoxelType::Float32; return true;
    case DT_FLOAT64: type = VoxelType::Float64; return true;
    default: return false;
  }
}

std::string floatText(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

}  // namespace

// Everything is checked here, in the order a reader depends on it, before
// the caller allocates anything from the header.
NiftiLayout parseNiftiHeader(const std::string& path, ByteReader& in, const NiftiContent& content) {
  nifti_1_header h;
  std::memset(&h, 0, sizeof(h));
  const std::size_t got = in.read(&h, sizeof(h));
  if (got != sizeof(h))
    throw InputError(path, "NIfTI header is truncated (" + std::to_string(got) + " of 348 bytes present)");

  bool swapped = false;
  if (h.sizeof_hdr != 348) {
    if (swapped32(h.sizeof_hdr) == 348u) {
      swapped = true;
    } else if (h.sizeof_hdr == 540 || swapped32(h.sizeof_hdr) == 540u) {
      throw InputError(path, "NIfTI-2 files are not supported (only NIfTI-1)");
    } else {
      throw InputError(path, "not a NIfTI-1 file (sizeof_hdr is " + std::to_string(h.sizeof_hdr) + ", expected 348)");
    }
  }
  if (swapped) swap_nifti_header(&h, 1);
  if (std::memcmp(h.magic, "ni1", 4) == 0)
    throw InputError(path, "NIfTI header/image pairs (magic \"ni1\") are not supported; use a single .nii or .nii.gz file");
  if (std::memcmp(h.magic, "n+1", 4) != 0) throw InputError(path, "not a NIfTI-1 file (bad magic, expected \"n+1\")");

  const int rank = h.dim[0];
  if (rank < 3 || rank > 7)
    throw InputError(path, "dim[0] is " + std::to_string(rank) + ": a " + content.grid + " needs 3 dimensions");
  for (int d = 4; d <= rank; ++d)
    if (h.dim[d] != 1)
      throw InputError(path, "dim[" + std::to_string(d) + "] is " + std::to_string(h.dim[d]) +
                                 ": only 3-D grids are supported (extra dimensions must be 1)");
  const Index3 dims{h.dim[1], h.dim[2], h.dim[3]};
  checkGridDims(path, dims);

  NiftiLayout layout;
  if (!niftiVoxelType(h.datatype, layout.encoding.type)) {
    if (!nifti_datatype_is_valid(h.datatype, 1)) throw InputError(path, "datatype " + std::to_string(h.datatype) + " is not a NIfTI-1 type");
    throw InputError(path, "datatype " + std::to_string(h.datatype) + " (" + nifti_datatype_string(h.datatype) +
                               ") is not supported for " + content.values + " (expected an integer or float type)");
  }
  layout.encoding.bigEndian = swapped ? std::endian::native == std::endian::little : std::endian::native == std::endian::big;

  for (int a = 1; a <= 3; ++a)
    if (!std::isfinite(h.pixdim[a]) || h.pixdim[a] <= 0.0f)
      throw InputError(path, "pixdim[" + std::to_string(a) + "] is " + floatText(h.pixdim[a]) +
                                 " (voxel spacing must be finite and positive)");

  // vox_offset 0 is what several writers leave in single files: the data
  // then follows the header and its extension flag.
  const double voxOffset = h.vox_offset;
  if (!std::isfinite(voxOffset) || voxOffset < 0.0 || voxOffset != std::floor(voxOffset) ||
      (voxOffset > 0.0 && voxOffset < double(kNiftiDataOffset)) || voxOffset > 1e15)
    throw InputError(path, "vox_offset " + floatText(voxOffset) + " is not a valid data offset (at least 352 bytes)");
  layout.dataOffset = voxOffset == 0.0 ? kNiftiDataOffset : std::uint64_t(voxOffset);

  // scl_slope 0 or non-finite means "not scaled" (as nibabel and niftilib read it).
  if (std::isfinite(h.scl_slope) && h.scl_slope != 0.0f) {
    if (!std::isfinite(h.scl_inter)) throw InputError(path, "scl_inter is not finite");
    layout.encoding.slope = h.scl_slope;
    layout.encoding.intercept = h.scl_inter;
  }

  // NIfTI's three methods, in order of precedence: sform, qform, pixdim.
  Eigen::Matrix3d linear = Eigen::Matrix3d::Zero();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  if (h.sform_code > 0) {
    const float* rows[3] = {h.srow_x, h.srow_y, h.srow_z};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) linear(r, c) = rows[r][c];
      translation[r] = rows[r][3];
    }
    if (!linear.allFinite() || !translation.allFinite()) throw InputError(path, "the sform (srow_x/y/z) is not finite");
  } else if (h.qform_code > 0) {
    const float q[] = {h.quatern_b, h.quatern_c, h.quatern_d, h.qoffset_x, h.qoffset_y, h.qoffset_z, h.pixdim[0]};
    for (float v : q)
      if (!std::isfinite(v)) throw InputError(path, "the qform (quatern_b/c/d, qoffset_x/y/z) is not finite");
    const mat44 m = nifti_quatern_to_mat44(h.quatern_b, h.quatern_c, h.quatern_d, h.qoffset_x, h.qoffset_y, h.qoffset_z,
                                           h.pixdim[1], h.pixdim[2], h.pixdim[3], h.pixdim[0]);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) linear(r, c) = m.m[r][c];
      translation[r] = m.m[r][3];
    }
  } else {
    linear = Eigen::Vector3d(h.pixdim[1], h.pixdim[2], h.pixdim[3]).asDiagonal();
  }
  layout.geometry = geometryFromAffine(path, dims, linear, translation);
  return layout;
}

std::unique_ptr<ByteReader> openNiftiBytes(const std::string& path) {
  quietNiftilib();
  return std::make_unique<ZnzReader>(path, isGzipFile(path));
}

namespace {

class ZnzWriter final : public ByteWriter {
public:
  ZnzWriter(ZnzHandle& file, const std::string& target) : file_(file), target_(target) {}
  void write(const void* src, std::size_t n) override {
    if (n > 0 && znzwrite(src, 1, n, file_.get()) != n)
      throw RuntimeFailure(target_ + ": write failed (" + std::strerror(errno) + ")");
  }
  void finish() override {}

private:
  ZnzHandle& file_;
  const std::string& target_;
};

bool endsWithGz(const std::string& path) {
  return path.size() >= 3 && (path.compare(path.size() - 3, 3, ".gz") == 0 || path.compare(path.size() - 3, 3, ".GZ") == 0);
}

class NiftiSliceWriter final : public EncodedSliceWriter {
public:
  NiftiSliceWriter(const std::string& path, const GridGeometry& geometry, Label maxLabel)
      : EncodedSliceWriter(path, geometry, maxLabel), file_(path), sink_(znz_, target_) {
    for (int a = 0; a < 3; ++a)
      if (geometry_.dims[a] > std::numeric_limits<short>::max())
        throw RuntimeFailure(target_ + ": grid dimension " + std::to_string(geometry_.dims[a]) +
                             " exceeds NIfTI-1's limit of 32767 voxels per axis");
    const nifti_1_header header = makeHeader();
    // The temporary keeps the target's extension; the gzip choice follows it.
    znz_.reset(znzopen(file_.tempPath().c_str(), "wb", endsWithGz(path) ? 1 : 0));
    if (!znz_) throw RuntimeFailure(target_ + ": cannot create output file (" + std::strerror(errno) + ")");
    const char extension[4] = {0, 0, 0, 0};
    sink_.write(&header, sizeof(header));
    sink_.write(extension, sizeof(extension));
  }
private:
  nifti_1_header makeHeader() const {
    const int dims[8] = {3, int(geometry_.dims[0]), int(geometry_.dims[1]), int(geometry_.dims[2]), 1, 1, 1, 1};
    const int datatype = storedType() == VoxelType::UInt8 ? DT_UINT8 : DT_UINT16;
    nifti_1_header* made = nifti_make_new_header(dims, datatype);
    if (!made) throw std::bad_alloc();
    nifti_1_header h = *made;
    std::free(made);

    h.vox_offset = float(kNiftiDataOffset);
    h.scl_slope = 1.0f;
    h.scl_inter = 0.0f;
    h.xyzt_units = SPACE_TIME_TO_XYZT(NIFTI_UNITS_MM, NIFTI_UNITS_UNKNOWN);
    std::strncpy(h.descrip, "voxmorph label grid", sizeof(h.descrip) - 1);
    for (int a = 0; a < 3; ++a) h.pixdim[a + 1] = float(geometry_.spacing[a]);

    // Both transforms carry the same affine: sform exactly (as floats), qform
    // as the rotation + qfac decomposition niftilib computes from it.
    const Eigen::Matrix4d affine = geometry_.indexToWorld();
    float* rows[3] = {h.srow_x, h.srow_y, h.srow_z};
    mat44 m;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) m.m[r][c] = float(affine(r, c));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) rows[r][c] = m.m[r][c];
    float dx, dy, dz, qfac;
    nifti_mat44_to_quatern(m, &h.quatern_b, &h.quatern_c, &h.quatern_d, &h.qoffset_x, &h.qoffset_y, &h.qoffset_z, &dx, &dy,
                           &dz, &qfac);
    h.pixdim[0] = qfac;
    h.qform_code = NIFTI_XFORM_SCANNER_ANAT;
    h.sform_code = NIFTI_XFORM_SCANNER_ANAT;
    return h;
  }

  ByteWriter& samples() override { return sink_; }
  void commitFiles() override {
    znzFile f = znz_.release();
    const int status = Xznzclose(&f);
    if (status != 0) throw RuntimeFailure(target_ + ": write failed while closing the file");
    file_.commit();
  }

  AtomicFile file_;
  ZnzHandle znz_;
  ZnzWriter sink_;
};

}  // namespace

std::unique_ptr<GridSliceReader> openNiftiSlices(const std::string& path) {
  std::unique_ptr<ByteReader> in = openNiftiBytes(path);
  const NiftiLayout layout = parseNiftiHeader(path, *in, kNiftiLabels);
  return std::make_unique<StreamSliceReader>(path, layout.geometry, layout.encoding, std::move(in), layout.dataOffset);
}

std::unique_ptr<GridSliceWriter> createNiftiSlices(const std::string& path, const GridGeometry& geometry, Label maxLabel) {
  quietNiftilib();
  return std::make_unique<NiftiSliceWriter>(path, geometry, maxLabel);
}

LabelGrid readNifti(const std::string& path) {
  const auto reader = openNiftiSlices(path);
  return readAllSlices(*reader);
}

void writeNifti(const std::string& path, const LabelGrid& grid) {
  const auto writer = createNiftiSlices(path, grid.geometry(), grid.maxLabel());
  writeAllSlices(*writer, grid);
}

}  // namespace vox
