#include "gpu/offscreen_target.h"

#include "geometry/error.h"

#include <string>

namespace vox::gpu {

OffscreenTarget::OffscreenTarget(Context& context, std::uint32_t width, std::uint32_t height)
    : RenderTarget(context, kFormat, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL) {
  resize(width, height);
}

OffscreenTarget::~OffscreenTarget() {
  vkDeviceWaitIdle(context_.device());
  destroyFramebuffers();
}

void OffscreenTarget::resize(std::uint32_t width, std::uint32_t height) {
  if (width == 0 || height == 0 || width > 16384 || height > 16384)
    throw RuntimeFailure("offscreen image: " + std::to_string(width) + " x " + std::to_string(height) + " pixels is not a frame size");
  vkDeviceWaitIdle(context_.device());
  destroyFramebuffers();
  image_ = DeviceImage(context_, VK_IMAGE_TYPE_2D, {width, height, 1}, kFormat,
                       VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT);
  extent_ = {width, height};
  images_ = {image_.handle()};
  createFramebuffers();
}

std::optional<RenderTarget::Frame> OffscreenTarget::beginFrame() {
  waitForPreviousFrame();
  return beginRecording(0);
}

bool OffscreenTarget::endFrame(const Frame& frame, RgbImage* screenshot) {
  if (screenshot) recordReadback(frame);
  submit(frame);
  if (screenshot) finishReadback(*screenshot);
  return true;
}

}  // namespace vox::gpu
