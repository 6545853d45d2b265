#include "gpu/buffer.h"

#include "geometry/error.h"
#include "gpu/command.h"
#include "gpu/vk_check.h"

#include <algorithm>
#include <cstring>
#include <utility>

namespace vox::gpu {

Buffer::Buffer(Context& context, std::uint64_t bytes, MemoryIntent intent, VkBufferUsageFlags extraUsage)
    : context_(&context), size_(bytes) {
  if (bytes == 0) throw RuntimeFailure("GPU buffer of zero bytes requested");
  if (bytes > context.info().maxAllocationSize)
    throw RuntimeFailure("GPU buffer of " + std::to_string(bytes) + " bytes exceeds the device's allocation limit of " +
                         std::to_string(context.info().maxAllocationSize) + " bytes");
  VkDevice dev = context.device();
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = bytes;
  bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT | extraUsage;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VOX_VK(vkCreateBuffer(dev, &bci, nullptr, &buffer_));
  try {
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(dev, buffer_, &req);
    std::uint32_t type = 0;
    const VkMemoryPropertyFlags hostBits = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    switch (intent) {
      case MemoryIntent::Device: type = context.findMemoryType(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT); break;
      case MemoryIntent::Upload: type = context.findMemoryType(req.memoryTypeBits, hostBits); break;
      case MemoryIntent::Readback: type = context.findMemoryType(req.memoryTypeBits, hostBits, VK_MEMORY_PROPERTY_HOST_CACHED_BIT); break;
    }
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = req.size;
    mai.memoryTypeIndex = type;
    VOX_VK(vkAllocateMemory(dev, &mai, nullptr, &memory_));
    VOX_VK(vkBindBufferMemory(dev, buffer_, memory_, 0));
    const bool staged = intent == MemoryIntent::Device && context.stagesDeviceMemory();
    if (!staged && (context.memoryTypeFlags(type) & hostBits) == hostBits) VOX_VK(vkMapMemory(dev, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_));
  } catch (...) {
    release();
    throw;
  }
}

Buffer::~Buffer() { release(); }

void Buffer::release() {
  if (!context_) return;
  VkDevice dev = context_->device();
  if (mapped_) vkUnmapMemory(dev, memory_);
  if (buffer_) vkDestroyBuffer(dev, buffer_, nullptr);
  if (memory_) vkFreeMemory(dev, memory_, nullptr);
  mapped_ = nullptr;
  buffer_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
  context_ = nullptr;
  size_ = 0;
}

Buffer::Buffer(Buffer&& o) noexcept
    : context_(std::exchange(o.context_, nullptr)),
      buffer_(std::exchange(o.buffer_, VK_NULL_HANDLE)),
      memory_(std::exchange(o.memory_, VK_NULL_HANDLE)),
      size_(std::exchange(o.size_, 0)),
      mapped_(std::exchange(o.mapped_, nullptr)) {}

Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    release();
    context_ = std::exchange(o.context_, nullptr);
    buffer_ = std::exchange(o.buffer_, VK_NULL_HANDLE);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
    size_ = std::exchange(o.size_, 0);
    mapped_ = std::exchange(o.mapped_, nullptr);
  }
  return *this;
}

std::uint64_t stagingChunk(std::uint64_t bytes, std::uint64_t granule, std::uint64_t stagingBytes) {
  granule = std::max<std::uint64_t>(granule, 1);
  return std::min(bytes, std::max<std::uint64_t>(1, stagingBytes / granule) * granule);
}

void Buffer::write(std::uint64_t offset, std::uint64_t bytes, std::uint64_t granule, const Fill& fill) {
  if (bytes == 0) return;
  if (offset + bytes > size_) throw RuntimeFailure("GPU buffer write out of range");
  if (mapped_) {
    fill(0, bytes, static_cast<std::uint8_t*>(mapped_) + offset);
    return;
  }
  const std::uint64_t chunk = stagingChunk(bytes, granule, context_->stagingBytes());
  Buffer staging(*context_, chunk, MemoryIntent::Upload);
  CommandBatch batch(*context_);
  for (std::uint64_t first = 0; first < bytes; first += chunk) {
    const std::uint64_t n = std::min(chunk, bytes - first);
    fill(first, n, static_cast<std::uint8_t*>(staging.mapped()));
    batch.copy(staging, *this, n, 0, offset + first);
    batch.submitAndWait();
  }
}

void Buffer::upload(const void* src, std::uint64_t bytes, std::uint64_t offset) {
  const auto* from = static_cast<const std::uint8_t*>(src);
  write(offset, bytes, 1, [from](std::uint64_t first, std::uint64_t n, std::uint8_t* dst) { std::memcpy(dst, from + first, n); });
}

void Buffer::download(void* dst, std::uint64_t bytes, std::uint64_t offset) const {
  if (bytes == 0) return;
  if (offset + bytes > size_) throw RuntimeFailure("GPU buffer download out of range");
  if (mapped_) {
    std::memcpy(dst, static_cast<const char*>(mapped_) + offset, bytes);
    return;
  }
  const std::uint64_t chunk = stagingChunk(bytes, 1, context_->stagingBytes());
  Buffer staging(*context_, chunk, MemoryIntent::Readback);
  CommandBatch batch(*context_);
  for (std::uint64_t first = 0; first < bytes; first += chunk) {
    const std::uint64_t n = std::min(chunk, bytes - first);
    batch.copy(*this, staging, n, offset + first, 0);
    batch.submitAndWait();
    std::memcpy(static_cast<char*>(dst) + first, staging.mapped(), n);
  }
}

}  // namespace vox::gpu
