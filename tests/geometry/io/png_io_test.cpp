// PNG images: round trip, conversion of other PNG kinds to RGB, atomic
// writes and corrupt input.

#include "geometry/error.h"
#include "geometry/io/png_io.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

namespace vox {
namespace {

RgbImage gradient(int w, int h) {
  RgbImage img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y) = {std::uint8_t(x * 7), std::uint8_t(y * 13), std::uint8_t((x * y) & 0xFF)};
  return img;
}

TEST(PngIo, RoundTripIsExact) {
  const std::string dir = test::tempDir();
  const RgbImage img = gradient(37, 21);
  writePng(dir + "/a.png", img);
  const RgbImage back = readPng(dir + "/a.png");
  ASSERT_EQ(back.width, 37);
  ASSERT_EQ(back.height, 21);
  const ImageDifference d = compareImages(img, back, 0);
  EXPECT_EQ(d.differing, 0u);
  EXPECT_EQ(d.maxChannelDifference, 0);
  EXPECT_EQ(test::listFiles(dir), "a.png\n");
}

TEST(PngIo, HeaderReadByPython) {
  const std::string py = test::python();
  if (py.empty()) GTEST_SKIP() << "no python3";
  const std::string dir = test::tempDir();
  writePng(dir + "/b.png", gradient(300, 7));
  std::ofstream(dir + "/header.py") << "import struct, sys\n"
                                       "d = open(sys.argv[1], 'rb').read()\n"
                                       "assert d[:8] == b'\\x89PNG\\r\\n\\x1a\\n'\n"
                                       "print(*struct.unpack('>IIBB', d[16:26]))\n";
  const auto r = test::runCommand(py + " " + test::quote(dir + "/header.py") + " " + test::quote(dir + "/b.png"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.out, "300 7 8 2\n");  // width, height, 8 bits, colour type RGB
}

TEST(PngIo, GreyAlphaImagesReadAsRgb) {
  const std::string py = test::python();
  if (py.empty()) GTEST_SKIP() << "no python3";
  const std::string dir = test::tempDir();
  // A 2x1 grey+alpha PNG written by hand (zlib-compressed rows, filter 0).
  std::ofstream(dir + "/make.py")
      << "import struct, zlib, sys\n"
         "def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)\n"
         "raw = b'\\x00' + bytes([10, 255, 200, 255])\n"
         "png = b'\\x89PNG\\r\\n\\x1a\\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', 2, 1, 8, 4, 0, 0, 0))"
         " + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b'')\n"
         "open(sys.argv[1], 'wb').write(png)\n";
  ASSERT_EQ(test::runCommand(py + " " + test::quote(dir + "/make.py") + " " + test::quote(dir + "/grey.png")).exitCode, 0);
  const RgbImage img = readPng(dir + "/grey.png");
  ASSERT_EQ(img.width, 2);
  ASSERT_EQ(img.height, 1);
  EXPECT_EQ(img.at(1, 0), (Rgb{200, 200, 200}));
  EXPECT_EQ(img.at(0, 0), (Rgb{10, 10, 10}));
}

TEST(PngIo, FailedWritesLeaveNothing) {
  const std::string dir = test::tempDir();
  EXPECT_THROW(writePng(dir + "/missing/dir/c.png", gradient(4, 4)), RuntimeFailure);
  EXPECT_THROW(writePng(dir + "/empty.png", RgbImage()), RuntimeFailure);
  RgbImage inconsistent(4, 4);
  inconsistent.pixels.pop_back();
  EXPECT_THROW(writePng(dir + "/bad.png", inconsistent), RuntimeFailure);
  EXPECT_EQ(test::listFiles(dir), "");
  // An existing file is replaced only by a complete new one.
  writePng(dir + "/keep.png", gradient(5, 5));
  EXPECT_THROW(writePng(dir + "/keep.png", RgbImage()), RuntimeFailure);
  EXPECT_EQ(readPng(dir + "/keep.png").width, 5);
  EXPECT_EQ(test::listFiles(dir), "keep.png\n");
}

TEST(PngIo, CorruptFilesAreInputErrorsNamingTheFile) {
  const std::string dir = test::tempDir();
  writePng(dir + "/good.png", gradient(64, 64));
  std::ifstream in(dir + "/good.png", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir + "/truncated.png", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  std::string flipped = bytes;
  flipped[60] = char(flipped[60] ^ 0x5A);  // inside the compressed rows: the CRC fails
  std::ofstream(dir + "/flipped.png", std::ios::binary) << flipped;
  std::ofstream(dir + "/text.png") << "not a png at all";
  for (const char* name : {"truncated.png", "flipped.png", "text.png", "absent.png"}) {
    const std::string path = dir + "/" + name;
    try {
      readPng(path);
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
    }
  }
}

}  // namespace
}  // namespace vox
