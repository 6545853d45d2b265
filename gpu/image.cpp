#include "gpu/image.h"

#include "geometry/error.h"
#include "gpu/buffer.h"
#include "gpu/command.h"
#include "gpu/vk_check.h"

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

// Creates an optimal-tiling image of `type` in device memory with its view,
// transitioned to VK_IMAGE_LAYOUT_GENERAL. Fills image, memory and view; the
// caller releases them when this throws.
void createGeneralImage(Context& context, VkImageType type, VkExtent3D extent, VkFormat format, VkImageUsageFlags usage, VkImage& image,
                        VkDeviceMemory& memory, VkImageView& view) {
  VkDevice dev = context.device();
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
  VOX_VK(vkCreateImage(dev, &ici, nullptr, &image));
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(dev, image, &req);
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = context.findMemoryType(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  VOX_VK(vkAllocateMemory(dev, &mai, nullptr, &memory));
  VOX_VK(vkBindImageMemory(dev, image, memory, 0));
  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = image;
  vci.viewType = type == VK_IMAGE_TYPE_3D ? VK_IMAGE_VIEW_TYPE_3D : VK_IMAGE_VIEW_TYPE_2D;
  vci.format = format;
  vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  VOX_VK(vkCreateImageView(dev, &vci, nullptr, &view));
  CommandBatch batch(context);
  batch.transitionToGeneral(image);
  batch.submitAndWait();
}

void destroyImage(Context* context, VkImage& image, VkDeviceMemory& memory, VkImageView& view) {
  if (!context) return;
  VkDevice dev = context->device();
  if (view) vkDestroyImageView(dev, view, nullptr);
  if (image) vkDestroyImage(dev, image, nullptr);
  if (memory) vkFreeMemory(dev, memory, nullptr);
  view = VK_NULL_HANDLE;
  image = VK_NULL_HANDLE;
  memory = VK_NULL_HANDLE;
}

}  // namespace

Image3D::Image3D(Context& context, std::array<std::uint32_t, 3> extent, VkFormat format)
    : context_(&context), extent_(extent), format_(format) {
  const auto& info = context.info();
  for (auto e : extent)
    if (e == 0 || e > info.maxImageDimension3D)
      throw RuntimeFailure("3D image side " + std::to_string(e) + " exceeds the device limit of " +
                           std::to_string(info.maxImageDimension3D));
  const std::uint64_t bytes = std::uint64_t(extent[0]) * extent[1] * extent[2] * formatBytes(format);
  if (bytes > info.maxAllocationSize)
    throw RuntimeFailure("3D image of " + std::to_string(bytes) + " bytes exceeds the device's allocation limit");
  try {
    createGeneralImage(context, VK_IMAGE_TYPE_3D, {extent[0], extent[1], extent[2]}, format,
                       VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                           VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                       image_, memory_, view_);
  } catch (...) {
    release();
    throw;
  }
}

Image3D::~Image3D() { release(); }

std::uint64_t Image3D::texelBytes() const { return formatBytes(format_); }

void Image3D::release() {
  destroyImage(context_, image_, memory_, view_);
  context_ = nullptr;
}

Image3D::Image3D(Image3D&& o) noexcept
    : context_(std::exchange(o.context_, nullptr)),
      image_(std::exchange(o.image_, VK_NULL_HANDLE)),
      view_(std::exchange(o.view_, VK_NULL_HANDLE)),
      memory_(std::exchange(o.memory_, VK_NULL_HANDLE)),
      extent_(o.extent_),
      format_(o.format_) {}

Image3D& Image3D::operator=(Image3D&& o) noexcept {
  if (this != &o) {
    release();
    context_ = std::exchange(o.context_, nullptr);
    image_ = std::exchange(o.image_, VK_NULL_HANDLE);
    view_ = std::exchange(o.view_, VK_NULL_HANDLE);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
    extent_ = o.extent_;
    format_ = o.format_;
  }
  return *this;
}

void Image3D::upload(const void* src) {
  const std::uint64_t bytes = std::uint64_t(extent_[0]) * extent_[1] * extent_[2] * texelBytes();
  Buffer staging(*context_, bytes, MemoryIntent::Upload);
  std::memcpy(staging.mapped(), src, bytes);
  CommandBatch batch(*context_);
  batch.copy(staging, *this);
  batch.submitAndWait();
}

void Image3D::download(void* dst) const {
  const std::uint64_t bytes = std::uint64_t(extent_[0]) * extent_[1] * extent_[2] * texelBytes();
  Buffer staging(*context_, bytes, MemoryIntent::Readback);
  CommandBatch batch(*context_);
  batch.copy(*this, staging);
  batch.submitAndWait();
  std::memcpy(dst, staging.mapped(), bytes);
}

}  // namespace vox::gpu

namespace vox::gpu {

Image2D::Image2D(Context& context, std::uint32_t width, std::uint32_t height) : context_(&context), width_(width), height_(height) {
  if (width == 0 || height == 0 || width > 16384 || height > 16384)
    throw RuntimeFailure("2D image of " + std::to_string(width) + " x " + std::to_string(height) + " pixels is out of range");
  try {
    createGeneralImage(context, VK_IMAGE_TYPE_2D, {width, height, 1}, kFormat,
                       VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                           VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                       image_, memory_, view_);
  } catch (...) {
    release();
    throw;
  }
}

Image2D::~Image2D() { release(); }

void Image2D::release() {
  destroyImage(context_, image_, memory_, view_);
  context_ = nullptr;
}

Image2D::Image2D(Image2D&& o) noexcept
    : context_(std::exchange(o.context_, nullptr)),
      image_(std::exchange(o.image_, VK_NULL_HANDLE)),
      view_(std::exchange(o.view_, VK_NULL_HANDLE)),
      memory_(std::exchange(o.memory_, VK_NULL_HANDLE)),
      width_(o.width_),
      height_(o.height_) {}

Image2D& Image2D::operator=(Image2D&& o) noexcept {
  if (this != &o) {
    release();
    context_ = std::exchange(o.context_, nullptr);
    image_ = std::exchange(o.image_, VK_NULL_HANDLE);
    view_ = std::exchange(o.view_, VK_NULL_HANDLE);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
    width_ = o.width_;
    height_ = o.height_;
  }
  return *this;
}

RgbImage Image2D::download() const {
  const std::uint64_t bytes = 4 * std::uint64_t(width_) * height_;
  Buffer staging(*context_, bytes, MemoryIntent::Readback);
  CommandBatch batch(*context_);
  batch.copy(*this, staging);
  batch.submitAndWait();
  RgbImage out{int(width_), int(height_)};
  const auto* px = static_cast<const std::uint8_t*>(staging.mapped());
  for (std::size_t i = 0; i < out.pixels.size(); ++i) out.pixels[i] = {px[4 * i], px[4 * i + 1], px[4 * i + 2]};
  return out;
}

}  // namespace vox::gpu
