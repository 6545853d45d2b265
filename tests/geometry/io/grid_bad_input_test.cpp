// Bad input for every grid reader: each case must throw InputError whose
// message names the file and the fault -- never crash, never allocate from a
// header that has not been checked (dims that overflow are tiny files here).

#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "tests/geometry/io/grid_test_grids.h"
#include "tests/support/test_environment.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <limits>

namespace vox {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

struct BadInput {
  std::string name;
  // Writes the files into the directory; returns the path to read.
  std::function<std::string(const std::string& dir)> make;
  std::string fault;
};

std::string put(const std::string& dir, const std::string& name, const std::string& bytes) {
  test::writeBytes(dir + "/" + name, bytes);
  return dir + "/" + name;
}

template <class T>
std::string samples(std::initializer_list<T> values, std::size_t count = 24) {
  std::string s;
  for (std::size_t n = 0; n < count; ++n) s += test::bytesOf(n < values.size() ? *(values.begin() + n) : T(1));
  return s;
}
// 24 voxels (4 x 3 x 2) of value 1, with the listed values first.
std::string u8s(std::initializer_list<std::uint8_t> v = {}) { return samples<std::uint8_t>(v); }

// A file written by our writer, then cut or damaged.
std::string writtenThen(const std::string& dir, const std::string& name, const std::function<void(std::string&)>& damage) {
  const std::string path = dir + "/" + name;
  writeGrid(path, test::makeTestGrid(40000));
  std::string bytes = test::readBytes(path);
  damage(bytes);
  test::writeBytes(path, bytes);
  return path;
}
std::function<void(std::string&)> keepFirst(std::size_t n) {
  return [n](std::string& b) { b.resize(n); };
}
std::function<void(std::string&)> dropLast(std::size_t n) {
  return [n](std::string& b) { b.resize(b.size() - n); };
}
std::function<void(std::string&)> keepFraction(double f) {
  return [f](std::string& b) { b.resize(std::size_t(double(b.size()) * f)); };
}
// Flips a byte of a compressed stream's checksum (gzip: CRC-32 then length;
// zlib: Adler-32 last).
std::function<void(std::string&)> flipFromEnd(std::size_t n) {
  return [n](std::string& b) { b[b.size() - n] = char(b[b.size() - n] ^ 0x5a); };
}

std::string nifti(const std::string& dir, const std::function<void(test::NiftiFields&)>& edit, const std::string& data = u8s(),
                  const std::string& name = "bad.nii") {
  test::NiftiFields f;
  edit(f);
  return put(dir, name, test::niftiHeader(f) + data);
}
const float kNaN = std::numeric_limits<float>::quiet_NaN();

std::vector<BadInput> niftiCases() {
  return {
      {"nifti_empty_file", [](auto& d) { return put(d, "bad.nii", ""); }, "NIfTI header is truncated (0 of 348 bytes present)"},
      {"nifti_truncated_header", [](auto& d) { return put(d, "bad.nii", test::niftiHeader({}).substr(0, 100)); },
       "NIfTI header is truncated (100 of 348 bytes present)"},
      {"nifti_truncated_data", [](auto& d) { return put(d, "bad.nii", test::niftiHeader({}) + u8s().substr(0, 10)); },
       "voxel data is truncated"},
      {"nifti_gz_truncated_header", [](auto& d) { return writtenThen(d, "bad.nii.gz", keepFirst(20)); }, "NIfTI header is truncated"},
      {"nifti_gz_truncated_data", [](auto& d) { return writtenThen(d, "bad.nii.gz", keepFraction(0.6)); }, "voxel data is truncated"},
      {"nifti_gz_truncated_trailer", [](auto& d) { return writtenThen(d, "bad.nii.gz", dropLast(3)); }, "gzip data is truncated"},
      {"nifti_gz_bad_crc", [](auto& d) { return writtenThen(d, "bad.nii.gz", flipFromEnd(6)); },
       "corrupt gzip data (incorrect data check)"},
      {"nifti_bad_magic", [](auto& d) { return nifti(d, [](auto& f) { std::memcpy(f.magic, "xyz", 4); }); },
       "not a NIfTI-1 file (bad magic"},
      {"nifti_pair_magic", [](auto& d) { return nifti(d, [](auto& f) { std::memcpy(f.magic, "ni1", 4); }); },
       "header/image pairs"},
      {"nifti_bad_sizeof_hdr", [](auto& d) { return nifti(d, [](auto& f) { f.sizeofHdr = 1000; }); },
       "not a NIfTI-1 file (sizeof_hdr is 1000"},
      {"nifti2", [](auto& d) { return nifti(d, [](auto& f) { f.sizeofHdr = 540; }); }, "NIfTI-2 files are not supported"},
      {"nifti_dims_exceed_limit", [](auto& d) { return nifti(d, [](auto& f) { f.dim[1] = f.dim[2] = f.dim[3] = 32767; }); },
       "grid dimensions 32767 x 32767 x 32767 exceed the largest supported grid"},
      {"nifti_zero_dim", [](auto& d) { return nifti(d, [](auto& f) { f.dim[2] = 0; }); }, "grid dimension 1 is 0"},
      {"nifti_negative_dim", [](auto& d) { return nifti(d, [](auto& f) { f.dim[3] = -4; }); }, "grid dimension 2 is -4"},
      {"nifti_4d", [](auto& d) { return nifti(d, [](auto& f) { f.dim[0] = 4, f.dim[4] = 3; }); }, "dim[4] is 3"},
      {"nifti_2d", [](auto& d) { return nifti(d, [](auto& f) { f.dim[0] = 2; }); }, "dim[0] is 2"},
      {"nifti_negative_spacing", [](auto& d) { return nifti(d, [](auto& f) { f.pixdim[1] = -1.5f; }); }, "pixdim[1] is -1.5"},
      {"nifti_zero_spacing", [](auto& d) { return nifti(d, [](auto& f) { f.pixdim[2] = 0; }); }, "pixdim[2] is 0"},
      {"nifti_nan_spacing", [](auto& d) { return nifti(d, [](auto& f) { f.pixdim[3] = kNaN; }); }, "pixdim[3] is nan"},
      {"nifti_unknown_datatype", [](auto& d) { return nifti(d, [](auto& f) { f.datatype = 9999; }); },
       "datatype 9999 is not a NIfTI-1 type"},
      {"nifti_rgb_datatype", [](auto& d) { return nifti(d, [](auto& f) { f.datatype = 128, f.bitpix = 24; }); },
       "datatype 128 (RGB24) is not supported"},
      {"nifti_negative_label",
       [](auto& d) { return nifti(d, [](auto& f) { f.datatype = 4, f.bitpix = 16; }, samples<std::int16_t>({1, 1, 1, 1, 1, -3})); },
       "voxel 5 (i 1, j 1, k 0) holds -3"},
      {"nifti_label_too_large",
       [](auto& d) {
         std::string data = samples<std::int32_t>({});
         data.replace(23 * 4, 4, test::bytesOf(std::int32_t(70000)));
         return nifti(d, [](auto& f) { f.datatype = 8, f.bitpix = 32; }, data);
       },
       "voxel 23 (i 3, j 2, k 1) holds 70000"},
      {"nifti_fractional_label",
       [](auto& d) { return nifti(d, [](auto& f) { f.datatype = 16, f.bitpix = 32; }, samples<float>({2.5f})); },
       "voxel 0 (i 0, j 0, k 0) holds 2.5"},
      {"nifti_nan_label", [](auto& d) { return nifti(d, [](auto& f) { f.datatype = 64, f.bitpix = 64; }, samples<double>({1, 1, kNaN})); },
       "voxel 2 (i 2, j 0, k 0) holds nan"},
      {"nifti_scaled_fractional", [](auto& d) { return nifti(d, [](auto& f) { f.sclSlope = 0.5f; }, u8s({3})); },
       "holds 1.5 after scaling by slope 0.5 and intercept 0"},
      {"nifti_bad_vox_offset", [](auto& d) { return nifti(d, [](auto& f) { f.voxOffset = 100; }); }, "vox_offset 100 is not a valid"},
      {"nifti_sheared_sform", [](auto& d) { return nifti(d, [](auto& f) { f.srow[1] = 1.0f; }); }, "voxel axes are not orthogonal"},
      {"nifti_nan_sform", [](auto& d) { return nifti(d, [](auto& f) { f.srow[3] = kNaN; }); }, "sform (srow_x/y/z) is not finite"},
      {"nifti_missing_file", [](auto& d) { return d + "/missing.nii"; }, "cannot open the file (No such file or directory)"},
      {"nifti_directory",
       [](auto& d) {
         fs::create_directory(d + "/dir.nii");
         return d + "/dir.nii";
       },
       "it is a directory"},
  };
}

const std::string kMeta = "ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\nElementSpacing = 1 1 1\nElementType = MET_UCHAR\n";
std::string meta(const std::string& dir, const std::string& fields, const std::string& data = u8s()) {
  return put(dir, "bad.mha", fields + "ElementDataFile = LOCAL\n" + data);
}
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  return text.replace(text.find(from), from.size(), to);
}

std::vector<BadInput> metaImageCases() {
  return {
      {"mha_truncated_header", [](auto& d) { return put(d, "bad.mha", kMeta.substr(0, 40)); }, "ends without an ElementDataFile field"},
      {"mha_truncated_data", [](auto& d) { return meta(d, kMeta, u8s().substr(0, 10)); }, "voxel data is truncated"},
      {"mha_zlib_truncated", [](auto& d) { return writtenThen(d, "bad.mha", dropLast(100)); }, "truncated"},
      {"mha_zlib_bad_checksum", [](auto& d) { return writtenThen(d, "bad.mha", flipFromEnd(2)); },
       "corrupt compressed data (incorrect data check)"},
      {"mha_wrong_magic", [](auto& d) { return put(d, "bad.mha", "\x89PNG\r\n\x1a\nbinary"); },
       "line 1 of the MetaImage header is not a \"Key = Value\" field"},
      {"mha_dims_overflow_int64", [](auto& d) { return meta(d, replaced(kMeta, "4 3 2", "4294967296 4294967296 4294967296")); },
       "grid dimensions 4294967296 x 4294967296 x 4294967296 exceed the largest supported grid"},
      {"mha_dims_out_of_range", [](auto& d) { return meta(d, replaced(kMeta, "4 3 2", "99999999999999999999 1 1")); },
       "DimSize: \"99999999999999999999\" is out of range"},
      {"mha_zero_dim", [](auto& d) { return meta(d, replaced(kMeta, "4 3 2", "4 0 2")); }, "grid dimension 1 is 0"},
      {"mha_negative_dim", [](auto& d) { return meta(d, replaced(kMeta, "4 3 2", "4 3 -2")); }, "grid dimension 2 is -2"},
      {"mha_negative_spacing", [](auto& d) { return meta(d, replaced(kMeta, "Spacing = 1 1 1", "Spacing = -1 1 1")); },
       "ElementSpacing along axis 0 is -1"},
      {"mha_zero_spacing", [](auto& d) { return meta(d, replaced(kMeta, "Spacing = 1 1 1", "Spacing = 1 0 1")); },
       "ElementSpacing along axis 1 is 0"},
      {"mha_nan_spacing", [](auto& d) { return meta(d, replaced(kMeta, "Spacing = 1 1 1", "Spacing = 1 1 nan")); },
       "ElementSpacing: \"nan\" is not finite"},
      {"mha_unknown_type", [](auto& d) { return meta(d, replaced(kMeta, "MET_UCHAR", "MET_FOO")); }, "ElementType MET_FOO is not supported"},
      {"mha_ndims_2", [](auto& d) { return meta(d, replaced(kMeta, "NDims = 3", "NDims = 2")); }, "only 3-D grids are supported"},
      {"mha_negative_label", [](auto& d) { return meta(d, replaced(kMeta, "MET_UCHAR", "MET_SHORT"), samples<std::int16_t>({-7})); },
       "voxel 0 (i 0, j 0, k 0) holds -7"},
      {"mha_label_too_large",
       [](auto& d) { return meta(d, replaced(kMeta, "MET_UCHAR", "MET_UINT"), samples<std::uint32_t>({0, 65536})); },
       "voxel 1 (i 1, j 0, k 0) holds 65536"},
      {"mha_fractional_label", [](auto& d) { return meta(d, replaced(kMeta, "MET_UCHAR", "MET_DOUBLE"), samples<double>({0.25})); },
       "holds 0.25"},
      {"mha_list_data_file", [](auto& d) { return put(d, "bad.mha", kMeta + "ElementDataFile = LIST\n"); }, "is not supported"},
      {"mhd_missing_data_file", [](auto& d) { return put(d, "bad.mhd", kMeta + "ElementDataFile = missing.raw\n"); },
       "cannot open its data file"},
      {"mhd_truncated_data_file",
       [](auto& d) {
         put(d, "short.raw", u8s().substr(0, 10));
         return put(d, "bad.mhd", kMeta + "ElementDataFile = short.raw\n");
       },
       "voxel data is truncated"},
  };
}

const std::string kNrrd = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 3 2\nspacings: 1 1 1\nendian: little\nencoding: raw\n";
std::string nrrd(const std::string& dir, const std::string& fields, const std::string& data = u8s()) {
  return put(dir, "bad.nrrd", fields + "\n" + data);
}

std::vector<BadInput> nrrdCases() {
  return {
      {"nrrd_truncated_header", [](auto& d) { return put(d, "bad.nrrd", kNrrd.substr(0, 20)); }, "has no \"dimension\" field"},
      {"nrrd_truncated_data", [](auto& d) { return nrrd(d, kNrrd, u8s().substr(0, 10)); }, "voxel data is truncated"},
      {"nrrd_gzip_truncated", [](auto& d) { return writtenThen(d, "bad.nrrd", dropLast(100)); }, "truncated"},
      {"nrrd_gzip_bad_crc", [](auto& d) { return writtenThen(d, "bad.nrrd", flipFromEnd(6)); },
       "corrupt compressed data (incorrect data check)"},
      {"nrrd_wrong_magic", [](auto& d) { return nrrd(d, replaced(kNrrd, "NRRD0004", "NRRX0004")); }, "not a NRRD file (bad magic"},
      {"nrrd_sizes_overflow_int64",
       [](auto& d) { return nrrd(d, replaced(kNrrd, "4 3 2", "3037000500 3037000500 3037000500")); },
       "exceed the largest supported grid"},
      {"nrrd_zero_size", [](auto& d) { return nrrd(d, replaced(kNrrd, "4 3 2", "0 3 2")); }, "grid dimension 0 is 0"},
      {"nrrd_negative_size", [](auto& d) { return nrrd(d, replaced(kNrrd, "4 3 2", "4 -3 2")); }, "grid dimension 1 is -3"},
      {"nrrd_negative_spacing", [](auto& d) { return nrrd(d, replaced(kNrrd, "spacings: 1 1 1", "spacings: 1 -2 1")); },
       "spacing along axis 1 is -2"},
      {"nrrd_zero_spacing", [](auto& d) { return nrrd(d, replaced(kNrrd, "spacings: 1 1 1", "spacings: 1 1 0")); },
       "spacing along axis 2 is 0"},
      {"nrrd_nan_spacing", [](auto& d) { return nrrd(d, replaced(kNrrd, "spacings: 1 1 1", "spacings: nan 1 1")); },
       "spacings: \"nan\" is not finite"},
      {"nrrd_zero_direction",
       [](auto& d) {
         return nrrd(d, replaced(kNrrd, "spacings: 1 1 1", "space: RAS\nspace directions: (0,0,0) (0,1,0) (0,0,1)"));
       },
       "voxel axis 0 has zero length"},
      {"nrrd_unknown_type", [](auto& d) { return nrrd(d, replaced(kNrrd, "uint8", "block")); }, "type \"block\" is not supported"},
      {"nrrd_4d", [](auto& d) { return nrrd(d, replaced(kNrrd, "dimension: 3", "dimension: 4")); }, "only 3-D grids are supported"},
      {"nrrd_ascii_encoding", [](auto& d) { return nrrd(d, replaced(kNrrd, "raw", "ascii")); }, "encoding \"ascii\" is not supported"},
      {"nrrd_negative_label", [](auto& d) { return nrrd(d, replaced(kNrrd, "uint8", "short"), samples<std::int16_t>({1, -1})); },
       "voxel 1 (i 1, j 0, k 0) holds -1"},
      {"nrrd_label_too_large", [](auto& d) { return nrrd(d, replaced(kNrrd, "uint8", "uint32"), samples<std::uint32_t>({100000})); },
       "holds 100000"},
      {"nrrd_fractional_label", [](auto& d) { return nrrd(d, replaced(kNrrd, "uint8", "float"), samples<float>({7.5f})); },
       "holds 7.5"},
      {"nhdr_missing_data_file", [](auto& d) { return put(d, "bad.nhdr", kNrrd + "data file: missing.raw\n"); },
       "cannot open its data file"},
      {"nhdr_without_data_file", [](auto& d) { return put(d, "bad.nhdr", kNrrd); }, "has no \"data file\" field"},
  };
}

const std::string kInr = "XDIM=4\nYDIM=3\nZDIM=2\nVDIM=1\nTYPE=unsigned fixed\nPIXSIZE=8 bits\nCPU=decm\nVX=1\nVY=1\nVZ=1\n";
std::string inr(const std::string& dir, const std::string& fields, const std::string& data = u8s()) {
  return put(dir, "bad.inr", test::inrHeader(fields) + data);
}

std::vector<BadInput> inrCases() {
  return {
      {"inr_truncated_header", [](auto& d) { return put(d, "bad.inr", test::inrHeader(kInr).substr(0, 100)); },
       "INR header is truncated"},
      {"inr_truncated_data", [](auto& d) { return inr(d, kInr, u8s().substr(0, 10)); }, "voxel data is truncated"},
      {"inr_gz_truncated", [](auto& d) { return writtenThen(d, "bad.inr.gz", dropLast(100)); }, "truncated"},
      {"inr_gz_bad_crc", [](auto& d) { return writtenThen(d, "bad.inr.gz", flipFromEnd(6)); },
       "corrupt compressed data (incorrect data check)"},
      {"inr_wrong_magic", [](auto& d) { return put(d, "bad.inr", replaced(test::inrHeader(kInr), "INRIMAGE-4", "INRIMAGE-5") + u8s()); },
       "not an INR file (bad magic"},
      {"inr_dims_overflow_int64",
       [](auto& d) { return inr(d, replaced(kInr, "XDIM=4\nYDIM=3\nZDIM=2", "XDIM=4294967296\nYDIM=4294967296\nZDIM=4294967296")); },
       "exceed the largest supported grid"},
      {"inr_zero_dim", [](auto& d) { return inr(d, replaced(kInr, "ZDIM=2", "ZDIM=0")); }, "grid dimension 2 is 0"},
      {"inr_negative_dim", [](auto& d) { return inr(d, replaced(kInr, "XDIM=4", "XDIM=-4")); }, "grid dimension 0 is -4"},
      {"inr_negative_spacing", [](auto& d) { return inr(d, replaced(kInr, "VX=1", "VX=-1")); }, "VX=-1: voxel spacing must be positive"},
      {"inr_zero_spacing", [](auto& d) { return inr(d, replaced(kInr, "VY=1", "VY=0")); }, "VY=0: voxel spacing must be positive"},
      {"inr_nan_spacing", [](auto& d) { return inr(d, replaced(kInr, "VZ=1", "VZ=nan")); }, "VZ: \"nan\" is not finite"},
      {"inr_unknown_type", [](auto& d) { return inr(d, replaced(kInr, "unsigned fixed", "packed")); }, "TYPE=packed with PIXSIZE=8 bits"},
      {"inr_vector_image", [](auto& d) { return inr(d, replaced(kInr, "VDIM=1", "VDIM=3")); }, "VDIM is 3"},
      {"inr_negative_label",
       [](auto& d) {
         return inr(d, replaced(replaced(kInr, "unsigned", "signed"), "8 bits", "16 bits"), samples<std::int16_t>({0, 0, -2}));
       },
       "voxel 2 (i 2, j 0, k 0) holds -2"},
      {"inr_label_too_large",
       [](auto& d) { return inr(d, replaced(kInr, "8 bits", "32 bits"), samples<std::uint32_t>({65536})); }, "holds 65536"},
      {"inr_fractional_label",
       [](auto& d) { return inr(d, replaced(replaced(kInr, "unsigned fixed", "float"), "8 bits", "32 bits"), samples<float>({0.5f})); },
       "holds 0.5"},
  };
}

std::vector<BadInput> allCases() {
  std::vector<BadInput> all;
  for (auto cases : {niftiCases(), metaImageCases(), nrrdCases(), inrCases()}) all.insert(all.end(), cases.begin(), cases.end());
  return all;
}

void PrintTo(const BadInput& c, std::ostream* os) { *os << c.name; }

class GridBadInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(GridBadInput, ThrowsInputErrorNamingFileAndFault) {
  const std::string path = GetParam().make(test::tempDir());
  for (const bool streamed : {false, true}) {
    try {
      if (streamed) {
        const auto reader = openGridSlices(path);
        std::vector<Label> labels(std::size_t(reader->geometry().voxelCount()));
        reader->readSlices(0, reader->geometry().dims[2], labels.data());
      } else {
        readGrid(path);
      }
      ADD_FAILURE() << (streamed ? "openGridSlices" : "readGrid") << " accepted " << path;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(path));
      EXPECT_THAT(e.what(), HasSubstr(GetParam().fault));
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllReaders, GridBadInput, ::testing::ValuesIn(allCases()),
                         [](const ::testing::TestParamInfo<BadInput>& info) { return info.param.name; });

TEST(GridBadInput, ValidBaselinesAreAccepted) {
  // The cases above each break one thing of these files.
  const std::string dir = test::tempDir();
  test::NiftiFields f;
  f.dim[0] = 5;  // trailing dimensions of 1 are accepted
  const std::vector<std::string> paths = {put(dir, "ok.nii", test::niftiHeader(f) + u8s({9})), meta(dir, kMeta, u8s({9})),
                                          nrrd(dir, kNrrd, u8s({9})), inr(dir, kInr, u8s({9}))};
  for (const std::string& path : paths) {
    const LabelGrid grid = readGrid(path);
    EXPECT_EQ(grid.dims(), (Index3{4, 3, 2})) << path;
    EXPECT_EQ(grid.at(0, 0, 0), 9) << path;
    EXPECT_EQ(grid.at(3, 2, 1), 1) << path;
  }
}

}  // namespace
}  // namespace vox
