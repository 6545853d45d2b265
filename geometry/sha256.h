#pragma once
// SHA-256 (FIPS 180-4), for the input digests of a report's provenance
// (provenance.h): which grid, organ table and pose a result came from.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace vox {

// Incremental digest: update() with the message in any number of pieces,
// then hex() once.
class Sha256 {
public:
  Sha256();
  void update(const void* data, std::size_t bytes);
  void update(std::string_view text) { update(text.data(), text.size()); }
  // The 32-byte digest as 64 lowercase hex digits; the object is spent.
  std::string hex();

private:
  void compressBlock(const std::uint8_t* block);

  std::array<std::uint32_t, 8> state_;
  std::array<std::uint8_t, 64> buffer_{};
  std::size_t buffered_ = 0;
  std::uint64_t totalBytes_ = 0;
};

std::string sha256Hex(std::string_view text);
// Digest of a file's bytes, read in pieces; throws InputError(path, ...)
// when it cannot be opened or read.
std::string sha256OfFile(const std::string& path);

}  // namespace vox
