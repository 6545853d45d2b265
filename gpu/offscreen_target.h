#pragma once
// OffscreenTarget: the RenderTarget (gpu/render_target.h) of no window: one
// RGBA8 colour image in device memory of the size a window would have. A
// finished frame stays there until the next one (read back by a screenshot),
// so the viewer's frame runs, and is timed, without a display server.

#include "gpu/image.h"
#include "gpu/render_target.h"

#include <cstdint>
#include <optional>

namespace vox::gpu {

class OffscreenTarget final : public RenderTarget {
public:
  static constexpr VkFormat kFormat = VK_FORMAT_R8G8B8A8_UNORM;

  // Throws RuntimeFailure for a side of 0 or over 16384 pixels.
  OffscreenTarget(Context& context, std::uint32_t width, std::uint32_t height);
  ~OffscreenTarget() override;

  void resize(std::uint32_t width, std::uint32_t height) override;
  // Waits for the previous frame; never nullopt.
  std::optional<Frame> beginFrame() override;
  // Submits; always true.
  bool endFrame(const Frame& frame, RgbImage* screenshot = nullptr) override;

private:
  DeviceImage image_;
};

}  // namespace vox::gpu
