// Compressed grids whose header declares far more voxels than the file can
// hold: rejected when the file is opened, before anything is allocated from
// the header (deflate decodes at most 1032 bytes per byte it reads), and the
// whole read fails the same way.

#include "geometry/error.h"
#include "geometry/io/byte_stream.h"
#include "geometry/io/grid_io.h"
#include "tests/geometry/io/grid_test_grids.h"
#include "tests/support/test_environment.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>

namespace vox {
namespace {

using ::testing::HasSubstr;

std::string compressed(const std::string& bytes, DeflateWrapper wrapper) {
  std::string out;
  auto sink = stringWriter(out);
  auto deflate = deflateWriter(*sink, wrapper, "test");
  deflate->write(bytes.data(), bytes.size());
  deflate->finish();
  return out;
}
std::string gzip(const std::string& bytes) { return compressed(bytes, DeflateWrapper::Gzip); }

struct HostileGrid {
  std::string name;
  std::function<std::string(const std::string& dir)> make;
};

const std::string kSamples(64, '\1');

std::vector<HostileGrid> hostileGrids() {
  return {
      {"nifti_gz",
       [](const std::string& d) {
         test::NiftiFields f;
         f.dim[1] = f.dim[2] = f.dim[3] = 2048;
         f.datatype = 512;  // uint16
         f.bitpix = 16;
         test::writeBytes(d + "/big.nii.gz", gzip(test::niftiHeader(f) + kSamples));
         return d + "/big.nii.gz";
       }},
      {"nrrd_gzip",
       [](const std::string& d) {
         test::writeBytes(d + "/big.nrrd", "NRRD0004\ntype: uint16\ndimension: 3\nsizes: 2048 2048 2048\nspacings: 1 1 1\n"
                                           "endian: little\nencoding: gzip\n\n" + gzip(kSamples));
         return d + "/big.nrrd";
       }},
      {"nhdr_raw_gz",
       [](const std::string& d) {
         test::writeBytes(d + "/big.raw.gz", gzip(kSamples));
         test::writeBytes(d + "/big.nhdr", "NRRD0004\ntype: uint16\ndimension: 3\nsizes: 2048 2048 2048\nspacings: 1 1 1\n"
                                           "endian: little\nencoding: gzip\ndata file: big.raw.gz\n");
         return d + "/big.nhdr";
       }},
      {"mha_compressed",
       [](const std::string& d) {
         test::writeBytes(d + "/big.mha", "ObjectType = Image\nNDims = 3\nDimSize = 2048 2048 2048\nElementSpacing = 1 1 1\n"
                                          "ElementType = MET_USHORT\nCompressedData = True\nElementDataFile = LOCAL\n" +
                                              compressed(kSamples, DeflateWrapper::Zlib));
         return d + "/big.mha";
       }},
      {"inr_gz",
       [](const std::string& d) {
         test::writeBytes(d + "/big.inr.gz", gzip(test::inrHeader("XDIM=2048\nYDIM=2048\nZDIM=2048\nVDIM=1\nTYPE=unsigned fixed\n"
                                                                  "PIXSIZE=16 bits\nCPU=decm\nVX=1\nVY=1\nVZ=1\n") +
                                                  kSamples));
         return d + "/big.inr.gz";
       }},
  };
}

class GridHostileSize : public ::testing::TestWithParam<HostileGrid> {};

TEST_P(GridHostileSize, RejectedWhenOpenedBeforeAnyAllocation) {
  const std::string dir = test::tempDir() + "/hostile_" + GetParam().name;
  std::filesystem::create_directories(dir);
  const std::string path = GetParam().make(dir);
  ASSERT_LT(std::filesystem::file_size(path), 2000u);
  try {
    openGridSlices(path);
    FAIL() << path << " opened although its compressed data cannot hold 2048^3 voxels";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("voxel data is truncated"));
    EXPECT_THAT(e.what(), HasSubstr("the compressed data can decode to at most"));
  }
  EXPECT_THROW(readGrid(path), InputError);
}

INSTANTIATE_TEST_SUITE_P(Formats, GridHostileSize, ::testing::ValuesIn(hostileGrids()),
                         [](const auto& info) { return info.param.name; });

}  // namespace
}  // namespace vox
