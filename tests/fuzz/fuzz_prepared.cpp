// libFuzzer harness: the prepared state's reader (deform/prepared_state.h,
// io/section_file.h) on arbitrary bytes in memory. Its CRC-32 and length
// would stop nearly every mutation at the header, so the harness first makes
// both match the bytes (when there are enough of them): the section table,
// the inflation and every section's unpacking are fuzzed. InputError is the
// one allowed outcome besides success.

#include "geometry/deform/prepared_state.h"
#include "geometry/error.h"

#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (bytes.size() >= 28 && bytes.compare(0, 8, "VXPREP\r\n") == 0) {
    const std::uint64_t total = bytes.size();
    std::memcpy(bytes.data() + 12, &total, 8);
    const auto crc = std::uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()), uInt(bytes.size() - 4)));
    std::memcpy(bytes.data() + bytes.size() - 4, &crc, 4);
  }
  try {
    vox::PreparedState::fromBytes(std::move(bytes), "fuzz.vxprep");
  } catch (const vox::InputError&) {
  }
  return 0;
}
