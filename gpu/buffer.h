#pragma once
// Device buffers with a memory intent. Every buffer can be bound as a storage
// buffer and used as a transfer source and destination.

#include "gpu/context.h"

#include <cstdint>
#include <functional>

namespace vox::gpu {

// Bytes per staged copy of `bytes`: whole granules (a slice, say) within
// `stagingBytes`, at least one granule, at most `bytes`.
std::uint64_t stagingChunk(std::uint64_t bytes, std::uint64_t granule, std::uint64_t stagingBytes);

enum class MemoryIntent {
  Device,    // fastest for the GPU; host access goes through a staging copy
  Upload,    // host-visible, written by the CPU, read by the GPU
  Readback,  // host-visible and cached, written by the GPU, read by the CPU
};

class Buffer {
public:
  Buffer() = default;
  // Throws RuntimeFailure when `bytes` exceeds the device's allocation limit.
  Buffer(Context& context, std::uint64_t bytes, MemoryIntent intent, VkBufferUsageFlags extraUsage = 0);
  ~Buffer();
  Buffer(Buffer&& other) noexcept;
  Buffer& operator=(Buffer&& other) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  std::uint64_t size() const { return size_; }
  VkBuffer handle() const { return buffer_; }
  bool valid() const { return buffer_ != VK_NULL_HANDLE; }
  // Host pointer when the memory is host visible, else nullptr.
  void* mapped() const { return mapped_; }

  // Host <-> buffer copies. When the memory is not host visible they go
  // through one temporary staging buffer of at most the context's
  // stagingBytes(), reused chunk by chunk, so a copy of any size holds at most
  // that much host memory besides the caller's. Must not overlap GPU work that
  // uses the same range.
  void upload(const void* src, std::uint64_t bytes, std::uint64_t offset = 0);
  void download(void* dst, std::uint64_t bytes, std::uint64_t offset = 0) const;
  // Writes bytes [offset, offset + bytes) in place: fill(first, n, dst) writes
  // the n bytes from `first` (relative to `offset`) at dst. Mapped memory gets
  // one call; otherwise one call per staging chunk, each a whole multiple of
  // `granule` bytes (at least one granule) but the last, so a producer that
  // works in units (slices of a grid) never splits one.
  using Fill = std::function<void(std::uint64_t first, std::uint64_t n, std::uint8_t* dst)>;
  void write(std::uint64_t offset, std::uint64_t bytes, std::uint64_t granule, const Fill& fill);

private:
  void release();
  Context* context_ = nullptr;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  std::uint64_t size_ = 0;
  void* mapped_ = nullptr;
};

}  // namespace vox::gpu
