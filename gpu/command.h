#pragma once
// CommandBatch: records compute dispatches, copies and timestamps into one
// command buffer, submits it and waits, or submits it and lets the host go
// on (submit(); recording the next batch first waits for this one).

#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/image.h"
#include "gpu/pipeline.h"

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace vox::gpu {

// One descriptor of a dispatch, in binding order.
struct Binding {
  const Buffer* buffer = nullptr;
  std::uint64_t offset = 0;
  std::uint64_t range = VK_WHOLE_SIZE;
  const Image3D* image = nullptr;

  static Binding storage(const Buffer& b, std::uint64_t offset = 0, std::uint64_t range = VK_WHOLE_SIZE) {
    return {&b, offset, range, nullptr};
  }
  static Binding uniform(const Buffer& b, std::uint64_t offset = 0, std::uint64_t range = VK_WHOLE_SIZE) {
    return {&b, offset, range, nullptr};
  }
  static Binding image3D(const Image3D& img) { return {nullptr, 0, 0, &img}; }
};

struct Timing {
  std::string label;
  double ms = 0.0;  // since the batch's first timestamp
};

class CommandBatch {
public:
  explicit CommandBatch(Context& context, std::uint32_t maxTimestamps = 64);
  ~CommandBatch();
  CommandBatch(const CommandBatch&) = delete;
  CommandBatch& operator=(const CommandBatch&) = delete;

  void dispatch(const ComputePipeline& pipeline, std::initializer_list<Binding> bindings, const void* push,
                std::uint32_t pushBytes, std::uint32_t groupsX, std::uint32_t groupsY = 1, std::uint32_t groupsZ = 1);
  template <class Push>
  void dispatch(const ComputePipeline& pipeline, std::initializer_list<Binding> bindings, const Push& push,
                std::uint32_t groupsX, std::uint32_t groupsY = 1, std::uint32_t groupsZ = 1) {
    dispatch(pipeline, bindings, &push, sizeof(Push), groupsX, groupsY, groupsZ);
  }

  // The dispatch size (x, y, z groups) read by the GPU from `sizes` at
  // `offset` (a buffer made with VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT), as an
  // earlier pass wrote it: the host never sees it.
  void dispatchIndirect(const ComputePipeline& pipeline, std::initializer_list<Binding> bindings, const void* push,
                        std::uint32_t pushBytes, const Buffer& sizes, std::uint64_t offset);
  template <class Push>
  void dispatchIndirect(const ComputePipeline& pipeline, std::initializer_list<Binding> bindings, const Push& push, const Buffer& sizes,
                        std::uint64_t offset) {
    dispatchIndirect(pipeline, bindings, &push, sizeof(Push), sizes, offset);
  }

  // Makes all earlier shader and transfer writes visible to later shader,
  // transfer, indirect-dispatch and host accesses.
  void barrier();
  void copy(const Buffer& src, Buffer& dst, std::uint64_t bytes, std::uint64_t srcOffset = 0, std::uint64_t dstOffset = 0);
  // The slices [z0, z0 + depth) of a 3D image from / to the buffer's start.
  void copy(const Buffer& src, Image3D& dst, std::uint32_t z0, std::uint32_t depth);
  void copy(const Image3D& src, Buffer& dst, std::uint32_t z0, std::uint32_t depth);
  // Tightly packed RGBA8 rows (x fastest) to and from a 2D image.
  void copy(const Buffer& src, Image2D& dst, std::uint64_t srcOffset = 0);
  void copy(const Image2D& src, Buffer& dst);
  void fill(Buffer& dst, std::uint32_t value, std::uint64_t offset = 0, std::uint64_t bytes = VK_WHOLE_SIZE);
  // From an undefined layout (contents discarded) to VK_IMAGE_LAYOUT_GENERAL.
  void transitionToGeneral(VkImage image);
  // Records arbitrary commands (e.g. a UI library's uploads) into the batch.
  void record(const std::function<void(VkCommandBuffer)>& commands);
  // Records a GPU timestamp (ignored when the queue has none).
  void timestamp(std::string label);

  void submitAndWait();
  // Submits without waiting. Later submissions to the queue are ordered
  // after this one's commands only as far as its last barrier() says.
  void submit();
  // Waits for the last submit(), if any.
  void wait();
  bool pending() const { return pending_; }
  // Timestamps of the last submission that was waited for.
  const std::vector<Timing>& timings() const { return timings_; }

  VkCommandBuffer handle() const { return cmd_; }

private:
  void begin();
  // Binds the pipeline, its descriptors and push constants.
  void bind(const ComputePipeline& pipeline, std::initializer_list<Binding> bindings, const void* push, std::uint32_t pushBytes);
  Context& context_;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  VkQueryPool queries_ = VK_NULL_HANDLE;
  std::uint32_t maxTimestamps_ = 0;
  std::vector<std::string> labels_;
  std::vector<Timing> timings_;
  bool recording_ = false;
  bool pending_ = false;
};

}  // namespace vox::gpu
