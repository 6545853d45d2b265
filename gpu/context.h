#pragma once
// Vulkan 1.3 context: instance, one device, one compute queue. Headless by
// default; the viewer passes the extensions its window system needs.
//
// Device choice: discrete GPU first, then integrated, virtual, CPU (lavapipe).
// The environment variable VOXMORPH_DEVICE overrides it: a device index (as
// listed by `voxmorph info --devices`) or a case-insensitive substring of the
// device name.

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace vox::gpu {

struct DeviceInfo {
  std::string name;
  std::string type;  // "discrete", "integrated", "virtual", "cpu", "other"
  std::uint32_t apiVersion = 0;
  std::uint64_t maxStorageBufferRange = 0;  // bytes per storage-buffer binding
  std::uint64_t maxAllocationSize = 0;      // bytes per allocation
  std::uint32_t maxImageDimension3D = 0;
  std::uint32_t maxWorkGroupCount[3] = {0, 0, 0};
  std::uint32_t maxPushConstantsSize = 0;
  std::uint32_t subgroupSize = 0;
  double timestampPeriodNs = 0.0;  // 0 when the queue has no timestamps
  bool unifiedMemory = false;      // every device-local type is host visible
};

struct ContextOptions {
  std::vector<const char*> instanceExtensions;
  std::vector<const char*> deviceExtensions;
  // Extra test a device and queue family must pass (e.g. presentation).
  std::function<bool(VkInstance, VkPhysicalDevice, std::uint32_t queueFamily)> acceptQueue;
  bool validation = false;  // enable VK_LAYER_KHRONOS_validation when present
  // Device-intent buffers stay unmapped even where their memory is host
  // visible, so host access is staged as on a discrete GPU (tests exercise
  // that path on lavapipe).
  bool stageDeviceMemory = false;
  // Largest staging buffer of a host <-> device copy (gpu/buffer.h): larger
  // copies go in chunks through one buffer of this size.
  std::uint64_t stagingBytes = std::uint64_t(64) << 20;
};

// The devices Vulkan reports, in enumeration order ("index: name (type)").
std::vector<std::string> listDevices();

class Context {
public:
  explicit Context(const ContextOptions& options = {});
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& info() const { return info_; }
  bool stagesDeviceMemory() const { return stageDeviceMemory_; }
  std::uint64_t stagingBytes() const { return stagingBytes_; }
  // Largest storage-buffer binding a kernel may use: the device limit capped
  // at the 128 MiB lavapipe offers, so chunking is exercised everywhere.
  std::uint64_t maxBindingBytes() const;

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physicalDevice() const { return physical_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  std::uint32_t queueFamily() const { return queueFamily_; }
  VkCommandPool commandPool() const { return commandPool_; }
  VkPipelineCache pipelineCache() const { return pipelineCache_; }

  // Memory type with all `required` flags, preferring `preferred` ones; throws
  // RuntimeFailure when none matches `typeBits`.
  std::uint32_t findMemoryType(std::uint32_t typeBits, VkMemoryPropertyFlags required,
                               VkMemoryPropertyFlags preferred = 0) const;
  VkMemoryPropertyFlags memoryTypeFlags(std::uint32_t type) const;

  // Push-descriptor entry point (VK_KHR_push_descriptor).
  PFN_vkCmdPushDescriptorSetKHR cmdPushDescriptorSet = nullptr;

private:
  void release();

  VkInstance instance_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  std::uint32_t queueFamily_ = 0;
  VkCommandPool commandPool_ = VK_NULL_HANDLE;
  VkPipelineCache pipelineCache_ = VK_NULL_HANDLE;
  VkPhysicalDeviceMemoryProperties memory_{};
  DeviceInfo info_;
  bool stageDeviceMemory_ = false;
  std::uint64_t stagingBytes_ = 0;
};

}  // namespace vox::gpu
