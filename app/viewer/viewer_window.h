#pragma once
// The viewer's window: GLFW window, Vulkan context and surface, swapchain,
// and Dear ImGui on them. It presents a frame (the ray-cast view right of
// the panel column, then the UI over it) and reports wheel scrolls.
// Offscreen (scripted sessions without a display server), there is no GLFW
// window: the frame is drawn the same way into an offscreen image of the
// window's size (gpu/offscreen_target.h), and Dear ImGui runs without a
// platform backend (display size set here, a fixed frame time, the script's
// mouse).

#include "gpu/context.h"
#include "gpu/image.h"
#include "gpu/render_target.h"

#include <functional>
#include <memory>
#include <string>

struct GLFWwindow;

namespace vox::app {

class ViewerWindow {
public:
  // Opens the window of width x height pixels, or the offscreen image of
  // that size; throws RuntimeFailure when there is no display (window) or
  // no Vulkan for it. vsync off for scripted sessions.
  ViewerWindow(const std::string& title, int width, int height, bool vsync, bool offscreen);
  ~ViewerWindow();
  ViewerWindow(const ViewerWindow&) = delete;
  ViewerWindow& operator=(const ViewerWindow&) = delete;

  // Dear ImGui on the window (its GLFW backend chains the scroll callback).
  void initImGui();
  // Ends Dear ImGui (the device idle first); the destructor does it otherwise.
  void shutdownImGui();

  gpu::Context& context() { return *context_; }
  gpu::RenderTarget& target() { return *target_; }
  // The window's framebuffer, or the offscreen image.
  void framebufferSize(int& width, int& height) const;
  // Window events: processed (pollEvents), awaited (waitEvents), whether
  // the user closed the window; none offscreen.
  void pollEvents();
  void waitEvents();
  bool closeRequested() const;
  // The pointer and the left, right and middle buttons as the window has them.
  void pointer(double& x, double& y, bool down[3]) const;
  // Called with each wheel scroll (notches, up positive).
  void onScroll(std::function<void(double)> handler) { onScroll_ = std::move(handler); }

  // The ImGui backends' part of a new UI frame (ImGui::NewFrame follows,
  // after a script has set ImGui's mouse).
  void newBackendFrame();
  enum class Presented { NoImage, Done, OutOfDate };
  // Draws `view` (when valid; else the background) right of the panel and
  // the rendered UI over it, and presents it (offscreen: leaves it in the
  // image); `screenshot` takes the finished image. NoImage: none could be acquired (resize first);
  // OutOfDate: presented, resize before the next frame.
  Presented present(const gpu::Image2D& view, RgbImage* screenshot = nullptr);

private:
  GLFWwindow* window_ = nullptr;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  std::unique_ptr<gpu::Context> context_;
  std::unique_ptr<gpu::RenderTarget> target_;
  VkDescriptorPool imguiPool_ = VK_NULL_HANDLE;
  bool imguiReady_ = false;
  std::function<void(double)> onScroll_;
};

}  // namespace vox::app
