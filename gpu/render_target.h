#pragma once
// RenderTarget: the colour images a frame of the viewer is drawn into, and
// where a finished frame goes: presented to a window (Swapchain,
// gpu/swapchain.h) or kept in one offscreen image (OffscreenTarget,
// gpu/offscreen_target.h). A frame is drawn the same way into either: the
// ray-cast Image2D blitted beside the panel column, then one render pass that
// draws the UI over what the blit left; a screenshot reads the finished
// image back, so both give the same pixels. One frame is in flight:
// beginFrame() waits for the previous one, so the images a frame reads (the
// ray-cast Image2D) may be rewritten as soon as it returns.
//
//   auto frame = target.beginFrame();      // nullopt: resize, then retry
//   target.blit(*frame, rayCastImage);     // scaled to the whole image
//   target.beginRenderPass(*frame); ... UI ...; target.endRenderPass(*frame);
//   target.endFrame(*frame, &screenshot);  // submit (and present)

#include "geometry/rgb_image.h"
#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/image.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace vox::gpu {

class RenderTarget {
public:
  virtual ~RenderTarget();
  RenderTarget(const RenderTarget&) = delete;
  RenderTarget& operator=(const RenderTarget&) = delete;

  // Recreates the images for a new size (waits for the device).
  virtual void resize(std::uint32_t width, std::uint32_t height) = 0;

  struct Frame {
    VkCommandBuffer commands = VK_NULL_HANDLE;  // recording
    std::uint32_t image = 0;                    // index of the target's image
  };
  // Waits for the previous frame, takes an image and begins recording;
  // nullopt when the target no longer matches its window (resize first).
  virtual std::optional<Frame> beginFrame() = 0;
  // Fills the frame's image with `background`, then `source` scaled (linear
  // filter; nearest when the sizes match) into the columns from `left` to
  // the right edge.
  void blit(const Frame& frame, const Image2D& source, std::uint32_t left = 0, Rgb background = {});
  // Fills the frame's image with one colour (nothing to blit yet).
  void clear(const Frame& frame, Rgb colour);
  void beginRenderPass(const Frame& frame);
  void endRenderPass(const Frame& frame);
  // Submits the frame (and presents it). With `screenshot`, the finished
  // image is also read back into it (waits for the GPU). Returns false when
  // the target is out of date (resize before the next frame).
  virtual bool endFrame(const Frame& frame, RgbImage* screenshot = nullptr) = 0;

  VkRenderPass renderPass() const { return renderPass_; }
  VkFormat format() const { return format_; }
  std::uint32_t width() const { return extent_.width; }
  std::uint32_t height() const { return extent_.height; }
  std::uint32_t imageCount() const { return std::uint32_t(images_.size()); }
  std::uint32_t minImageCount() const { return minImageCount_; }

protected:
  // The render pass loads what the frame's commands put in the image and
  // leaves it in `finalLayout` (where presentation or the read-back finds
  // it); the fence starts signalled.
  RenderTarget(Context& context, VkFormat format, VkImageLayout finalLayout);
  // Views and framebuffers of images_ at extent_.
  void createFramebuffers();
  // Destroys the views and framebuffers and forgets images_.
  void destroyFramebuffers();
  void waitForPreviousFrame();
  Frame beginRecording(std::uint32_t image);
  // Records the copy of the finished image into the read-back buffer.
  void recordReadback(const Frame& frame);
  // Ends recording and submits, signalling the fence (and `signal`).
  void submit(const Frame& frame, VkSemaphore wait = VK_NULL_HANDLE, VkSemaphore signal = VK_NULL_HANDLE);
  // Waits for the submitted frame and converts the read-back to RGB.
  void finishReadback(RgbImage& screenshot);

  Context& context_;
  VkFormat format_;
  VkExtent2D extent_{0, 0};
  std::uint32_t minImageCount_ = 2;
  std::vector<VkImage> images_;

private:
  void toLayout(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to);

  VkImageLayout finalLayout_;
  VkRenderPass renderPass_ = VK_NULL_HANDLE;
  std::vector<VkImageView> views_;
  std::vector<VkFramebuffer> framebuffers_;
  VkFence inFlight_ = VK_NULL_HANDLE;
  VkCommandBuffer commands_ = VK_NULL_HANDLE;
  Buffer readback_;
};

}  // namespace vox::gpu
