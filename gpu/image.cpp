#include "gpu/image.h"

#include "geometry/error.h"
#include "gpu/buffer.h"
#include "gpu/command.h"
#include "gpu/vk_check.h"

#include <algorithm>
#include <cstring>
#include <utility>

namespace vox::gpu {

namespace {
std::uint64_t formatBytes(VkFormat f) {
  switch (f) {
    case VK_FORMAT_R8_UINT:
    case VK_FORMAT_R8_UNORM: return 1;
    case VK_FORMAT_R16_UINT:
    case VK_FORMAT_R16_UNORM: return 2;
    case VK_FORMAT_R32_UINT:
    case VK_FORMAT_R32_SFLOAT:
    case VK_FORMAT_R8G8B8A8_UNORM: return 4;
    case VK_FORMAT_R32G32B32A32_SFLOAT: return 16;
    default: throw RuntimeFailure("Image3D: unsupported format " + std::to_string(int(f)));
  }
}

}  // namespace

DeviceImage::DeviceImage(Context& context, VkImageType type, VkExtent3D extent, VkFormat format, VkImageUsageFlags usage)
    : context_(&context) {
  VkDevice dev = context.device();
  try {
    VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ici.imageType = type;
    ici.format = format;
    ici.extent = extent;
    ici.mipLevels = 1;
    ici.arrayLayers = 1;
    ici.samples = VK_SAMPLE_COUNT_1_BIT;
    ici.tiling = VK_IMAGE_TILING_OPTIMAL;
    ici.usage = usage;
    ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    VOX_VK(vkCreateImage(dev, &ici, nullptr, &image_));
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(dev, image_, &req);
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = req.size;
    mai.memoryTypeIndex = context.findMemoryType(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    VOX_VK(vkAllocateMemory(dev, &mai, nullptr, &memory_));
    VOX_VK(vkBindImageMemory(dev, image_, memory_, 0));
    VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vci.image = image_;
    vci.viewType = type == VK_IMAGE_TYPE_3D ? VK_IMAGE_VIEW_TYPE_3D : VK_IMAGE_VIEW_TYPE_2D;
    vci.format = format;
    vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VOX_VK(vkCreateImageView(dev, &vci, nullptr, &view_));
    CommandBatch batch(context);
    batch.transitionToGeneral(image_);
    batch.submitAndWait();
  } catch (...) {
    release();
    throw;
  }
}

void DeviceImage::release() {
  if (!context_) return;
  VkDevice dev = context_->device();
  if (view_) vkDestroyImageView(dev, view_, nullptr);
  if (image_) vkDestroyImage(dev, image_, nullptr);
  if (memory_) vkFreeMemory(dev, memory_, nullptr);
  view_ = VK_NULL_HANDLE;
  image_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
  context_ = nullptr;
}

DeviceImage::DeviceImage(DeviceImage&& o) noexcept
    : context_(std::exchange(o.context_, nullptr)),
      image_(std::exchange(o.image_, VK_NULL_HANDLE)),
      view_(std::exchange(o.view_, VK_NULL_HANDLE)),
      memory_(std::exchange(o.memory_, VK_NULL_HANDLE)) {}

DeviceImage& DeviceImage::operator=(DeviceImage&& o) noexcept {
  if (this != &o) {
    release();
    context_ = std::exchange(o.context_, nullptr);
    image_ = std::exchange(o.image_, VK_NULL_HANDLE);
    view_ = std::exchange(o.view_, VK_NULL_HANDLE);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
  }
  return *this;
}

Image3D::Image3D(Context& context, std::array<std::uint32_t, 3> extent, VkFormat format) : extent_(extent), format_(format) {
  const auto& info = context.info();
  for (auto e : extent)
    if (e == 0 || e > info.maxImageDimension3D)
      throw RuntimeFailure("3D image side " + std::to_string(e) + " exceeds the device limit of " +
                           std::to_string(info.maxImageDimension3D));
  const std::uint64_t bytes = std::uint64_t(extent[0]) * extent[1] * extent[2] * formatBytes(format);
  if (bytes > info.maxAllocationSize)
    throw RuntimeFailure("3D image of " + std::to_string(bytes) + " bytes exceeds the device's allocation limit");
  image_ = DeviceImage(context, VK_IMAGE_TYPE_3D, {extent[0], extent[1], extent[2]}, format,
                       VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                           VK_IMAGE_USAGE_TRANSFER_SRC_BIT);
}

std::uint64_t Image3D::texelBytes() const { return formatBytes(format_); }

// Both directions go slab by slab through one staging buffer of at most
// the context's stagingBytes() (whole slices, at least one), so an image of
// any size holds at most that much host memory besides the caller's.
std::uint32_t Image3D::stagingSlices() const {
  const std::uint64_t slice = std::uint64_t(extent_[0]) * extent_[1] * texelBytes();
  return std::uint32_t(stagingChunk(slice * extent_[2], slice, image_.context()->stagingBytes()) / slice);
}

void Image3D::upload(const void* src) {
  const std::uint64_t slice = std::uint64_t(extent_[0]) * extent_[1] * texelBytes();
  const std::uint32_t step = stagingSlices();
  Buffer staging(*image_.context(), step * slice, MemoryIntent::Upload);
  CommandBatch batch(*image_.context());
  for (std::uint32_t z0 = 0; z0 < extent_[2]; z0 += step) {
    const std::uint32_t depth = std::min(step, extent_[2] - z0);
    std::memcpy(staging.mapped(), static_cast<const std::uint8_t*>(src) + z0 * slice, depth * slice);
    batch.copy(staging, *this, z0, depth);
    batch.submitAndWait();
  }
}

void Image3D::download(void* dst) const {
  const std::uint64_t slice = std::uint64_t(extent_[0]) * extent_[1] * texelBytes();
  const std::uint32_t step = stagingSlices();
  Buffer staging(*image_.context(), step * slice, MemoryIntent::Readback);
  CommandBatch batch(*image_.context());
  for (std::uint32_t z0 = 0; z0 < extent_[2]; z0 += step) {
    const std::uint32_t depth = std::min(step, extent_[2] - z0);
    batch.copy(*this, staging, z0, depth);
    batch.submitAndWait();
    std::memcpy(static_cast<std::uint8_t*>(dst) + z0 * slice, staging.mapped(), depth * slice);
  }
}

Image2D::Image2D(Context& context, std::uint32_t width, std::uint32_t height) : width_(width), height_(height) {
  if (width == 0 || height == 0 || width > 16384 || height > 16384)
    throw RuntimeFailure("2D image of " + std::to_string(width) + " x " + std::to_string(height) + " pixels is out of range");
  image_ = DeviceImage(context, VK_IMAGE_TYPE_2D, {width, height, 1}, kFormat,
                       VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                           VK_IMAGE_USAGE_TRANSFER_SRC_BIT);
}

RgbImage Image2D::download() const {
  const std::uint64_t bytes = 4 * std::uint64_t(width_) * height_;
  Buffer staging(*image_.context(), bytes, MemoryIntent::Readback);
  CommandBatch batch(*image_.context());
  batch.copy(*this, staging);
  batch.submitAndWait();
  RgbImage out{int(width_), int(height_)};
  const auto* px = static_cast<const std::uint8_t*>(staging.mapped());
  for (std::size_t i = 0; i < out.pixels.size(); ++i) out.pixels[i] = {px[4 * i], px[4 * i + 1], px[4 * i + 2]};
  return out;
}

}  // namespace vox::gpu
