// Host <-> device copies through bounded staging buffers (gpu/buffer.h,
// gpu/image.h), on a context that stages device memory even where it is host
// visible, so the discrete-GPU path runs on lavapipe too.

#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/image.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

namespace vox {
namespace {

// Staging buffers of `bytes`, as small as the tests need to make many chunks.
gpu::Context& stagedContext(std::uint64_t bytes) {
  static std::map<std::uint64_t, std::unique_ptr<gpu::Context>> contexts;
  auto& ctx = contexts[bytes];
  if (!ctx) ctx = std::make_unique<gpu::Context>(gpu::ContextOptions{.stageDeviceMemory = true, .stagingBytes = bytes});
  return *ctx;
}

std::vector<std::uint8_t> pattern(std::size_t n, std::uint32_t seed) {
  std::vector<std::uint8_t> v(n);
  std::uint32_t x = seed;
  for (auto& b : v) {
    x = x * 1664525u + 1013904223u;
    b = std::uint8_t(x >> 24);
  }
  return v;
}

TEST(StagingGpu, BufferCopiesInChunksRoundTrip) {
  const std::uint64_t bytes = 1000003;
  const auto data = pattern(bytes, 7);
  const auto part = pattern(20000, 11);
  for (std::uint64_t staging : {std::uint64_t(4103), std::uint64_t(5000), std::uint64_t(1) << 26}) {
    gpu::Buffer buffer(stagedContext(staging), bytes, gpu::MemoryIntent::Device);
    ASSERT_EQ(buffer.mapped(), nullptr);  // staged, as on a discrete GPU
    buffer.upload(data.data(), bytes);
    std::vector<std::uint8_t> back(bytes, 0);
    buffer.download(back.data(), bytes);
    EXPECT_EQ(back, data) << staging;
    // A range inside the buffer; the rest must stay.
    buffer.upload(part.data(), part.size(), 12345);
    buffer.download(back.data(), bytes);
    for (std::uint64_t i = 0; i < bytes; ++i) {
      const std::uint8_t want = (i >= 12345 && i < 12345 + part.size()) ? part[i - 12345] : data[i];
      ASSERT_EQ(back[i], want) << i << ", staging " << staging;
    }
    // Part of the buffer read back from an offset.
    std::vector<std::uint8_t> tail(30001);
    buffer.download(tail.data(), tail.size(), bytes - tail.size());
    EXPECT_TRUE(std::equal(tail.begin(), tail.end(), data.end() - std::ptrdiff_t(tail.size()))) << staging;
  }
}

TEST(StagingGpu, WriteFillsWholeGranulesPerChunk) {
  const std::uint64_t granule = 1000, bytes = 23 * granule;
  const auto data = pattern(bytes, 3);
  for (std::uint64_t staging : {std::uint64_t(4500), std::uint64_t(700), std::uint64_t(1) << 20}) {
    gpu::Buffer buffer(stagedContext(staging), bytes + 64, gpu::MemoryIntent::Device);
    std::vector<std::pair<std::uint64_t, std::uint64_t>> calls;
    buffer.write(64, bytes, granule, [&](std::uint64_t first, std::uint64_t n, std::uint8_t* dst) {
      calls.emplace_back(first, n);
      std::copy(data.begin() + std::ptrdiff_t(first), data.begin() + std::ptrdiff_t(first + n), dst);
    });
    // Whole granules, within the staging size unless one granule exceeds it.
    const std::uint64_t chunk = staging >= granule ? std::min(bytes, staging / granule * granule) : granule;
    ASSERT_EQ(calls.size(), (bytes + chunk - 1) / chunk) << staging;
    std::uint64_t next = 0;
    for (const auto& [first, n] : calls) {
      EXPECT_EQ(first, next);
      EXPECT_EQ(n % granule, 0u);
      EXPECT_LE(n, chunk);
      next = first + n;
    }
    EXPECT_EQ(next, bytes);
    std::vector<std::uint8_t> back(bytes);
    buffer.download(back.data(), bytes, 64);
    EXPECT_EQ(back, data) << staging;
  }
}

TEST(StagingGpu, ImageCopiesInSlabsRoundTrip) {
  const std::uint64_t slice = 37 * 23 * 2, bytes = slice * 19;
  const auto data = pattern(bytes, 5);
  // Two slices per copy, one (a staging buffer smaller than a slice still
  // takes one), the whole image.
  for (std::uint64_t staging : {3 * slice - 1, std::uint64_t(1), std::uint64_t(1) << 26}) {
    gpu::Image3D image(stagedContext(staging), {37, 23, 19}, VK_FORMAT_R16_UINT);
    image.upload(data.data());
    std::vector<std::uint8_t> back(bytes, 0);
    image.download(back.data());
    EXPECT_EQ(back, data) << staging;
  }
}

}  // namespace
}  // namespace vox
