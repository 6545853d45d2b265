#pragma once
// 3D images (storage / sampled) kept in VK_IMAGE_LAYOUT_GENERAL.

#include "gpu/context.h"

#include <array>
#include <cstdint>

namespace vox::gpu {

class Image3D {
public:
  Image3D() = default;
  // Throws RuntimeFailure when a side exceeds maxImageDimension3D or the
  // image exceeds the allocation limit.
  Image3D(Context& context, std::array<std::uint32_t, 3> extent, VkFormat format);
  ~Image3D();
  Image3D(Image3D&& other) noexcept;
  Image3D& operator=(Image3D&& other) noexcept;
  Image3D(const Image3D&) = delete;
  Image3D& operator=(const Image3D&) = delete;

  const std::array<std::uint32_t, 3>& extent() const { return extent_; }
  VkFormat format() const { return format_; }
  VkImage handle() const { return image_; }
  VkImageView view() const { return view_; }
  std::uint64_t texelBytes() const;

  // Whole-image copies from / to tightly packed host memory (x fastest).
  void upload(const void* src);
  void download(void* dst) const;

private:
  void release();
  Context* context_ = nullptr;
  VkImage image_ = VK_NULL_HANDLE;
  VkImageView view_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  std::array<std::uint32_t, 3> extent_{0, 0, 0};
  VkFormat format_ = VK_FORMAT_UNDEFINED;
};

}  // namespace vox::gpu
