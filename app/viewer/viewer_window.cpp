#include "app/viewer/viewer_window.h"

#include "app/viewer/orbit_camera.h"
#include "geometry/error.h"
#include "geometry/render/raycast_scene.h"
#include "gpu/command.h"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_vulkan.h>

#include <vector>

namespace vox::app {

ViewerWindow::ViewerWindow(const std::string& title, int width, int height, bool vsync) {
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
    std::uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, nullptr);
    std::vector<VkQueueFamilyProperties> props(count);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, props.data());
    return family < count && (props[family].queueFlags & VK_QUEUE_GRAPHICS_BIT) &&
           glfwGetPhysicalDevicePresentationSupport(instance, pd, family) == GLFW_TRUE;
  };
  context_ = std::make_unique<gpu::Context>(co);
  if (glfwCreateWindowSurface(context_->instance(), window_, nullptr, &surface_) != VK_SUCCESS)
    throw RuntimeFailure("view: no Vulkan surface for the window");
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(window_, &fw, &fh);
  swapchain_ = std::make_unique<gpu::Swapchain>(*context_, surface_, std::uint32_t(fw), std::uint32_t(fh),
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
  swapchain_.reset();
  if (imguiPool_) vkDestroyDescriptorPool(context_->device(), imguiPool_, nullptr);
  if (surface_) vkDestroySurfaceKHR(context_->instance(), surface_, nullptr);
  context_.reset();
  if (window_) glfwDestroyWindow(window_);
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
  ImGui_ImplGlfw_InitForVulkan(window_, true);
  ImGui_ImplVulkan_InitInfo info{};
  info.Instance = context_->instance();
  info.PhysicalDevice = context_->physicalDevice();
  info.Device = context_->device();
  info.QueueFamily = context_->queueFamily();
  info.Queue = context_->queue();
  info.PipelineCache = context_->pipelineCache();
  info.DescriptorPool = imguiPool_;
  info.MinImageCount = swapchain_->minImageCount();
  info.ImageCount = swapchain_->imageCount();
  info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
  ImGui_ImplVulkan_Init(&info, swapchain_->renderPass());
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
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  imguiReady_ = false;
}

void ViewerWindow::framebufferSize(int& width, int& height) const { glfwGetFramebufferSize(window_, &width, &height); }

void ViewerWindow::newBackendFrame() {
  ImGui_ImplVulkan_NewFrame();
  ImGui_ImplGlfw_NewFrame();
}

ViewerWindow::Presented ViewerWindow::present(const gpu::Image2D& view, RgbImage* screenshot) {
  auto frame = swapchain_->beginFrame();
  if (!frame) return Presented::NoImage;
  const Rgb background = RaycastShading{}.background;
  if (view.valid()) swapchain_->blit(*frame, view, std::uint32_t(viewLeft(int(swapchain_->width()))), background);
  else swapchain_->clear(*frame, background);
  swapchain_->beginRenderPass(*frame);
  ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), frame->commands);
  swapchain_->endRenderPass(*frame);
  return swapchain_->endFrame(*frame, screenshot) ? Presented::Done : Presented::OutOfDate;
}

}  // namespace vox::app
