#pragma once
// Grids, checksums and byte-level file builders shared by the grid io tests.

#include "geometry/label_grid.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

namespace vox::test {

// Label of voxel (i,j,k) in the test pattern: every residue modulo `modulus`
// appears, neighbouring voxels differ.
inline Label patternLabel(std::int64_t i, std::int64_t j, std::int64_t k, std::int64_t modulus) {
  return Label((3 * i + 5 * j + 7 * k + i * j * k) % modulus);
}

// 17 x 13 x 11 voxels, anisotropic spacing, an origin away from zero and a
// rotated frame (mirrored: a reflection, determinant -1). The largest label
// is exactly maxLabel.
inline LabelGrid makeTestGrid(Label maxLabel, bool mirrored = false) {
  GridGeometry g;
  g.dims = {17, 13, 11};
  g.spacing = {0.8, 1.25, 2.5};
  g.origin = {-31.5, 12.25, 101.0};
  g.direction = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  if (mirrored) g.direction = g.direction * Eigen::Vector3d(1, 1, -1).asDiagonal();
  LabelGrid grid(g);
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) grid.at(i, j, k) = patternLabel(i, j, k, std::int64_t(maxLabel) + 1);
  grid.at(0, 0, 0) = maxLabel;
  return grid;
}

// sum of label * (index mod 65521 + 1): order-sensitive, computed the same
// way in the nibabel scripts.
inline std::uint64_t labelChecksum(const LabelGrid& grid) {
  std::uint64_t sum = 0;
  for (std::size_t n = 0; n < grid.labels().size(); ++n) sum += std::uint64_t(grid.labels()[n]) * (n % 65521 + 1);
  return sum;
}

inline void expectSameGeometry(const GridGeometry& expected, const GridGeometry& actual, double tolerance) {
  EXPECT_EQ(expected.dims, actual.dims);
  EXPECT_TRUE(expected.spacing.isApprox(actual.spacing, tolerance)) << actual.spacing.transpose();
  EXPECT_LT((expected.origin - actual.origin).cwiseAbs().maxCoeff(), tolerance * 100.0) << actual.origin.transpose();
  EXPECT_LT((expected.direction - actual.direction).cwiseAbs().maxCoeff(), tolerance) << actual.direction;
  EXPECT_LT((expected.indexToWorld() - actual.indexToWorld()).cwiseAbs().maxCoeff(), tolerance * 100.0);
}

inline void expectSameLabels(const LabelGrid& expected, const LabelGrid& actual) {
  ASSERT_EQ(expected.labels().size(), actual.labels().size());
  for (std::size_t n = 0; n < expected.labels().size(); ++n)
    ASSERT_EQ(expected.labels()[n], actual.labels()[n]) << "first difference at voxel " << n;
}

inline void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

template <class T>
std::string bytesOf(T value, bool bigEndian = false) {
  std::string s(sizeof(T), '\0');
  std::memcpy(s.data(), &value, sizeof(T));
  if (bigEndian) std::reverse(s.begin(), s.end());
  return s;
}

template <class T>
void putAt(std::string& bytes, std::size_t offset, T value, bool bigEndian = false) {
  const std::string b = bytesOf(value, bigEndian);
  bytes.replace(offset, b.size(), b);
}

// A NIfTI-1 single-file header (348 bytes + 4-byte extension flag) built
// field by field, so that tests can break any field.
struct NiftiFields {
  std::int32_t sizeofHdr = 348;
  std::int16_t dim[8] = {3, 4, 3, 2, 1, 1, 1, 1};
  std::int16_t datatype = 2;  // uint8
  std::int16_t bitpix = 8;
  float pixdim[8] = {1, 1.5f, 2.0f, 3.0f, 0, 0, 0, 0};
  float voxOffset = 352;
  float sclSlope = 0;
  float sclInter = 0;
  std::int16_t qformCode = 0;
  std::int16_t sformCode = 1;
  float srow[12] = {1.5f, 0, 0, 10, 0, 2.0f, 0, 20, 0, 0, 3.0f, 30};
  char magic[4] = {'n', '+', '1', '\0'};
  bool bigEndian = false;
};

inline std::string niftiHeader(const NiftiFields& f) {
  std::string h(352, '\0');
  const bool be = f.bigEndian;
  putAt(h, 0, f.sizeofHdr, be);
  for (int d = 0; d < 8; ++d) putAt(h, 40 + 2 * std::size_t(d), f.dim[d], be);
  putAt(h, 70, f.datatype, be);
  putAt(h, 72, f.bitpix, be);
  for (int d = 0; d < 8; ++d) putAt(h, 76 + 4 * std::size_t(d), f.pixdim[d], be);
  putAt(h, 108, f.voxOffset, be);
  putAt(h, 112, f.sclSlope, be);
  putAt(h, 116, f.sclInter, be);
  putAt(h, 252, f.qformCode, be);
  putAt(h, 254, f.sformCode, be);
  for (int n = 0; n < 12; ++n) putAt(h, 280 + 4 * std::size_t(n), f.srow[n], be);
  h.replace(344, 4, f.magic, 4);
  return h;
}

// An INRIMAGE-4 header from its field lines, padded to 256 bytes.
inline std::string inrHeader(const std::string& fields) {
  std::string h = "#INRIMAGE-4#{\n" + fields;
  h.append(252 - h.size(), '\n');
  return h + "##}\n";
}

}  // namespace vox::test
