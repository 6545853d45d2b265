#include "gpu/swapchain.h"

#include "geometry/error.h"
#include "gpu/vk_check.h"

#include <algorithm>
#include <cstdint>
#include <limits>

namespace vox::gpu {

namespace {

VkSurfaceFormatKHR surfaceFormat(Context& context, VkSurfaceKHR surface) {
  VkBool32 presents = VK_FALSE;
  VOX_VK(vkGetPhysicalDeviceSurfaceSupportKHR(context.physicalDevice(), context.queueFamily(), surface, &presents));
  if (!presents) throw RuntimeFailure("Vulkan: the device's queue cannot present to this window");
  std::uint32_t n = 0;
  VOX_VK(vkGetPhysicalDeviceSurfaceFormatsKHR(context.physicalDevice(), surface, &n, nullptr));
  std::vector<VkSurfaceFormatKHR> formats(n);
  VOX_VK(vkGetPhysicalDeviceSurfaceFormatsKHR(context.physicalDevice(), surface, &n, formats.data()));
  // UNORM, so the ray caster's colours reach the screen as they reach PNGs.
  for (const VkSurfaceFormatKHR& f : formats)
    if (f.format == VK_FORMAT_B8G8R8A8_UNORM || f.format == VK_FORMAT_R8G8B8A8_UNORM) return f;
  throw RuntimeFailure("Vulkan: the window offers no 8-bit UNORM colour format");
}

}  // namespace

Swapchain::Swapchain(Context& context, VkSurfaceKHR surface, std::uint32_t width, std::uint32_t height, SwapchainOptions options)
    : Swapchain(context, surface, surfaceFormat(context, surface), width, height, options) {}

Swapchain::Swapchain(Context& context, VkSurfaceKHR surface, VkSurfaceFormatKHR format, std::uint32_t width, std::uint32_t height,
                     SwapchainOptions options)
    : RenderTarget(context, format.format, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR),
      surface_(surface),
      options_(options),
      colorSpace_(format.colorSpace) {
  VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  VOX_VK(vkCreateSemaphore(context.device(), &sci, nullptr, &acquired_));
  create(width, height);
}

Swapchain::~Swapchain() {
  VkDevice dev = context_.device();
  vkDeviceWaitIdle(dev);
  destroyImages();
  if (swapchain_) vkDestroySwapchainKHR(dev, swapchain_, nullptr);
  if (acquired_) vkDestroySemaphore(dev, acquired_, nullptr);
}

void Swapchain::destroyImages() {
  destroyFramebuffers();
  for (VkSemaphore s : renderDone_) vkDestroySemaphore(context_.device(), s, nullptr);
  renderDone_.clear();
}

void Swapchain::create(std::uint32_t width, std::uint32_t height) {
  VkPhysicalDevice pd = context_.physicalDevice();
  VkDevice dev = context_.device();
  VkSurfaceCapabilitiesKHR caps;
  VOX_VK(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(pd, surface_, &caps));
  if (caps.currentExtent.width != std::numeric_limits<std::uint32_t>::max()) {
    extent_ = caps.currentExtent;
  } else {
    extent_.width = std::clamp(width, caps.minImageExtent.width, caps.maxImageExtent.width);
    extent_.height = std::clamp(height, caps.minImageExtent.height, caps.maxImageExtent.height);
  }
  if (extent_.width == 0 || extent_.height == 0) return;  // minimised: nothing to draw into
  constexpr VkImageUsageFlags kUsage =
      VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  if ((caps.supportedUsageFlags & kUsage) != kUsage)
    throw RuntimeFailure("Vulkan: the window's images cannot be blitted to and read back");

  VkPresentModeKHR mode = VK_PRESENT_MODE_FIFO_KHR;
  if (!options_.vsync) {
    std::uint32_t n = 0;
    VOX_VK(vkGetPhysicalDeviceSurfacePresentModesKHR(pd, surface_, &n, nullptr));
    std::vector<VkPresentModeKHR> modes(n);
    VOX_VK(vkGetPhysicalDeviceSurfacePresentModesKHR(pd, surface_, &n, modes.data()));
    for (VkPresentModeKHR m : {VK_PRESENT_MODE_MAILBOX_KHR, VK_PRESENT_MODE_IMMEDIATE_KHR})
      if (std::find(modes.begin(), modes.end(), m) != modes.end()) {
        mode = m;
        break;
      }
  }
  minImageCount_ = std::max<std::uint32_t>(2, caps.minImageCount);
  std::uint32_t count = minImageCount_ + 1;
  if (caps.maxImageCount > 0) count = std::min(count, caps.maxImageCount);

  VkSwapchainCreateInfoKHR ci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  ci.surface = surface_;
  ci.minImageCount = count;
  ci.imageFormat = format_;
  ci.imageColorSpace = colorSpace_;
  ci.imageExtent = extent_;
  ci.imageArrayLayers = 1;
  ci.imageUsage = kUsage;
  ci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  ci.preTransform = caps.currentTransform;
  ci.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  ci.presentMode = mode;
  ci.clipped = VK_TRUE;
  ci.oldSwapchain = swapchain_;
  VkSwapchainKHR created = VK_NULL_HANDLE;
  VOX_VK(vkCreateSwapchainKHR(dev, &ci, nullptr, &created));
  if (swapchain_) vkDestroySwapchainKHR(dev, swapchain_, nullptr);
  swapchain_ = created;

  std::uint32_t n = 0;
  VOX_VK(vkGetSwapchainImagesKHR(dev, swapchain_, &n, nullptr));
  images_.resize(n);
  VOX_VK(vkGetSwapchainImagesKHR(dev, swapchain_, &n, images_.data()));
  createFramebuffers();
  for (std::uint32_t i = 0; i < n; ++i) {
    VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    VkSemaphore s = VK_NULL_HANDLE;
    VOX_VK(vkCreateSemaphore(dev, &sci, nullptr, &s));
    renderDone_.push_back(s);
  }
}

void Swapchain::resize(std::uint32_t width, std::uint32_t height) {
  vkDeviceWaitIdle(context_.device());
  destroyImages();
  create(width, height);
}

std::optional<RenderTarget::Frame> Swapchain::beginFrame() {
  waitForPreviousFrame();
  if (images_.empty()) return std::nullopt;
  std::uint32_t index = 0;
  const VkResult r = vkAcquireNextImageKHR(context_.device(), swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &index);
  if (r == VK_ERROR_OUT_OF_DATE_KHR) return std::nullopt;
  if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR) vkCheck(r, "vkAcquireNextImageKHR");
  return beginRecording(index);
}

bool Swapchain::endFrame(const Frame& frame, RgbImage* screenshot) {
  if (screenshot) recordReadback(frame);
  submit(frame, acquired_, renderDone_[frame.image]);
  VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  pi.waitSemaphoreCount = 1;
  pi.pWaitSemaphores = &renderDone_[frame.image];
  pi.swapchainCount = 1;
  pi.pSwapchains = &swapchain_;
  pi.pImageIndices = &frame.image;
  const VkResult r = vkQueuePresentKHR(context_.queue(), &pi);
  if (screenshot) finishReadback(*screenshot);
  if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR) return false;
  vkCheck(r, "vkQueuePresentKHR");
  return true;
}

}  // namespace vox::gpu
