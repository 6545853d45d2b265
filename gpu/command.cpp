#include "gpu/command.h"

#include "geometry/error.h"
#include "gpu/vk_check.h"

#include <cstdint>

namespace vox::gpu {

CommandBatch::CommandBatch(Context& context, std::uint32_t maxTimestamps) : context_(context), maxTimestamps_(maxTimestamps) {
  VkDevice dev = context.device();
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = context.commandPool();
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VOX_VK(vkAllocateCommandBuffers(dev, &ai, &cmd_));
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  if (VkResult r = vkCreateFence(dev, &fci, nullptr, &fence_); r != VK_SUCCESS) {
    vkFreeCommandBuffers(dev, context.commandPool(), 1, &cmd_);
    throwVulkanFailure("vkCreateFence", r);
  }
  if (context.info().timestampPeriodNs > 0.0 && maxTimestamps > 0) {
    VkQueryPoolCreateInfo qci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qci.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qci.queryCount = maxTimestamps;
    if (vkCreateQueryPool(dev, &qci, nullptr, &queries_) != VK_SUCCESS) queries_ = VK_NULL_HANDLE;
  }
}

CommandBatch::~CommandBatch() {
  VkDevice dev = context_.device();
  if (pending_) vkWaitForFences(dev, 1, &fence_, VK_TRUE, UINT64_MAX);
  if (recording_) vkEndCommandBuffer(cmd_);
  if (queries_) vkDestroyQueryPool(dev, queries_, nullptr);
  vkDestroyFence(dev, fence_, nullptr);
  vkFreeCommandBuffers(dev, context_.commandPool(), 1, &cmd_);
}

void CommandBatch::begin() {
  if (recording_) return;
  wait();
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VOX_VK(vkBeginCommandBuffer(cmd_, &bi));
  if (queries_) vkCmdResetQueryPool(cmd_, queries_, 0, maxTimestamps_);
  labels_.clear();
  recording_ = true;
}

namespace {

void checkInterface(const PipelineDesc& desc, std::size_t bindings, std::uint32_t pushBytes) {
  if (bindings != desc.bindings.size())
    throw RuntimeFailure(desc.shader + ": dispatch given " + std::to_string(bindings) + " bindings, pipeline has " +
                         std::to_string(desc.bindings.size()));
  if (pushBytes != desc.pushConstantBytes) throw RuntimeFailure(desc.shader + ": push constant size mismatch");
}

}  // namespace

void CommandBatch::dispatch(const ComputePipeline& pipeline, std::initializer_list<Binding> bindings, const void* push,
                            std::uint32_t pushBytes, std::uint32_t gx, std::uint32_t gy, std::uint32_t gz) {
  const auto& desc = pipeline.desc();
  const auto& lim = context_.info().maxWorkGroupCount;
  checkInterface(desc, bindings.size(), pushBytes);
  if (gx == 0 || gy == 0 || gz == 0) return;
  if (gx > lim[0] || gy > lim[1] || gz > lim[2]) throw RuntimeFailure(desc.shader + ": dispatch exceeds the work group count limit");
  bind(pipeline, bindings, push, pushBytes);
  vkCmdDispatch(cmd_, gx, gy, gz);
}

void CommandBatch::dispatchIndirect(const ComputePipeline& pipeline, std::initializer_list<Binding> bindings, const void* push,
                                    std::uint32_t pushBytes, const Buffer& sizes, std::uint64_t offset) {
  if (!sizes.valid() || offset % 4 != 0 || offset + 12 > sizes.size())
    throw RuntimeFailure(pipeline.desc().shader + ": indirect dispatch sizes out of the buffer");
  bind(pipeline, bindings, push, pushBytes);
  vkCmdDispatchIndirect(cmd_, sizes.handle(), offset);
}

void CommandBatch::bind(const ComputePipeline& pipeline, std::initializer_list<Binding> bindings, const void* push,
                        std::uint32_t pushBytes) {
  const auto& desc = pipeline.desc();
  checkInterface(desc, bindings.size(), pushBytes);
  begin();
  std::vector<VkDescriptorBufferInfo> bufferInfos(bindings.size());
  std::vector<VkDescriptorImageInfo> imageInfos(bindings.size());
  std::vector<VkWriteDescriptorSet> writes;
  std::size_t i = 0;
  for (const Binding& b : bindings) {
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstBinding = std::uint32_t(i);
    w.descriptorCount = 1;
    switch (desc.bindings[i]) {
      case BindingKind::StorageBuffer:
      case BindingKind::UniformBuffer:
        if (!b.buffer || !b.buffer->valid()) throw RuntimeFailure(desc.shader + ": binding " + std::to_string(i) + " needs a buffer");
        if (b.range != VK_WHOLE_SIZE && desc.bindings[i] == BindingKind::StorageBuffer && b.range > context_.info().maxStorageBufferRange)
          throw RuntimeFailure(desc.shader + ": binding " + std::to_string(i) + " exceeds maxStorageBufferRange");
        bufferInfos[i] = {b.buffer->handle(), b.offset, b.range};
        w.descriptorType = desc.bindings[i] == BindingKind::StorageBuffer ? VK_DESCRIPTOR_TYPE_STORAGE_BUFFER : VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
        w.pBufferInfo = &bufferInfos[i];
        break;
      case BindingKind::StorageImage:
      case BindingKind::SampledImage:
        if (!b.image) throw RuntimeFailure(desc.shader + ": binding " + std::to_string(i) + " needs an image");
        imageInfos[i] = {VK_NULL_HANDLE, b.image->view(), VK_IMAGE_LAYOUT_GENERAL};
        w.descriptorType = desc.bindings[i] == BindingKind::StorageImage ? VK_DESCRIPTOR_TYPE_STORAGE_IMAGE : VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
        w.pImageInfo = &imageInfos[i];
        break;
    }
    writes.push_back(w);
    ++i;
  }
  vkCmdBindPipeline(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
  if (!writes.empty())
    context_.cmdPushDescriptorSet(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.layout(), 0, std::uint32_t(writes.size()), writes.data());
  if (pushBytes) vkCmdPushConstants(cmd_, pipeline.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, pushBytes, push);
}

void CommandBatch::barrier() {
  begin();
  VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                     VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_HOST_READ_BIT | VK_ACCESS_INDIRECT_COMMAND_READ_BIT;
  vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_HOST_BIT |
                           VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT,
                       0, 1, &mb,
                       0, nullptr, 0, nullptr);
}

void CommandBatch::copy(const Buffer& src, Buffer& dst, std::uint64_t bytes, std::uint64_t srcOffset, std::uint64_t dstOffset) {
  begin();
  VkBufferCopy region{srcOffset, dstOffset, bytes};
  vkCmdCopyBuffer(cmd_, src.handle(), dst.handle(), 1, &region);
  barrier();
}

namespace {
VkBufferImageCopy imageSlices(const Image3D& img, std::uint32_t z0, std::uint32_t depth) {
  VkBufferImageCopy r{};
  r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  r.imageOffset = {0, 0, std::int32_t(z0)};
  r.imageExtent = {img.extent()[0], img.extent()[1], depth};
  return r;
}
}  // namespace

void CommandBatch::copy(const Buffer& src, Image3D& dst, std::uint32_t z0, std::uint32_t depth) {
  begin();
  const VkBufferImageCopy r = imageSlices(dst, z0, depth);
  vkCmdCopyBufferToImage(cmd_, src.handle(), dst.handle(), VK_IMAGE_LAYOUT_GENERAL, 1, &r);
  barrier();
}

void CommandBatch::copy(const Image3D& src, Buffer& dst, std::uint32_t z0, std::uint32_t depth) {
  begin();
  const VkBufferImageCopy r = imageSlices(src, z0, depth);
  vkCmdCopyImageToBuffer(cmd_, src.handle(), VK_IMAGE_LAYOUT_GENERAL, dst.handle(), 1, &r);
  barrier();
}

void CommandBatch::copy(const Buffer& src, Image2D& dst, std::uint64_t srcOffset) {
  begin();
  VkBufferImageCopy r{};
  r.bufferOffset = srcOffset;
  r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  r.imageExtent = {dst.width(), dst.height(), 1};
  vkCmdCopyBufferToImage(cmd_, src.handle(), dst.handle(), VK_IMAGE_LAYOUT_GENERAL, 1, &r);
  barrier();
}

void CommandBatch::copy(const Image2D& src, Buffer& dst) {
  begin();
  VkBufferImageCopy r{};
  r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  r.imageExtent = {src.width(), src.height(), 1};
  vkCmdCopyImageToBuffer(cmd_, src.handle(), VK_IMAGE_LAYOUT_GENERAL, dst.handle(), 1, &r);
  barrier();
}

void CommandBatch::record(const std::function<void(VkCommandBuffer)>& commands) {
  begin();
  commands(cmd_);
}

void CommandBatch::fill(Buffer& dst, std::uint32_t value, std::uint64_t offset, std::uint64_t bytes) {
  begin();
  vkCmdFillBuffer(cmd_, dst.handle(), offset, bytes, value);
  barrier();
}

void CommandBatch::transitionToGeneral(VkImage image) {
  begin();
  VkImageMemoryBarrier ib{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  ib.srcAccessMask = 0;
  ib.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT;
  ib.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  ib.newLayout = VK_IMAGE_LAYOUT_GENERAL;
  ib.srcQueueFamilyIndex = ib.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  ib.image = image;
  ib.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       0, 0, nullptr, 0, nullptr, 1, &ib);
}

void CommandBatch::timestamp(std::string label) {
  begin();
  if (!queries_ || labels_.size() >= maxTimestamps_) return;
  vkCmdWriteTimestamp(cmd_, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queries_, std::uint32_t(labels_.size()));
  labels_.push_back(std::move(label));
}

void CommandBatch::submitAndWait() {
  submit();
  wait();
}

void CommandBatch::submit() {
  if (!recording_) return;
  recording_ = false;
  VOX_VK(vkEndCommandBuffer(cmd_));
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd_;
  VkDevice dev = context_.device();
  VOX_VK(vkResetFences(dev, 1, &fence_));
  VOX_VK(vkQueueSubmit(context_.queue(), 1, &si, fence_));
  pending_ = true;
}

void CommandBatch::wait() {
  if (!pending_) return;
  pending_ = false;
  VkDevice dev = context_.device();
  VOX_VK(vkWaitForFences(dev, 1, &fence_, VK_TRUE, UINT64_MAX));
  timings_.clear();
  if (queries_ && !labels_.empty()) {
    std::vector<std::uint64_t> ticks(labels_.size());
    VOX_VK(vkGetQueryPoolResults(dev, queries_, 0, std::uint32_t(ticks.size()), ticks.size() * sizeof(std::uint64_t), ticks.data(),
                                 sizeof(std::uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    for (std::size_t i = 0; i < ticks.size(); ++i)
      timings_.push_back({labels_[i], double(ticks[i] - ticks[0]) * context_.info().timestampPeriodNs * 1e-6});
  }
  VOX_VK(vkResetCommandBuffer(cmd_, 0));
}

}  // namespace vox::gpu
