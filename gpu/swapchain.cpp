#include "gpu/swapchain.h"

#include "geometry/error.h"
#include "gpu/vk_check.h"

#include <algorithm>
#include <cstdint>
#include <limits>

namespace vox::gpu {

namespace {

bool isBgr(VkFormat f) { return f == VK_FORMAT_B8G8R8A8_UNORM || f == VK_FORMAT_B8G8R8A8_SRGB; }

// Fills an image in VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL with one colour.
void clearTransferDst(VkCommandBuffer cmd, VkImage image, Rgb colour) {
  VkClearColorValue c{};
  c.float32[0] = float(colour.r) / 255.0f;
  c.float32[1] = float(colour.g) / 255.0f;
  c.float32[2] = float(colour.b) / 255.0f;
  c.float32[3] = 1.0f;
  const VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdClearColorImage(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &c, 1, &range);
}

}  // namespace

Swapchain::Swapchain(Context& context, VkSurfaceKHR surface, std::uint32_t width, std::uint32_t height, SwapchainOptions options)
    : context_(context), surface_(surface), options_(options) {
  VkBool32 presents = VK_FALSE;
  VOX_VK(vkGetPhysicalDeviceSurfaceSupportKHR(context.physicalDevice(), context.queueFamily(), surface, &presents));
  if (!presents) throw RuntimeFailure("Vulkan: the device's queue cannot present to this window");

  std::uint32_t n = 0;
  VOX_VK(vkGetPhysicalDeviceSurfaceFormatsKHR(context.physicalDevice(), surface, &n, nullptr));
  std::vector<VkSurfaceFormatKHR> formats(n);
  VOX_VK(vkGetPhysicalDeviceSurfaceFormatsKHR(context.physicalDevice(), surface, &n, formats.data()));
  // UNORM, so the ray caster's colours reach the screen as they reach PNGs.
  for (const VkSurfaceFormatKHR& f : formats)
    if (f.format == VK_FORMAT_B8G8R8A8_UNORM || f.format == VK_FORMAT_R8G8B8A8_UNORM) {
      format_ = f.format;
      colorSpace_ = f.colorSpace;
      break;
    }
  if (format_ == VK_FORMAT_UNDEFINED) throw RuntimeFailure("Vulkan: the window offers no 8-bit UNORM colour format");

  VkAttachmentDescription colour{};
  colour.format = format_;
  colour.samples = VK_SAMPLE_COUNT_1_BIT;
  colour.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
  colour.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  colour.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  colour.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  colour.initialLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  colour.finalLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
  VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 1;
  subpass.pColorAttachments = &ref;
  VkSubpassDependency dep{};
  dep.srcSubpass = VK_SUBPASS_EXTERNAL;
  dep.dstSubpass = 0;
  dep.srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  dep.dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  dep.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  dep.dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  VkRenderPassCreateInfo rpci{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  rpci.attachmentCount = 1;
  rpci.pAttachments = &colour;
  rpci.subpassCount = 1;
  rpci.pSubpasses = &subpass;
  rpci.dependencyCount = 1;
  rpci.pDependencies = &dep;
  VkDevice dev = context.device();
  VOX_VK(vkCreateRenderPass(dev, &rpci, nullptr, &renderPass_));

  VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  VOX_VK(vkCreateSemaphore(dev, &sci, nullptr, &acquired_));
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  fci.flags = VK_FENCE_CREATE_SIGNALED_BIT;
  VOX_VK(vkCreateFence(dev, &fci, nullptr, &inFlight_));
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = context.commandPool();
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  VOX_VK(vkAllocateCommandBuffers(dev, &cai, &commands_));
  create(width, height);
}

Swapchain::~Swapchain() {
  VkDevice dev = context_.device();
  vkDeviceWaitIdle(dev);
  destroyImages();
  if (swapchain_) vkDestroySwapchainKHR(dev, swapchain_, nullptr);
  if (commands_) vkFreeCommandBuffers(dev, context_.commandPool(), 1, &commands_);
  if (inFlight_) vkDestroyFence(dev, inFlight_, nullptr);
  if (acquired_) vkDestroySemaphore(dev, acquired_, nullptr);
  if (renderPass_) vkDestroyRenderPass(dev, renderPass_, nullptr);
}

void Swapchain::destroyImages() {
  VkDevice dev = context_.device();
  for (VkFramebuffer f : framebuffers_) vkDestroyFramebuffer(dev, f, nullptr);
  for (VkImageView v : views_) vkDestroyImageView(dev, v, nullptr);
  for (VkSemaphore s : renderDone_) vkDestroySemaphore(dev, s, nullptr);
  framebuffers_.clear();
  views_.clear();
  renderDone_.clear();
  images_.clear();
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
  for (VkImage image : images_) {
    VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vci.image = image;
    vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vci.format = format_;
    vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkImageView view = VK_NULL_HANDLE;
    VOX_VK(vkCreateImageView(dev, &vci, nullptr, &view));
    views_.push_back(view);
    VkFramebufferCreateInfo fci{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fci.renderPass = renderPass_;
    fci.attachmentCount = 1;
    fci.pAttachments = &views_.back();
    fci.width = extent_.width;
    fci.height = extent_.height;
    fci.layers = 1;
    VkFramebuffer fb = VK_NULL_HANDLE;
    VOX_VK(vkCreateFramebuffer(dev, &fci, nullptr, &fb));
    framebuffers_.push_back(fb);
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

std::optional<Swapchain::Frame> Swapchain::beginFrame() {
  VkDevice dev = context_.device();
  VOX_VK(vkWaitForFences(dev, 1, &inFlight_, VK_TRUE, UINT64_MAX));
  if (images_.empty()) return std::nullopt;
  std::uint32_t index = 0;
  const VkResult r = vkAcquireNextImageKHR(dev, swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &index);
  if (r == VK_ERROR_OUT_OF_DATE_KHR) return std::nullopt;
  if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR) vkCheck(r, "vkAcquireNextImageKHR");
  VOX_VK(vkResetFences(dev, 1, &inFlight_));
  VOX_VK(vkResetCommandBuffer(commands_, 0));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VOX_VK(vkBeginCommandBuffer(commands_, &bi));
  return Frame{commands_, index};
}

void Swapchain::toLayout(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to) {
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_COLOR_ATTACHMENT_READ_BIT |
                    VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                       VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, 0, 0, nullptr, 0, nullptr, 1, &b);
}

void Swapchain::blit(const Frame& frame, const Image2D& source, std::uint32_t left, Rgb background) {
  const VkImage image = images_[frame.image];
  toLayout(frame.commands, image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
  left = std::min(left, extent_.width - 1);
  if (left > 0) {
    clearTransferDst(frame.commands, image, background);
    VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    vkCmdPipelineBarrier(frame.commands, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &b, 0, nullptr, 0, nullptr);
  }
  VkImageBlit region{};
  region.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.srcOffsets[1] = {std::int32_t(source.width()), std::int32_t(source.height()), 1};
  region.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.dstOffsets[0] = {std::int32_t(left), 0, 0};
  region.dstOffsets[1] = {std::int32_t(extent_.width), std::int32_t(extent_.height), 1};
  const bool sameSize = source.width() == extent_.width - left && source.height() == extent_.height;
  vkCmdBlitImage(frame.commands, source.handle(), VK_IMAGE_LAYOUT_GENERAL, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region,
                 sameSize ? VK_FILTER_NEAREST : VK_FILTER_LINEAR);
  toLayout(frame.commands, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
}

void Swapchain::clear(const Frame& frame, Rgb colour) {
  const VkImage image = images_[frame.image];
  toLayout(frame.commands, image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
  clearTransferDst(frame.commands, image, colour);
  toLayout(frame.commands, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
}

void Swapchain::beginRenderPass(const Frame& frame) {
  VkRenderPassBeginInfo rbi{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  rbi.renderPass = renderPass_;
  rbi.framebuffer = framebuffers_[frame.image];
  rbi.renderArea.extent = extent_;
  vkCmdBeginRenderPass(frame.commands, &rbi, VK_SUBPASS_CONTENTS_INLINE);
}

void Swapchain::endRenderPass(const Frame& frame) { vkCmdEndRenderPass(frame.commands); }

bool Swapchain::endFrame(const Frame& frame, RgbImage* screenshot) {
  const VkImage image = images_[frame.image];
  const std::uint64_t bytes = 4 * std::uint64_t(extent_.width) * extent_.height;
  if (screenshot) {
    if (!readback_.valid() || readback_.size() < bytes) readback_ = Buffer(context_, bytes, MemoryIntent::Readback);
    toLayout(frame.commands, image, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    VkBufferImageCopy r{};
    r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    r.imageExtent = {extent_.width, extent_.height, 1};
    vkCmdCopyImageToBuffer(frame.commands, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback_.handle(), 1, &r);
    toLayout(frame.commands, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR);
    VkMemoryBarrier host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(frame.commands, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &host, 0, nullptr, 0, nullptr);
  }
  VOX_VK(vkEndCommandBuffer(frame.commands));
  const VkPipelineStageFlags waitStage = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.waitSemaphoreCount = 1;
  si.pWaitSemaphores = &acquired_;
  si.pWaitDstStageMask = &waitStage;
  si.commandBufferCount = 1;
  si.pCommandBuffers = &frame.commands;
  si.signalSemaphoreCount = 1;
  si.pSignalSemaphores = &renderDone_[frame.image];
  VOX_VK(vkQueueSubmit(context_.queue(), 1, &si, inFlight_));
  VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  pi.waitSemaphoreCount = 1;
  pi.pWaitSemaphores = &renderDone_[frame.image];
  pi.swapchainCount = 1;
  pi.pSwapchains = &swapchain_;
  pi.pImageIndices = &frame.image;
  const VkResult r = vkQueuePresentKHR(context_.queue(), &pi);
  if (screenshot) {
    VOX_VK(vkWaitForFences(context_.device(), 1, &inFlight_, VK_TRUE, UINT64_MAX));
    *screenshot = RgbImage(int(extent_.width), int(extent_.height));
    const auto* px = static_cast<const std::uint8_t*>(readback_.mapped());
    const bool bgr = isBgr(format_);
    for (std::size_t i = 0; i < screenshot->pixels.size(); ++i) {
      const std::uint8_t* p = px + 4 * i;
      screenshot->pixels[i] = bgr ? Rgb{p[2], p[1], p[0]} : Rgb{p[0], p[1], p[2]};
    }
  }
  if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR) return false;
  vkCheck(r, "vkQueuePresentKHR");
  return true;
}

}  // namespace vox::gpu
