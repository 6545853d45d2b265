// SHA-256 against the FIPS 180-4 example vectors (one block, two blocks with
// the padding spilling into the second, a million bytes), updates split at
// every offset around the block and padding boundaries, and files.

#include "geometry/error.h"
#include "geometry/sha256.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

namespace vox {
namespace {

const std::string kTwoBlocks = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";  // 56 bytes

TEST(Sha256, KnownVectors) {
  EXPECT_EQ(sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256Hex(kTwoBlocks), "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256Hex("abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklmnoijklmnopjklmnopqklmnopqrlmnopqrsmnopqrstnopqrstu"),
            "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1");
  EXPECT_EQ(sha256Hex(std::string(1000000, 'a')), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, PiecesGiveTheDigestOfTheWhole) {
  const std::string message = kTwoBlocks + kTwoBlocks + "tail";  // 116 bytes: crosses a block boundary
  const std::string whole = sha256Hex(message);
  for (std::size_t cut = 0; cut <= message.size(); ++cut) {
    Sha256 h;
    h.update(std::string_view(message).substr(0, cut));
    h.update(std::string_view(message).substr(cut));
    EXPECT_EQ(h.hex(), whole) << "cut at " << cut;
  }
  Sha256 bytes;
  for (const char c : message) bytes.update(&c, 1);
  EXPECT_EQ(bytes.hex(), whole);
}

TEST(Sha256, FileDigestAndUnreadableFile) {
  const std::string dir = test::tempDir();
  const std::string path = dir + "/a.bin";
  std::ofstream(path, std::ios::binary) << std::string(1000000, 'a');
  EXPECT_EQ(sha256OfFile(path), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  const std::string big = dir + "/big.bin";
  std::ofstream(big, std::ios::binary) << std::string(3 << 20, 'b');
  EXPECT_EQ(sha256OfFile(big), sha256Hex(std::string(3 << 20, 'b')));
  try {
    sha256OfFile(dir + "/missing.json");
    FAIL() << "no error for a missing file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.json: cannot open"), std::string::npos) << e.what();
  }
  EXPECT_THROW(sha256OfFile(dir), InputError);  // a directory cannot be read
}

}  // namespace
}  // namespace vox
