// Every VTU data encoding reads back to the same mesh.
#include "geometry/io/mesh_io.h"
#include "tests/geometry/io/mesh_test_meshes.h"
#include "tests/geometry/io/mesh_vtu_builder.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

namespace vox {
namespace {

using test::VtuEncoding;

TEST(VtuEncodings, AllCombinationsReadExactly) {
  const std::string dir = test::tempDir();
  const TetMesh mesh = test::labeledMesh();
  int files = 0;
  for (auto format : {VtuEncoding::Binary, VtuEncoding::AppendedRaw, VtuEncoding::AppendedBase64})
    for (bool zlib : {false, true})
      for (bool header64 : {false, true})
        for (bool bigEndian : {false, true}) {
          const VtuEncoding e{format, zlib, header64, bigEndian};
          const std::string name = "f" + std::to_string(int(format)) + (zlib ? "_zlib" : "") + (header64 ? "_u64" : "_u32") +
                                   (bigEndian ? "_be" : "_le") + ".vtu";
          SCOPED_TRACE(name);
          const std::string path = dir + "/" + name;
          test::writeText(path, test::vtuFile(mesh, e));
          test::expectSameMesh(mesh, readVtu(path));
          ++files;
        }
  EXPECT_EQ(files, 24);
  const std::string ascii = dir + "/ascii.vtu";
  test::writeText(ascii, test::vtuFile(mesh, {VtuEncoding::Ascii}));
  test::expectSameMesh(mesh, readVtu(ascii));
}

TEST(VtuEncodings, ZlibBlockSizesAndLastPartialBlock) {
  // Block sizes that divide the arrays exactly (last block full, "last size"
  // 0) and ones that leave a partial last block.
  const std::string dir = test::tempDir();
  const TetMesh mesh = test::junctionSphereMesh();
  for (std::size_t blockSize : {std::size_t(96), std::size_t(1000), std::size_t(32768), std::size_t(1) << 24}) {
    SCOPED_TRACE(blockSize);
    const std::string path = dir + "/b" + std::to_string(blockSize) + ".vtu";
    test::writeText(path, test::vtuFile(mesh, {VtuEncoding::AppendedRaw, true, false, false, blockSize}));
    test::expectSameMesh(mesh, readVtu(path));
  }
}

}  // namespace
}  // namespace vox
