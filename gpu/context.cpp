#include "gpu/context.h"

#include "geometry/ascii_text.h"
#include "geometry/error.h"
#include "gpu/vk_check.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <dlfcn.h>
#include <link.h>

namespace vox::gpu {

const char* resultName(VkResult r) {
  switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_INCOMPLETE: return "VK_INCOMPLETE";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
    case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY";
    case VK_ERROR_SURFACE_LOST_KHR: return "VK_ERROR_SURFACE_LOST_KHR";
    case VK_ERROR_OUT_OF_DATE_KHR: return "VK_ERROR_OUT_OF_DATE_KHR";
    case VK_SUBOPTIMAL_KHR: return "VK_SUBOPTIMAL_KHR";
    default: return "VkResult error";
  }
}

// Under AddressSanitizer: the Vulkan loader unloads the driver when the last
// instance goes, and a driver allocation LeakSanitizer reports at exit then
// has no module name, so tests/sanitizer/lsan.supp cannot name it. Loaded
// Vulkan drivers are pinned (RTLD_NODELETE) in sanitized builds only.
static void keepDriversLoadedForLeakReports() {
#if defined(__SANITIZE_ADDRESS__)
  dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void*) {
        const char* name = info->dlpi_name;
        if (name && std::strstr(name, "libvulkan_")) dlopen(name, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
        return 0;
      },
      nullptr);
#endif
}

void throwVulkanFailure(const char* call, VkResult r) {
  throw RuntimeFailure(std::string("Vulkan: ") + call + " failed with " + resultName(r) + " (" + std::to_string(int(r)) + ")");
}

namespace {

const char* typeName(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

int typeRank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
  }
}

VkInstance createInstance(const ContextOptions& options) {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "voxmorph";
  app.apiVersion = VK_API_VERSION_1_3;
  std::vector<const char*> layers;
  if (options.validation) {
    std::uint32_t n = 0;
    vkEnumerateInstanceLayerProperties(&n, nullptr);
    std::vector<VkLayerProperties> props(n);
    vkEnumerateInstanceLayerProperties(&n, props.data());
    for (const auto& p : props)
      if (std::strcmp(p.layerName, "VK_LAYER_KHRONOS_validation") == 0) layers.push_back("VK_LAYER_KHRONOS_validation");
  }
  VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ci.pApplicationInfo = &app;
  ci.enabledExtensionCount = std::uint32_t(options.instanceExtensions.size());
  ci.ppEnabledExtensionNames = options.instanceExtensions.data();
  ci.enabledLayerCount = std::uint32_t(layers.size());
  ci.ppEnabledLayerNames = layers.data();
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult r = vkCreateInstance(&ci, nullptr, &instance);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
    throw RuntimeFailure("Vulkan: no Vulkan 1.3 driver found (install mesa-vulkan-drivers for the CPU driver lavapipe)");
  VOX_VK(r);
  return instance;
}

std::vector<VkPhysicalDevice> physicalDevices(VkInstance instance) {
  std::uint32_t n = 0;
  VOX_VK(vkEnumeratePhysicalDevices(instance, &n, nullptr));
  std::vector<VkPhysicalDevice> devices(n);
  VOX_VK(vkEnumeratePhysicalDevices(instance, &n, devices.data()));
  return devices;
}

bool hasExtension(VkPhysicalDevice pd, const char* name) {
  std::uint32_t n = 0;
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, nullptr);
  std::vector<VkExtensionProperties> props(n);
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, props.data());
  return std::any_of(props.begin(), props.end(), [&](const VkExtensionProperties& p) { return std::strcmp(p.extensionName, name) == 0; });
}

// Compute-capable queue family (preferring one that also does graphics, so the
// viewer and the kernels share a queue); -1 when none qualifies.
int pickQueueFamily(VkInstance instance, VkPhysicalDevice pd, const ContextOptions& options) {
  std::uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> fams(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, fams.data());
  int best = -1;
  for (std::uint32_t f = 0; f < n; ++f) {
    if (!(fams[f].queueFlags & VK_QUEUE_COMPUTE_BIT)) continue;
    if (options.acceptQueue && !options.acceptQueue(instance, pd, f)) continue;
    if (best < 0 || ((fams[f].queueFlags & VK_QUEUE_GRAPHICS_BIT) && !(fams[std::size_t(best)].queueFlags & VK_QUEUE_GRAPHICS_BIT)))
      best = int(f);
  }
  return best;
}

bool suitable(VkInstance instance, VkPhysicalDevice pd, const ContextOptions& options) {
  VkPhysicalDeviceProperties p;
  vkGetPhysicalDeviceProperties(pd, &p);
  if (p.apiVersion < VK_API_VERSION_1_3) return false;
  if (!hasExtension(pd, VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME)) return false;
  for (const char* e : options.deviceExtensions)
    if (!hasExtension(pd, e)) return false;
  return pickQueueFamily(instance, pd, options) >= 0;
}

}  // namespace

std::vector<std::string> listDevices() {
  ContextOptions none;
  VkInstance instance = createInstance(none);
  std::vector<std::string> out;
  const auto devices = physicalDevices(instance);
  for (std::size_t i = 0; i < devices.size(); ++i) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(devices[i], &p);
    out.push_back(std::to_string(i) + ": " + p.deviceName + " (" + typeName(p.deviceType) + ", Vulkan " +
                  std::to_string(VK_API_VERSION_MAJOR(p.apiVersion)) + "." + std::to_string(VK_API_VERSION_MINOR(p.apiVersion)) +
                  (suitable(instance, devices[i], none) ? ")" : ", unsuitable)"));
  }
  vkDestroyInstance(instance, nullptr);
  return out;
}

Context::Context(const ContextOptions& options)
    : stageDeviceMemory_(options.stageDeviceMemory), stagingBytes_(std::max<std::uint64_t>(options.stagingBytes, 1)) {
  instance_ = createInstance(options);
  try {
    const auto devices = physicalDevices(instance_);
    if (devices.empty()) throw RuntimeFailure("Vulkan: no device found (install mesa-vulkan-drivers for the CPU driver lavapipe)");

    const char* env = std::getenv("VOXMORPH_DEVICE");
    int chosen = -1;
    if (env && *env) {
      const std::string want = env;
      const bool numeric = std::all_of(want.begin(), want.end(), [](unsigned char c) { return std::isdigit(c); });
      for (std::size_t i = 0; i < devices.size() && chosen < 0; ++i) {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(devices[i], &p);
        const bool match = numeric ? std::to_string(i) == want : toLowerAscii(p.deviceName).find(toLowerAscii(want)) != std::string::npos;
        if (!match) continue;
        if (!suitable(instance_, devices[i], options))
          throw RuntimeFailure(std::string("Vulkan: VOXMORPH_DEVICE selects '") + p.deviceName +
                               "', which lacks Vulkan 1.3, push descriptors or a compute queue");
        chosen = int(i);
      }
      if (chosen < 0) throw RuntimeFailure("Vulkan: VOXMORPH_DEVICE='" + want + "' matches no device");
    } else {
      int bestRank = 1 << 30;
      for (std::size_t i = 0; i < devices.size(); ++i) {
        if (!suitable(instance_, devices[i], options)) continue;
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(devices[i], &p);
        if (typeRank(p.deviceType) < bestRank) {
          bestRank = typeRank(p.deviceType);
          chosen = int(i);
        }
      }
      if (chosen < 0) throw RuntimeFailure("Vulkan: no device offers Vulkan 1.3 with push descriptors and a compute queue");
    }
    physical_ = devices[std::size_t(chosen)];
    queueFamily_ = std::uint32_t(pickQueueFamily(instance_, physical_, options));

    VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
    VkPhysicalDeviceMaintenance3Properties maint3{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
    maint3.pNext = &subgroup;
    VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    props2.pNext = &maint3;
    vkGetPhysicalDeviceProperties2(physical_, &props2);
    const VkPhysicalDeviceProperties& p = props2.properties;
    info_.name = p.deviceName;
    info_.type = typeName(p.deviceType);
    info_.apiVersion = p.apiVersion;
    info_.maxStorageBufferRange = p.limits.maxStorageBufferRange;
    info_.maxAllocationSize = maint3.maxMemoryAllocationSize;
    info_.maxImageDimension3D = p.limits.maxImageDimension3D;
    for (int a = 0; a < 3; ++a) info_.maxWorkGroupCount[a] = p.limits.maxComputeWorkGroupCount[a];
    info_.maxPushConstantsSize = p.limits.maxPushConstantsSize;
    info_.subgroupSize = subgroup.subgroupSize;

    std::uint32_t nf = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &nf, nullptr);
    std::vector<VkQueueFamilyProperties> fams(nf);
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &nf, fams.data());
    if (fams[queueFamily_].timestampValidBits > 0) info_.timestampPeriodNs = p.limits.timestampPeriod;

    vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);
    info_.unifiedMemory = true;
    for (std::uint32_t t = 0; t < memory_.memoryTypeCount; ++t) {
      const auto f = memory_.memoryTypes[t].propertyFlags;
      if ((f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) && !(f & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)) info_.unifiedMemory = false;
    }

    const float priority = 1.0f;
    VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qci.queueFamilyIndex = queueFamily_;
    qci.queueCount = 1;
    qci.pQueuePriorities = &priority;

    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
    f11.pNext = &f12;
    VkPhysicalDeviceFeatures2 supported{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    supported.pNext = &f11;
    vkGetPhysicalDeviceFeatures2(physical_, &supported);

    // Only what the kernels use, and only when offered.
    VkPhysicalDeviceVulkan12Features e12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    e12.storageBuffer8BitAccess = f12.storageBuffer8BitAccess;
    e12.shaderInt8 = f12.shaderInt8;
    e12.hostQueryReset = f12.hostQueryReset;
    VkPhysicalDeviceVulkan11Features e11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
    e11.storageBuffer16BitAccess = f11.storageBuffer16BitAccess;
    e11.pNext = &e12;
    VkPhysicalDeviceFeatures2 enabled{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    enabled.features.shaderInt16 = supported.features.shaderInt16;
    enabled.features.shaderInt64 = supported.features.shaderInt64;
    enabled.features.shaderFloat64 = supported.features.shaderFloat64;
    enabled.pNext = &e11;

    std::vector<const char*> extensions = options.deviceExtensions;
    extensions.push_back(VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME);
    VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    dci.pNext = &enabled;
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    dci.enabledExtensionCount = std::uint32_t(extensions.size());
    dci.ppEnabledExtensionNames = extensions.data();
    VOX_VK(vkCreateDevice(physical_, &dci, nullptr, &device_));
    vkGetDeviceQueue(device_, queueFamily_, 0, &queue_);
    keepDriversLoadedForLeakReports();

    cmdPushDescriptorSet = reinterpret_cast<PFN_vkCmdPushDescriptorSetKHR>(vkGetDeviceProcAddr(device_, "vkCmdPushDescriptorSetKHR"));
    if (!cmdPushDescriptorSet) throw RuntimeFailure("Vulkan: vkCmdPushDescriptorSetKHR is unavailable");

    VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT | VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
    pci.queueFamilyIndex = queueFamily_;
    VOX_VK(vkCreateCommandPool(device_, &pci, nullptr, &commandPool_));
    VkPipelineCacheCreateInfo cci{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
    VOX_VK(vkCreatePipelineCache(device_, &cci, nullptr, &pipelineCache_));
  } catch (...) {
    release();
    throw;
  }
}

Context::~Context() { release(); }

void Context::release() {
  if (device_) {
    vkDeviceWaitIdle(device_);
    if (pipelineCache_) vkDestroyPipelineCache(device_, pipelineCache_, nullptr);
    if (commandPool_) vkDestroyCommandPool(device_, commandPool_, nullptr);
    vkDestroyDevice(device_, nullptr);
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
  device_ = VK_NULL_HANDLE;
  instance_ = VK_NULL_HANDLE;
  pipelineCache_ = VK_NULL_HANDLE;
  commandPool_ = VK_NULL_HANDLE;
}

std::uint64_t Context::maxBindingBytes() const {
  return std::min<std::uint64_t>(info_.maxStorageBufferRange, std::uint64_t(128) << 20);
}

std::uint32_t Context::findMemoryType(std::uint32_t typeBits, VkMemoryPropertyFlags required,
                                      VkMemoryPropertyFlags preferred) const {
  int fallback = -1;
  for (std::uint32_t t = 0; t < memory_.memoryTypeCount; ++t) {
    if (!(typeBits & (1u << t))) continue;
    const auto f = memory_.memoryTypes[t].propertyFlags;
    if ((f & required) != required) continue;
    if ((f & preferred) == preferred) return t;
    if (fallback < 0) fallback = int(t);
  }
  if (fallback < 0) throw RuntimeFailure("Vulkan: no memory type with the required properties");
  return std::uint32_t(fallback);
}

VkMemoryPropertyFlags Context::memoryTypeFlags(std::uint32_t type) const { return memory_.memoryTypes[type].propertyFlags; }

}  // namespace vox::gpu
