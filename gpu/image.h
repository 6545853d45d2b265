#pragma once
// 3D images (storage / sampled) and 2D colour images, kept in
// VK_IMAGE_LAYOUT_GENERAL.

#include "geometry/rgb_image.h"
#include "gpu/context.h"

#include <array>
#include <cstdint>

namespace vox::gpu {

// An image in device memory with its view, owned (destroyed with it).
// Created in VK_IMAGE_LAYOUT_GENERAL, where Image3D and Image2D keep it.
class DeviceImage {
public:
  DeviceImage() = default;
  DeviceImage(Context& context, VkImageType type, VkExtent3D extent, VkFormat format, VkImageUsageFlags usage);
  ~DeviceImage() { release(); }
  DeviceImage(DeviceImage&& other) noexcept;
  DeviceImage& operator=(DeviceImage&& other) noexcept;
  DeviceImage(const DeviceImage&) = delete;
  DeviceImage& operator=(const DeviceImage&) = delete;

  Context* context() const { return context_; }
  VkImage handle() const { return image_; }
  VkImageView view() const { return view_; }

private:
  void release();
  Context* context_ = nullptr;
  VkImage image_ = VK_NULL_HANDLE;
  VkImageView view_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
};

class Image3D {
public:
  Image3D() = default;
  // Throws RuntimeFailure when a side exceeds maxImageDimension3D or the
  // image exceeds the allocation limit.
  Image3D(Context& context, std::array<std::uint32_t, 3> extent, VkFormat format);

  const std::array<std::uint32_t, 3>& extent() const { return extent_; }
  VkFormat format() const { return format_; }
  VkImage handle() const { return image_.handle(); }
  VkImageView view() const { return image_.view(); }
  std::uint64_t texelBytes() const;

  // Whole-image copies from / to tightly packed host memory (x fastest),
  // staged in slabs of whole slices within the context's stagingBytes() (at
  // least one slice).
  void upload(const void* src);
  void download(void* dst) const;

private:
  std::uint32_t stagingSlices() const;  // slices per staged copy
  DeviceImage image_;
  std::array<std::uint32_t, 3> extent_{0, 0, 0};
  VkFormat format_ = VK_FORMAT_UNDEFINED;
};

// An RGBA8 2D image: kernels write it through a buffer copy, the swapchain
// blits it to the screen (scaled), nothing reads it back unless asked.
class Image2D {
public:
  static constexpr VkFormat kFormat = VK_FORMAT_R8G8B8A8_UNORM;

  Image2D() = default;
  // Throws RuntimeFailure for a side of 0 or over 16384 pixels.
  Image2D(Context& context, std::uint32_t width, std::uint32_t height);

  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  bool valid() const { return image_.handle() != VK_NULL_HANDLE; }
  VkImage handle() const { return image_.handle(); }
  VkImageView view() const { return image_.view(); }

  // Reads the image back (screenshots, tests); waits for the GPU.
  RgbImage download() const;

private:
  DeviceImage image_;
  std::uint32_t width_ = 0, height_ = 0;
};

}  // namespace vox::gpu
