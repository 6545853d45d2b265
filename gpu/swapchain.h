#pragma once
// Swapchain: the RenderTarget (gpu/render_target.h) of a window surface.
// What presenting needs on top of Context (a queue family that draws and
// presents: ContextOptions::acceptQueue): the swapchain images, and the
// frame's synchronisation with the presentation engine (an acquire
// semaphore, one render-done semaphore per image). A finished frame is
// presented.
//
// The surface belongs to the caller (gpu/ knows no window system) and must
// outlive the swapchain.

#include "gpu/render_target.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace vox::gpu {

struct SwapchainOptions {
  bool vsync = true;  // FIFO; else MAILBOX or IMMEDIATE when offered
};

class Swapchain final : public RenderTarget {
public:
  // Throws RuntimeFailure when the surface offers no usable format or the
  // queue cannot present to it.
  Swapchain(Context& context, VkSurfaceKHR surface, std::uint32_t width, std::uint32_t height, SwapchainOptions options = {});
  ~Swapchain() override;

  void resize(std::uint32_t width, std::uint32_t height) override;
  std::optional<Frame> beginFrame() override;
  // Submits and presents; false when the swapchain is out of date.
  bool endFrame(const Frame& frame, RgbImage* screenshot = nullptr) override;

private:
  Swapchain(Context& context, VkSurfaceKHR surface, VkSurfaceFormatKHR format, std::uint32_t width, std::uint32_t height,
            SwapchainOptions options);
  void create(std::uint32_t width, std::uint32_t height);
  void destroyImages();

  VkSurfaceKHR surface_;
  SwapchainOptions options_;
  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkColorSpaceKHR colorSpace_;
  std::vector<VkSemaphore> renderDone_;  // per image: presentation may still wait on it
  VkSemaphore acquired_ = VK_NULL_HANDLE;
};

}  // namespace vox::gpu
