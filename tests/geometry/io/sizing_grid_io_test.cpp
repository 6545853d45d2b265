// The remesher's sizing grid reader (sizing_grid_io.h): real values in the
// file's affine, and the label grid reader's header check with its messages
// (nifti_header.h), so that a header one reader refuses the other refuses in
// the same words.

#include "geometry/error.h"
#include "geometry/io/byte_stream.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/sizing_grid_io.h"
#include "tests/geometry/io/grid_test_grids.h"
#include "tests/support/test_environment.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>

namespace vox {
namespace {

using ::testing::HasSubstr;

const float kNaN = std::numeric_limits<float>::quiet_NaN();

template <class T>
std::string samples(std::initializer_list<T> values, std::size_t count = 24, bool bigEndian = false) {
  std::string s;
  for (std::size_t n = 0; n < count; ++n) s += test::bytesOf(n < values.size() ? *(values.begin() + n) : T(1), bigEndian);
  return s;
}

std::string gzip(const std::string& bytes) {
  std::string out;
  auto sink = stringWriter(out);
  auto deflate = deflateWriter(*sink, DeflateWrapper::Gzip, "test");
  deflate->write(bytes.data(), bytes.size());
  deflate->finish();
  return out;
}

// A 4 x 3 x 2 NIfTI-1 file (test::NiftiFields' defaults, edited) with `data`.
std::string sizeFile(const std::string& name, const std::function<void(test::NiftiFields&)>& edit, const std::string& data) {
  test::NiftiFields f;
  edit(f);
  const std::string path = test::tempDir() + "/" + name;
  test::writeBytes(path, test::niftiHeader(f) + data);
  return path;
}

std::string messageOf(const std::function<void()>& read) {
  try {
    read();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(SizingGridIo, ReadsScaledValuesInTheFilesAffine) {
  const auto float32 = [](test::NiftiFields& f) { f.datatype = 16, f.bitpix = 32; };
  const ScalarGrid plain = readSizingGrid(sizeFile("float.nii", float32, samples<float>({2.5f, 0.75f, 4.0f})));
  EXPECT_EQ(plain.geometry.dims, (Index3{4, 3, 2}));
  EXPECT_TRUE(plain.geometry.spacing.isApprox(Eigen::Vector3d(1.5, 2.0, 3.0)));
  EXPECT_TRUE(plain.geometry.indexToWorld().col(3).head<3>().isApprox(Eigen::Vector3d(10, 20, 30)));
  ASSERT_EQ(plain.values.size(), 24u);
  EXPECT_EQ(plain.values[0], 2.5f);
  EXPECT_EQ(plain.values[1], 0.75f);
  EXPECT_EQ(plain.values[2], 4.0f);
  EXPECT_EQ(plain.values[23], 1.0f);

  // Big-endian (the whole header swapped) and compressed: the same grid.
  const ScalarGrid swapped = readSizingGrid(sizeFile(
      "swapped.nii", [&](test::NiftiFields& f) { float32(f), f.bigEndian = true; }, samples<float>({2.5f, 0.75f, 4.0f}, 24, true)));
  EXPECT_EQ(swapped.values, plain.values);
  test::NiftiFields f;
  float32(f);
  const std::string gz = test::tempDir() + "/float.nii.gz";
  test::writeBytes(gz, gzip(test::niftiHeader(f) + samples<float>({2.5f, 0.75f, 4.0f})));
  EXPECT_EQ(readSizingGrid(gz).values, plain.values);

  // int16 scaled by scl_slope / scl_inter: mm = 0.5 * sample + 1.
  const ScalarGrid scaled = readSizingGrid(sizeFile(
      "scaled.nii", [](test::NiftiFields& f) { f.datatype = 4, f.bitpix = 16, f.sclSlope = 0.5f, f.sclInter = 1.0f; },
      samples<std::int16_t>({6, -2})));
  EXPECT_EQ(scaled.values[0], 4.0f);
  EXPECT_EQ(scaled.values[1], 0.0f);
  EXPECT_EQ(scaled.values[2], 1.5f);
}

TEST(SizingGridIo, ValuesBeyondFloatComeBackInfinite) {
  const ScalarGrid g = readSizingGrid(sizeFile(
      "huge.nii", [](test::NiftiFields& f) { f.datatype = 64, f.bitpix = 64; }, samples<double>({1e300, -1e300, double(kNaN), 3.0})));
  EXPECT_EQ(g.values[0], std::numeric_limits<float>::infinity());
  EXPECT_EQ(g.values[1], -std::numeric_limits<float>::infinity());
  EXPECT_TRUE(std::isnan(g.values[2]));
  EXPECT_EQ(g.values[3], 3.0f);
}

// Each header fault: the sizing grid reader refuses it with the label grid
// reader's one-line message (the same check), naming the file.
TEST(SizingGridIo, RefusesBadHeadersWithTheLabelReadersMessages) {
  const std::string u8(24, '\1');
  const std::vector<std::pair<std::string, std::function<void(test::NiftiFields&)>>> faults = {
      {"bad magic", [](auto& f) { std::memcpy(f.magic, "xyz", 4); }},
      {"pair magic", [](auto& f) { std::memcpy(f.magic, "ni1", 4); }},
      {"sizeof_hdr", [](auto& f) { f.sizeofHdr = 1000; }},
      {"NIfTI-2", [](auto& f) { f.sizeofHdr = 540; }},
      {"dims beyond the limit", [](auto& f) { f.dim[1] = f.dim[2] = f.dim[3] = 32767; }},
      {"zero dim", [](auto& f) { f.dim[2] = 0; }},
      {"negative dim", [](auto& f) { f.dim[3] = -4; }},
      {"4-D", [](auto& f) { f.dim[0] = 4, f.dim[4] = 3; }},
      {"negative spacing", [](auto& f) { f.pixdim[1] = -1.5f; }},
      {"NaN spacing", [](auto& f) { f.pixdim[3] = kNaN; }},
      {"unknown datatype", [](auto& f) { f.datatype = 9999; }},
      {"vox_offset", [](auto& f) { f.voxOffset = 100; }},
      {"NaN scl_inter", [](auto& f) { f.sclSlope = 2.0f, f.sclInter = kNaN; }},
      {"sheared sform", [](auto& f) { f.srow[1] = 1.0f; }},
      {"NaN sform", [](auto& f) { f.srow[3] = kNaN; }},
      {"NaN qform", [](auto& f) { f.sformCode = 0, f.qformCode = 1, f.pixdim[0] = kNaN; }},
      {"more voxels than the file holds", [](auto& f) { f.dim[3] = 200; }},
  };
  for (const auto& [fault, edit] : faults) {
    const std::string path = sizeFile("fault.nii", edit, u8);
    const std::string labels = messageOf([&] { readGrid(path); });
    EXPECT_THAT(labels, HasSubstr(path + ": ")) << fault;
    EXPECT_EQ(messageOf([&] { readSizingGrid(path); }), labels) << fault;
  }
  // A header cut short, and samples cut short.
  test::NiftiFields f;
  const std::string path = test::tempDir() + "/short.nii";
  test::writeBytes(path, test::niftiHeader(f).substr(0, 100));
  EXPECT_EQ(messageOf([&] { readSizingGrid(path); }), path + ": NIfTI header is truncated (100 of 348 bytes present)");
  test::writeBytes(path, test::niftiHeader(f) + u8.substr(0, 10));
  EXPECT_EQ(messageOf([&] { readSizingGrid(path); }), messageOf([&] { readGrid(path); }));
  EXPECT_THAT(messageOf([&] { readSizingGrid(test::tempDir() + "/missing.nii"); }), HasSubstr("cannot open the file"));

  // Where the values' kind is named, it is sizes.
  EXPECT_EQ(messageOf([&] { readSizingGrid(sizeFile("rgb.nii", [](auto& f) { f.datatype = 128, f.bitpix = 24; }, u8 + u8 + u8)); }),
            test::tempDir() + "/rgb.nii: datatype 128 (RGB24) is not supported for sizes (expected an integer or float type)");
  EXPECT_EQ(messageOf([&] { readSizingGrid(sizeFile("flat.nii", [](auto& f) { f.dim[0] = 2; }, u8)); }),
            test::tempDir() + "/flat.nii: dim[0] is 2: a size grid needs 3 dimensions");
}

// A compressed file whose header declares more values than deflate can
// decode from its bytes: refused before the values are allocated.
TEST(SizingGridIo, RefusesAGzipHeaderPromisingMoreThanItsBytesHold) {
  test::NiftiFields f;
  f.dim[1] = f.dim[2] = f.dim[3] = 2048;
  f.datatype = 16;
  f.bitpix = 32;
  const std::string path = test::tempDir() + "/big.nii.gz";
  test::writeBytes(path, gzip(test::niftiHeader(f) + std::string(64, '\1')));
  ASSERT_LT(std::filesystem::file_size(path), 2000u);
  const std::string message = messageOf([&] { readSizingGrid(path); });
  EXPECT_THAT(message, HasSubstr(path + ": voxel data is truncated"));
  EXPECT_THAT(message, HasSubstr("the compressed data can decode to at most"));
}

}  // namespace
}  // namespace vox
