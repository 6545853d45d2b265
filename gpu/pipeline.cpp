#include "gpu/pipeline.h"

#include "geometry/error.h"
#include "gpu/shader_library.h"
#include "gpu/vk_check.h"

namespace vox::gpu {

namespace {
VkDescriptorType descriptorType(BindingKind k) {
  switch (k) {
    case BindingKind::StorageBuffer: return VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    case BindingKind::UniformBuffer: return VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    case BindingKind::StorageImage: return VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    case BindingKind::SampledImage: return VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  }
  return VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
}
}  // namespace

ComputePipeline::ComputePipeline(Context& context, const PipelineDesc& desc) : context_(context), desc_(desc) {
  VkDevice dev = context.device();
  if (desc.pushConstantBytes > 128) throw RuntimeFailure(desc.shader + ": push constants exceed 128 bytes");
  const auto code = embeddedShader(desc.shader);
  VkShaderModule module = VK_NULL_HANDLE;
  try {
    std::vector<VkDescriptorSetLayoutBinding> bindings;
    bool needsSampler = false;
    for (std::size_t i = 0; i < desc.bindings.size(); ++i) needsSampler |= desc.bindings[i] == BindingKind::SampledImage;
    if (needsSampler) {
      VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
      sci.magFilter = sci.minFilter = VK_FILTER_NEAREST;
      sci.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
      sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
      sci.unnormalizedCoordinates = VK_FALSE;
      VOX_VK(vkCreateSampler(dev, &sci, nullptr, &sampler_));
    }
    for (std::size_t i = 0; i < desc.bindings.size(); ++i) {
      VkDescriptorSetLayoutBinding b{};
      b.binding = std::uint32_t(i);
      b.descriptorType = descriptorType(desc.bindings[i]);
      b.descriptorCount = 1;
      b.stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
      b.pImmutableSamplers = desc.bindings[i] == BindingKind::SampledImage ? &sampler_ : nullptr;
      bindings.push_back(b);
    }
    VkDescriptorSetLayoutCreateInfo dl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    dl.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
    dl.bindingCount = std::uint32_t(bindings.size());
    dl.pBindings = bindings.data();
    VOX_VK(vkCreateDescriptorSetLayout(dev, &dl, nullptr, &setLayout_));

    VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, desc.pushConstantBytes};
    VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pl.setLayoutCount = 1;
    pl.pSetLayouts = &setLayout_;
    pl.pushConstantRangeCount = desc.pushConstantBytes ? 1 : 0;
    pl.pPushConstantRanges = &range;
    VOX_VK(vkCreatePipelineLayout(dev, &pl, nullptr, &layout_));

    VkShaderModuleCreateInfo sm{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    sm.codeSize = code.size_bytes();
    sm.pCode = code.data();
    VOX_VK(vkCreateShaderModule(dev, &sm, nullptr, &module));

    std::vector<VkSpecializationMapEntry> entries;
    for (std::size_t i = 0; i < desc.specialization.size(); ++i)
      entries.push_back({std::uint32_t(i), std::uint32_t(i * sizeof(std::uint32_t)), sizeof(std::uint32_t)});
    VkSpecializationInfo spec{};
    spec.mapEntryCount = std::uint32_t(entries.size());
    spec.pMapEntries = entries.data();
    spec.dataSize = desc.specialization.size() * sizeof(std::uint32_t);
    spec.pData = desc.specialization.data();

    VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    ci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    ci.stage.module = module;
    ci.stage.pName = "main";
    ci.stage.pSpecializationInfo = entries.empty() ? nullptr : &spec;
    ci.layout = layout_;
    VOX_VK(vkCreateComputePipelines(dev, context.pipelineCache(), 1, &ci, nullptr, &pipeline_));
    vkDestroyShaderModule(dev, module, nullptr);
  } catch (...) {
    if (module) vkDestroyShaderModule(dev, module, nullptr);
    release();
    throw;
  }
}

ComputePipeline::~ComputePipeline() { release(); }

void ComputePipeline::release() {
  VkDevice dev = context_.device();
  if (pipeline_) vkDestroyPipeline(dev, pipeline_, nullptr);
  if (layout_) vkDestroyPipelineLayout(dev, layout_, nullptr);
  if (setLayout_) vkDestroyDescriptorSetLayout(dev, setLayout_, nullptr);
  if (sampler_) vkDestroySampler(dev, sampler_, nullptr);
  pipeline_ = VK_NULL_HANDLE;
  layout_ = VK_NULL_HANDLE;
  setLayout_ = VK_NULL_HANDLE;
  sampler_ = VK_NULL_HANDLE;
}

}  // namespace vox::gpu
