// Every grid format: write -> read reproduces dims, spacing, origin, a rotated
// or mirrored direction and every label, for both stored types (uint8 and
// uint16), and leaves exactly the expected files behind.

#include "geometry/io/grid_io.h"
#include "tests/geometry/io/grid_test_grids.h"
#include "tests/support/test_environment.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

namespace vox {
namespace {

namespace fs = std::filesystem;

struct RoundTripCase {
  std::string extension;
  Label maxLabel;
  bool mirrored;
};

std::string caseName(const ::testing::TestParamInfo<RoundTripCase>& info) {
  std::string name;
  for (char c : info.param.extension) name += c == '.' ? '_' : c;
  return name.substr(1) + (info.param.maxLabel <= 255 ? "_uint8" : "_uint16") + (info.param.mirrored ? "_mirrored" : "_rotated");
}

// NIfTI stores its affine in float32; the text formats print 17 digits.
double geometryTolerance(const std::string& extension) {
  return gridFormatFromPath(extension) == GridFormat::Nifti ? 2e-6 : 1e-12;
}

// Files the writer leaves in an empty directory.
std::string expectedFiles(const std::string& extension) {
  if (extension == ".mhd") return "grid.mhd\ngrid.raw\n";
  if (extension == ".nhdr") return "grid.nhdr\ngrid.raw.gz\n";
  return "grid" + extension + "\n";
}

void PrintTo(const RoundTripCase& c, std::ostream* os) { *os << c.extension << " max " << c.maxLabel << (c.mirrored ? " mirrored" : ""); }

class GridRoundTrip : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(GridRoundTrip, ReproducesGeometryAndLabels) {
  const RoundTripCase& c = GetParam();
  const std::string dir = test::tempDir();
  const std::string path = dir + "/grid" + c.extension;
  const LabelGrid grid = test::makeTestGrid(c.maxLabel, c.mirrored);
  writeGrid(path, grid);

  const LabelGrid back = readGrid(path);
  test::expectSameGeometry(grid.geometry(), back.geometry(), geometryTolerance(c.extension));
  test::expectSameLabels(grid, back);
  EXPECT_EQ(back.maxLabel(), c.maxLabel);
  EXPECT_EQ(test::listFiles(dir), expectedFiles(c.extension));

  // The stored type shows in the size of the uncompressed files.
  const std::uintmax_t sampleBytes = std::uintmax_t(grid.voxelCount()) * (c.maxLabel <= 255 ? 1 : 2);
  if (c.extension == ".nii") {
    EXPECT_EQ(fs::file_size(path), 352 + sampleBytes);
  } else if (c.extension == ".inr") {
    EXPECT_EQ((fs::file_size(path) - sampleBytes) % 256, 0u);  // header in 256-byte blocks
  } else if (c.extension == ".mhd") {
    EXPECT_EQ(fs::file_size(dir + "/grid.raw"), sampleBytes);
  }
}

std::vector<RoundTripCase> allCases() {
  std::vector<RoundTripCase> cases;
  for (const char* ext : {".nii", ".nii.gz", ".mha", ".mhd", ".nrrd", ".nhdr", ".inr", ".inr.gz"})
    for (Label maxLabel : {Label(200), Label(40000)})
      for (bool mirrored : {false, true}) cases.push_back({ext, maxLabel, mirrored});
  return cases;
}

INSTANTIATE_TEST_SUITE_P(AllFormats, GridRoundTrip, ::testing::ValuesIn(allCases()), caseName);

TEST(GridWrite, ReplacesAnExistingFile) {
  const std::string dir = test::tempDir();
  for (const char* ext : {".nii.gz", ".mhd", ".nrrd", ".inr"}) {
    const std::string path = dir + "/grid" + ext;
    writeGrid(path, test::makeTestGrid(40000));
    const LabelGrid second = test::makeTestGrid(9, true);
    writeGrid(path, second);
    test::expectSameLabels(second, readGrid(path));
  }
}

TEST(GridWrite, StoredTypeIsUint8ExactlyUpTo255) {
  const std::string dir = test::tempDir();
  for (Label maxLabel : {Label(255), Label(256)}) {
    const LabelGrid grid = test::makeTestGrid(maxLabel);
    const std::string path = dir + "/grid" + std::to_string(maxLabel) + ".nii";
    writeGrid(path, grid);
    EXPECT_EQ(fs::file_size(path), 352 + std::uintmax_t(grid.voxelCount()) * (maxLabel == 255 ? 1 : 2));
    test::expectSameLabels(grid, readGrid(path));
  }
}

TEST(GridWrite, MetaImageHeaderIsInItkLpsConvention) {
  // An identity RAS direction is diag(-1, -1, 1) in ITK's LPS world, and the
  // origin flips with it.
  GridGeometry g;
  g.dims = {2, 3, 4};
  g.spacing = {0.5, 0.75, 1.5};
  g.origin = {10, 20, 30};
  const std::string path = test::tempDir() + "/lps.mhd";
  writeGrid(path, LabelGrid(g, 7));
  const std::string header = test::readBytes(path);
  EXPECT_THAT(header, ::testing::HasSubstr("TransformMatrix = -1 0 0 0 -1 0 0 0 1\n"));
  EXPECT_THAT(header, ::testing::HasSubstr("Offset = -10 -20 30\n"));
  EXPECT_THAT(header, ::testing::HasSubstr("ElementDataFile = lps.raw\n"));
  const LabelGrid back = readGrid(path);
  EXPECT_EQ(back.geometry().direction, Eigen::Matrix3d::Identity());
  EXPECT_EQ(back.origin(), g.origin);
}

TEST(GridRead, NrrdSpacesAreConvertedToRas) {
  // The same voxel-to-world map written in LPS and in RAS reads back the same.
  const std::string dir = test::tempDir();
  const std::string common =
      "type: uint8\ndimension: 3\nsizes: 2 2 1\nendian: little\nencoding: raw\n";
  test::writeBytes(dir + "/lps.nrrd", "NRRD0004\nspace: left-posterior-superior\n" + common +
                                          "space directions: (-2,0,0) (0,-3,0) (0,0,4)\nspace origin: (-5,-6,7)\n\n" +
                                          std::string("\x01\x02\x03\x04", 4));
  test::writeBytes(dir + "/ras.nrrd", "NRRD0004\nspace: RAS\n" + common +
                                          "space directions: (2,0,0) (0,3,0) (0,0,4)\nspace origin: (5,6,7)\n\n" +
                                          std::string("\x01\x02\x03\x04", 4));
  const LabelGrid lps = readGrid(dir + "/lps.nrrd");
  const LabelGrid ras = readGrid(dir + "/ras.nrrd");
  EXPECT_EQ(lps.geometry().indexToWorld(), ras.geometry().indexToWorld());
  EXPECT_EQ(ras.geometry().spacing, Eigen::Vector3d(2, 3, 4));
  EXPECT_EQ(ras.origin(), Eigen::Vector3d(5, 6, 7));
  EXPECT_EQ(lps.labels(), (std::vector<Label>{1, 2, 3, 4}));
}

TEST(GridRead, BigEndianSamplesInEveryFormat) {
  const std::string dir = test::tempDir();
  // uint16 samples 0x0102, 0x0304, ... stored most significant byte first.
  std::string samples;
  for (int n = 0; n < 8; ++n) samples += std::string{char(1 + 2 * n), char(2 + 2 * n)};
  const std::vector<Label> expected{0x0102, 0x0304, 0x0506, 0x0708, 0x090a, 0x0b0c, 0x0d0e, 0x0f10};
  test::writeBytes(dir + "/be.mha", "NDims = 3\nDimSize = 2 2 2\nElementType = MET_USHORT\nBinaryDataByteOrderMSB = True\n"
                                    "ElementDataFile = LOCAL\n" + samples);
  test::writeBytes(dir + "/be.nrrd", "NRRD0004\ntype: ushort\ndimension: 3\nsizes: 2 2 2\nendian: big\nencoding: raw\n\n" + samples);
  test::writeBytes(dir + "/be.inr", test::inrHeader("XDIM=2\nYDIM=2\nZDIM=2\nTYPE=unsigned fixed\nPIXSIZE=16 bits\nCPU=sun\n") +
                                        samples);
  test::NiftiFields f;
  f.dim[1] = f.dim[2] = f.dim[3] = 2;
  f.datatype = 512;  // uint16
  f.bitpix = 16;
  f.bigEndian = true;
  test::writeBytes(dir + "/be.nii", test::niftiHeader(f) + samples);
  for (const char* name : {"/be.mha", "/be.nrrd", "/be.inr", "/be.nii"}) EXPECT_EQ(readGrid(dir + name).labels(), expected) << name;
  const LabelGrid nii = readGrid(dir + "/be.nii");
  EXPECT_EQ(nii.spacing(), Eigen::Vector3d(1.5, 2.0, 3.0));
  EXPECT_EQ(nii.origin(), Eigen::Vector3d(10, 20, 30));
}

}  // namespace
}  // namespace vox
