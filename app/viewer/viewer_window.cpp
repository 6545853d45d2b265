#include "app/viewer/viewer_window.h"

#include "app/viewer/orbit_camera.h"
#include "geometry/error.h"
#include "geometry/render/raycast_scene.h"
#include "gpu/command.h"
#include "gpu/offscreen_target.h"
#include "gpu/swapchain.h"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_vulkan.h>

#include <algorithm>
#include <vector>

namespace vox::app {

namespace {

bool drawsGraphics(VkPhysicalDevice pd, std::uint32_t family) {
  std::uint32_t count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, nullptr);
  std::vector<VkQueueFamilyProperties> props(count);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, props.data());
  return family < count && (props[family].queueFlags & VK_QUEUE_GRAPHICS_BIT);
}

}  // namespace

ViewerWindow::ViewerWindow(const std::string& title, int width, int height, bool vsync, bool offscreen) {
  if (offscreen) {
    gpu::ContextOptions co;
    co.acceptQueue = [](VkInstance, VkPhysicalDevice pd, std::uint32_t family) { return drawsGraphics(pd, family); };
    context_ = std::make_unique<gpu::Context>(co);
    target_ = std::make_unique<gpu::OffscreenTarget>(*context_, std::uint32_t(width), std::uint32_t(height));
    return;
  }
  glfwSetErrorCallback(nullptr);
  if (!glfwInit()) throw RuntimeFailure("view: no display (set DISPLAY, or run under xvfb-run); the window cannot open");
  if (!glfwVulkanSupported()) throw RuntimeFailure("view: GLFW finds no Vulkan loader for this display");
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!window_) throw RuntimeFailure("view: the window could not be created on this display");
  gpu::ContextOptions co;
  std::uint32_t n = 0;
  const char** extensions = glfwGetRequiredInstanceExtensions(&n);
  co.instanceExtensions.assign(extensions, extensions + n);
  co.deviceExtensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  co.acceptQueue = [](VkInstance instance, VkPhysicalDevice pd, std::uint32_t family) {
    return drawsGraphics(pd, family) && glfwGetPhysicalDevicePresentationSupport(instance, pd, family) == GLFW_TRUE;
  };
  context_ = std::make_unique<gpu::Context>(co);
  if (glfwCreateWindowSurface(context_->instance(), window_, nullptr, &surface_) != VK_SUCCESS)
    throw RuntimeFailure("view: no Vulkan surface for the window");
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(window_, &fw, &fh);
  target_ = std::make_unique<gpu::Swapchain>(*context_, surface_, std::uint32_t(fw), std::uint32_t(fh),
                                             gpu::SwapchainOptions{.vsync = vsync});
  glfwSetWindowUserPointer(window_, this);
  glfwSetScrollCallback(window_, [](GLFWwindow* w, double, double dy) {
    auto* self = static_cast<ViewerWindow*>(glfwGetWindowUserPointer(w));
    ImGui_ImplGlfw_ScrollCallback(w, 0, dy);
    if (self->onScroll_) self->onScroll_(dy);
  });
}

ViewerWindow::~ViewerWindow() {
  shutdownImGui();
  target_.reset();
  if (imguiPool_) vkDestroyDescriptorPool(context_->device(), imguiPool_, nullptr);
  if (surface_) vkDestroySurfaceKHR(context_->instance(), surface_, nullptr);
  context_.reset();
  if (!window_) return;
  glfwDestroyWindow(window_);
  glfwTerminate();
}

void ViewerWindow::initImGui() {
  const VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 16}};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
  pci.maxSets = 16;
  pci.poolSizeCount = 1;
  pci.pPoolSizes = sizes;
  if (vkCreateDescriptorPool(context_->device(), &pci, nullptr, &imguiPool_) != VK_SUCCESS)
    throw RuntimeFailure("view: cannot create the UI's descriptor pool");
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsDark();
  // The GLFW backend installs its callbacks and chains ours (scroll).
  if (window_) ImGui_ImplGlfw_InitForVulkan(window_, true);
  ImGui_ImplVulkan_InitInfo info{};
  info.Instance = context_->instance();
  info.PhysicalDevice = context_->physicalDevice();
  info.Device = context_->device();
  info.QueueFamily = context_->queueFamily();
  info.Queue = context_->queue();
  info.PipelineCache = context_->pipelineCache();
  info.DescriptorPool = imguiPool_;
  // Dear ImGui keeps per-image vertex buffers for at least two images.
  info.MinImageCount = target_->minImageCount();
  info.ImageCount = std::max<std::uint32_t>(2, target_->imageCount());
  info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
  ImGui_ImplVulkan_Init(&info, target_->renderPass());
  gpu::CommandBatch batch(*context_);
  batch.record([](VkCommandBuffer cmd) { ImGui_ImplVulkan_CreateFontsTexture(cmd); });
  batch.submitAndWait();
  ImGui_ImplVulkan_DestroyFontUploadObjects();
  imguiReady_ = true;
}

void ViewerWindow::shutdownImGui() {
  if (context_) vkDeviceWaitIdle(context_->device());
  if (!imguiReady_) return;
  ImGui_ImplVulkan_Shutdown();
  if (window_) ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  imguiReady_ = false;
}

void ViewerWindow::framebufferSize(int& width, int& height) const {
  if (window_) {
    glfwGetFramebufferSize(window_, &width, &height);
  } else {
    width = int(target_->width());
    height = int(target_->height());
  }
}

void ViewerWindow::pollEvents() {
  if (window_) glfwPollEvents();
}

void ViewerWindow::waitEvents() {
  if (window_) glfwWaitEvents();
}

bool ViewerWindow::closeRequested() const { return window_ && glfwWindowShouldClose(window_); }

void ViewerWindow::pointer(double& x, double& y, bool down[3]) const {
  x = y = 0.0;
  for (int b = 0; b < 3; ++b) down[b] = false;
  if (!window_) return;
  glfwGetCursorPos(window_, &x, &y);
  for (int b = 0; b < 3; ++b) down[b] = glfwGetMouseButton(window_, b) == GLFW_PRESS;
}

void ViewerWindow::newBackendFrame() {
  ImGui_ImplVulkan_NewFrame();
  if (window_) {
    ImGui_ImplGlfw_NewFrame();
    return;
  }
  // What the platform backend would set: the image's size at a scale of 1,
  // and a fixed frame time so that a scripted session runs the same way
  // each time.
  ImGuiIO& io = ImGui::GetIO();
  io.DisplaySize = ImVec2(float(target_->width()), float(target_->height()));
  io.DisplayFramebufferScale = ImVec2(1.0f, 1.0f);
  io.DeltaTime = 1.0f / 60.0f;
}

ViewerWindow::Presented ViewerWindow::present(const gpu::Image2D& view, RgbImage* screenshot) {
  auto frame = target_->beginFrame();
  if (!frame) return Presented::NoImage;
  const Rgb background = RaycastShading{}.background;
  if (view.valid()) target_->blit(*frame, view, std::uint32_t(viewLeft(int(target_->width()))), background);
  else target_->clear(*frame, background);
  target_->beginRenderPass(*frame);
  ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), frame->commands);
  target_->endRenderPass(*frame);
  return target_->endFrame(*frame, screenshot) ? Presented::Done : Presented::OutOfDate;
}

}  // namespace vox::app
