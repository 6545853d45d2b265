#pragma once
// Swapchain: what presenting to a window surface needs on top of Context (a
// queue family that draws and presents: ContextOptions::acceptQueue): the
// swapchain images, one render pass that draws over what the frame's
// commands put in the image (the viewer's UI over the blitted ray-cast
// image), framebuffers, and the frame's synchronisation (an acquire
// semaphore, one render-done semaphore per image, a fence). One frame is in
// flight: beginFrame() waits for the previous one, so the images a frame
// reads (the ray-cast Image2D) may be rewritten as soon as it returns.
//
//   auto frame = swapchain.beginFrame();     // nullopt: resize, then retry
//   swapchain.blit(*frame, rayCastImage);    // scaled to the whole image
//   swapchain.beginRenderPass(*frame); ... UI ...; swapchain.endRenderPass(*frame);
//   swapchain.endFrame(*frame, &screenshot); // submit and present
//
// The surface belongs to the caller (gpu/ knows no window system) and must
// outlive the swapchain.

#include "geometry/rgb_image.h"
#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/image.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace vox::gpu {

struct SwapchainOptions {
  bool vsync = true;  // FIFO; else MAILBOX or IMMEDIATE when offered
};

class Swapchain {
public:
  // Throws RuntimeFailure when the surface offers no usable format or the
  // queue cannot present to it.
  Swapchain(Context& context, VkSurfaceKHR surface, std::uint32_t width, std::uint32_t height, SwapchainOptions options = {});
  ~Swapchain();
  Swapchain(const Swapchain&) = delete;
  Swapchain& operator=(const Swapchain&) = delete;

  // Recreates the images for a new window size (waits for the device).
  void resize(std::uint32_t width, std::uint32_t height);

  struct Frame {
    VkCommandBuffer commands = VK_NULL_HANDLE;  // recording
    std::uint32_t image = 0;                    // swapchain image index
  };
  // Waits for the previous frame, acquires an image and begins recording;
  // nullopt when the swapchain no longer matches the surface (resize first).
  std::optional<Frame> beginFrame();
  // Fills the frame's image with `background`, then `source` scaled (linear
  // filter) into the columns from `left` to the right edge.
  void blit(const Frame& frame, const Image2D& source, std::uint32_t left = 0, Rgb background = {});
  // Fills the frame's image with one colour (nothing to blit yet).
  void clear(const Frame& frame, Rgb colour);
  void beginRenderPass(const Frame& frame);
  void endRenderPass(const Frame& frame);
  // Submits and presents. With `screenshot`, the presented image is also
  // read back into it (waits for the GPU). Returns false when the swapchain
  // is out of date (resize before the next frame).
  bool endFrame(const Frame& frame, RgbImage* screenshot = nullptr);

  VkRenderPass renderPass() const { return renderPass_; }
  VkFormat format() const { return format_; }
  std::uint32_t width() const { return extent_.width; }
  std::uint32_t height() const { return extent_.height; }
  std::uint32_t imageCount() const { return std::uint32_t(images_.size()); }
  std::uint32_t minImageCount() const { return minImageCount_; }

private:
  void create(std::uint32_t width, std::uint32_t height);
  void destroyImages();
  void toLayout(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to);

  Context& context_;
  VkSurfaceKHR surface_;
  SwapchainOptions options_;
  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  VkColorSpaceKHR colorSpace_ = VK_COLOR_SPACE_SRGB_NONLINEAR_KHR;
  VkExtent2D extent_{0, 0};
  std::uint32_t minImageCount_ = 2;
  VkRenderPass renderPass_ = VK_NULL_HANDLE;
  std::vector<VkImage> images_;
  std::vector<VkImageView> views_;
  std::vector<VkFramebuffer> framebuffers_;
  std::vector<VkSemaphore> renderDone_;  // per image: presentation may still wait on it
  VkSemaphore acquired_ = VK_NULL_HANDLE;
  VkFence inFlight_ = VK_NULL_HANDLE;
  VkCommandBuffer commands_ = VK_NULL_HANDLE;
  Buffer readback_;
};

}  // namespace vox::gpu
