#include "gpu/render_target.h"

#include "gpu/vk_check.h"

#include <algorithm>
#include <cstdint>

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

RenderTarget::RenderTarget(Context& context, VkFormat format, VkImageLayout finalLayout)
    : context_(context), format_(format), finalLayout_(finalLayout) {
  VkAttachmentDescription colour{};
  colour.format = format_;
  colour.samples = VK_SAMPLE_COUNT_1_BIT;
  colour.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
  colour.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  colour.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  colour.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  colour.initialLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  colour.finalLayout = finalLayout_;
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

  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  fci.flags = VK_FENCE_CREATE_SIGNALED_BIT;
  VOX_VK(vkCreateFence(dev, &fci, nullptr, &inFlight_));
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = context.commandPool();
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  VOX_VK(vkAllocateCommandBuffers(dev, &cai, &commands_));
}

RenderTarget::~RenderTarget() {
  VkDevice dev = context_.device();
  vkDeviceWaitIdle(dev);
  destroyFramebuffers();
  if (commands_) vkFreeCommandBuffers(dev, context_.commandPool(), 1, &commands_);
  if (inFlight_) vkDestroyFence(dev, inFlight_, nullptr);
  if (renderPass_) vkDestroyRenderPass(dev, renderPass_, nullptr);
}

void RenderTarget::createFramebuffers() {
  VkDevice dev = context_.device();
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
  }
}

void RenderTarget::destroyFramebuffers() {
  VkDevice dev = context_.device();
  for (VkFramebuffer f : framebuffers_) vkDestroyFramebuffer(dev, f, nullptr);
  for (VkImageView v : views_) vkDestroyImageView(dev, v, nullptr);
  framebuffers_.clear();
  views_.clear();
  images_.clear();
}

void RenderTarget::waitForPreviousFrame() { VOX_VK(vkWaitForFences(context_.device(), 1, &inFlight_, VK_TRUE, UINT64_MAX)); }

RenderTarget::Frame RenderTarget::beginRecording(std::uint32_t image) {
  VOX_VK(vkResetFences(context_.device(), 1, &inFlight_));
  VOX_VK(vkResetCommandBuffer(commands_, 0));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VOX_VK(vkBeginCommandBuffer(commands_, &bi));
  return Frame{commands_, image};
}

void RenderTarget::toLayout(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to) {
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

void RenderTarget::blit(const Frame& frame, const Image2D& source, std::uint32_t left, Rgb background) {
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

void RenderTarget::clear(const Frame& frame, Rgb colour) {
  const VkImage image = images_[frame.image];
  toLayout(frame.commands, image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
  clearTransferDst(frame.commands, image, colour);
  toLayout(frame.commands, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
}

void RenderTarget::beginRenderPass(const Frame& frame) {
  VkRenderPassBeginInfo rbi{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  rbi.renderPass = renderPass_;
  rbi.framebuffer = framebuffers_[frame.image];
  rbi.renderArea.extent = extent_;
  vkCmdBeginRenderPass(frame.commands, &rbi, VK_SUBPASS_CONTENTS_INLINE);
}

void RenderTarget::endRenderPass(const Frame& frame) { vkCmdEndRenderPass(frame.commands); }

void RenderTarget::recordReadback(const Frame& frame) {
  const VkImage image = images_[frame.image];
  const std::uint64_t bytes = 4 * std::uint64_t(extent_.width) * extent_.height;
  if (!readback_.valid() || readback_.size() < bytes) readback_ = Buffer(context_, bytes, MemoryIntent::Readback);
  toLayout(frame.commands, image, finalLayout_, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
  VkBufferImageCopy r{};
  r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  r.imageExtent = {extent_.width, extent_.height, 1};
  vkCmdCopyImageToBuffer(frame.commands, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback_.handle(), 1, &r);
  toLayout(frame.commands, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, finalLayout_);
  VkMemoryBarrier host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(frame.commands, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &host, 0, nullptr, 0, nullptr);
}

void RenderTarget::submit(const Frame& frame, VkSemaphore wait, VkSemaphore signal) {
  VOX_VK(vkEndCommandBuffer(frame.commands));
  const VkPipelineStageFlags waitStage = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.waitSemaphoreCount = wait ? 1 : 0;
  si.pWaitSemaphores = &wait;
  si.pWaitDstStageMask = &waitStage;
  si.commandBufferCount = 1;
  si.pCommandBuffers = &frame.commands;
  si.signalSemaphoreCount = signal ? 1 : 0;
  si.pSignalSemaphores = &signal;
  VOX_VK(vkQueueSubmit(context_.queue(), 1, &si, inFlight_));
}

void RenderTarget::finishReadback(RgbImage& screenshot) {
  waitForPreviousFrame();
  screenshot = RgbImage(int(extent_.width), int(extent_.height));
  const auto* px = static_cast<const std::uint8_t*>(readback_.mapped());
  const bool bgr = isBgr(format_);
  for (std::size_t i = 0; i < screenshot.pixels.size(); ++i) {
    const std::uint8_t* p = px + 4 * i;
    screenshot.pixels[i] = bgr ? Rgb{p[2], p[1], p[0]} : Rgb{p[0], p[1], p[2]};
  }
}

}  // namespace vox::gpu
