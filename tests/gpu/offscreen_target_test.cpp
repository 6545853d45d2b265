// OffscreenTarget (gpu/offscreen_target.h): a frame drawn as the viewer draws
// it (clear or blit beside a left column, the UI's render pass) is what its
// screenshot reads back, at the target's size, before and after a resize.

#include "geometry/error.h"
#include "gpu/context.h"
#include "gpu/image.h"
#include "gpu/offscreen_target.h"

#include <gtest/gtest.h>

#include <cstddef>

namespace vox {
namespace {

gpu::Context& context() {
  static gpu::Context ctx;
  return ctx;
}

std::size_t countColour(const RgbImage& image, Rgb colour, int x0, int x1) {
  std::size_t n = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = x0; x < x1; ++x) n += image.pixels[std::size_t(y) * image.width + x] == colour;
  return n;
}

TEST(OffscreenTarget, ClearedFrameReadsBackAtItsSize) {
  gpu::OffscreenTarget target(context(), 64, 48);
  const Rgb colour{10, 200, 30};
  auto frame = target.beginFrame();
  ASSERT_TRUE(frame);
  target.clear(*frame, colour);
  target.beginRenderPass(*frame);
  target.endRenderPass(*frame);
  RgbImage shot;
  EXPECT_TRUE(target.endFrame(*frame, &shot));
  ASSERT_EQ(shot.width, 64);
  ASSERT_EQ(shot.height, 48);
  EXPECT_EQ(countColour(shot, colour, 0, 64), 64u * 48u);

  target.resize(32, 16);
  frame = target.beginFrame();
  ASSERT_TRUE(frame);
  target.clear(*frame, Rgb{1, 2, 3});
  target.beginRenderPass(*frame);
  target.endRenderPass(*frame);
  EXPECT_TRUE(target.endFrame(*frame, &shot));
  ASSERT_EQ(shot.width, 32);
  ASSERT_EQ(shot.height, 16);
  EXPECT_EQ(countColour(shot, Rgb{1, 2, 3}, 0, 32), 32u * 16u);
}

TEST(OffscreenTarget, BlitLeavesTheColumnsLeftOfTheViewInTheBackground) {
  gpu::OffscreenTarget target(context(), 80, 40);
  gpu::Image2D view(context(), 20, 10);
  const Rgb background{40, 50, 60};
  // Two frames: the second waits for the first, as in the viewer's loop.
  for (int i = 0; i < 2; ++i) {
    auto frame = target.beginFrame();
    ASSERT_TRUE(frame);
    target.blit(*frame, view, 30, background);
    target.beginRenderPass(*frame);
    target.endRenderPass(*frame);
    RgbImage shot;
    EXPECT_TRUE(target.endFrame(*frame, &shot));
    ASSERT_EQ(shot.width, 80);
    EXPECT_EQ(countColour(shot, background, 0, 30), 30u * 40u);
  }
}

TEST(OffscreenTarget, RefusesAnEmptyOrOversizedImage) {
  EXPECT_THROW(gpu::OffscreenTarget(context(), 0, 10), RuntimeFailure);
  EXPECT_THROW(gpu::OffscreenTarget(context(), 20000, 10), RuntimeFailure);
}

}  // namespace
}  // namespace vox
