#pragma once
// Compute pipeline built from an embedded shader, with a push-descriptor set
// layout (set 0, bindings 0..n-1 in the order given) and push constants.

#include "gpu/context.h"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace vox::gpu {

enum class BindingKind { StorageBuffer, UniformBuffer, StorageImage, SampledImage };

struct PipelineDesc {
  std::string shader;                    // embedded shader name, e.g. "label_stats.comp"
  std::vector<BindingKind> bindings;     // set 0, binding i = bindings[i]
  std::uint32_t pushConstantBytes = 0;   // <= 128 (the portable minimum)
  std::vector<std::uint32_t> specialization;  // constant_id i = specialization[i]
};

class ComputePipeline {
public:
  ComputePipeline(Context& context, const PipelineDesc& desc);
  ~ComputePipeline();
  ComputePipeline(const ComputePipeline&) = delete;
  ComputePipeline& operator=(const ComputePipeline&) = delete;

  const PipelineDesc& desc() const { return desc_; }
  VkPipeline handle() const { return pipeline_; }
  VkPipelineLayout layout() const { return layout_; }

private:
  void release();

  Context& context_;
  PipelineDesc desc_;
  VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkSampler sampler_ = VK_NULL_HANDLE;
  friend class CommandBatch;
};

}  // namespace vox::gpu
