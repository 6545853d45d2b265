#pragma once
// GPU transfer-mesh-guided ray caster (shaders/raycast_prepare.comp and
// shaders/raycast.comp; CPU reference geometry/render/raycast_reference.h).
//
// The source grid goes to the GPU once, as uint16 labels packed two per word
// in z-slabs of whole slices, one storage binding (at most 128 MiB) per slab,
// up to VOX_RAYCAST_MAX_SLABS slabs (512 M voxels with 128 MiB bindings). The
// mesh connectivity, neighbours, boundary faces and rest coordinates go once
// too, and so does the boundary BVH's topology. Per frame the host writes
// only the deformed positions, as floats straight into one of two
// persistently mapped host-visible buffers (frames alternate, so that a
// frame's writes never touch the buffer the previous frame's passes read)
// that the passes bind without a copy. Compute passes refit the BVH's boxes
// (one per tree level: shaders/raycast_refit.comp) and recompute the per-tet
// factors (eq. 5.1-5.2), two rasterize the front boundary faces into the
// entry buffer (each pixel's first entry face and the number of front faces
// its ray crosses, and which 8x8 tiles hold such pixels, listed on the GPU:
// shaders/raycast_entries.comp), then one invocation per
// pixel of those tiles casts its ray, querying the BVH only for re-entries:
// on CPU drivers an invocation of the ray shader costs even when it exits at
// once, and most tiles see no mesh. The entry passes also size their own
// and the ray pass's dispatches (indirect dispatch), so a frame is one
// submission that the host neither reads from nor waits on midway.
//
// lavapipe ends a shader invocation after 65535 loop iterations. The entry
// pass splits large faces to stay below; a ray takes about three iterations
// per cell it crosses, so rays longer than about 20,000 cells (grids of over
// 6,000 voxels per side) would be cut short there.

#include "geometry/label_grid.h"
#include "geometry/render/palette.h"
#include "geometry/render/raycast_scene.h"
#include "geometry/rgb_image.h"
#include "gpu/buffer.h"
#include "gpu/command.h"
#include "gpu/context.h"
#include "gpu/image.h"
#include "gpu/pipeline.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace vox::gpu {

struct RaycastKernelOptions {
  // Bytes per label slab; 0 = the context's largest binding. Tests set small
  // values so that several slabs are exercised on small grids.
  std::uint64_t slabBytes = 0;
  // Work groups per row of the ray pass's dispatch; 0 = the device's limit.
  // Tests set small values so that the dispatch spans several rows.
  std::uint32_t rayGroupsPerRow = 0;
};

// Times of the last frame (ms). Host times are the last call's; GPU times
// come from timestamps (0 when the queue has none) of the last frame the host
// waited for: renderTo's frame is waited for when the next frame starts or
// at wait().
struct RaycastFrameTimes {
  double uploadMs = 0.0;     // host: positions and parameters into mapped memory
  double prepareGpuMs = 0.0; // GPU: BVH refit and per-tet factors
  double entriesGpuMs = 0.0; // GPU: entry buffer
  double raycastGpuMs = 0.0; // GPU: the rays
  double totalMs = 0.0;      // host: render() from call to image
};

class RaycastKernel {
public:
  // `mesh` must have been built for `source` (buildRaycastMesh). Throws
  // RuntimeFailure when it was not, when the grid needs more than
  // VOX_RAYCAST_MAX_SLABS slabs, or when a mesh array exceeds one binding.
  RaycastKernel(Context& context, const LabelGrid& source, const RaycastMesh& mesh, RaycastKernelOptions options = {});

  // frame.positions go to the GPU; frame.bvh is not read (the kernel refits
  // its own tree).
  RgbImage render(const RaycastFrame& frame, const RaycastView& view, const Palette& palette, const RaycastShading& shading = {},
                  const RaycastLimits& limits = {});
  // The same frame into a GPU image of the camera's size, not read back (the
  // viewer blits it to the screen). Returns once the frame is submitted:
  // later submissions to the queue see the image written (the frame ends
  // with a barrier), and the next frame waits for this one before it reuses
  // the kernel's buffers. The target must live until then (wait()).
  void renderTo(Image2D& target, const RaycastFrame& frame, const RaycastView& view, const Palette& palette,
                const RaycastShading& shading = {}, const RaycastLimits& limits = {});

  // The viewer's frame: `frame` from placeRaycastFrame (no positions or
  // BVH) and `deformedPositions` (#V, grid frame), which go to the render
  // frame on their way into the mapped positions buffer. The image equals
  // renderTo's with prepareRaycastFrame's frame. Returns once submitted.
  void renderTo(Image2D& target, const RaycastFrame& frame, const std::vector<Eigen::Vector3d>& deformedPositions,
                const RaycastView& view, const Palette& palette, const RaycastShading& shading = {}, const RaycastLimits& limits = {});

  // Waits for the last frame's GPU work.
  void wait();

  // The boundary BVH of the last frame as the GPU refitted it (float boxes
  // padded for the tolerant face test; before any frame, the rest tree's).
  // Waits for the frame.
  std::vector<BvhNode> downloadBvh();

  const RaycastFrameTimes& lastTimes() const { return times_; }
  std::size_t slabCount() const { return slabs_.size(); }
  std::uint64_t gridUploadBytes() const { return gridBytes_; }

private:
  // Records and runs everything up to the ray pass, whose dispatch stays
  // recorded for the caller to append its copy and call finishFrame().
  // `deformed`: grid-frame positions, or nullptr for frame.positions.
  void castRays(const RaycastFrame& frame, const std::vector<Eigen::Vector3d>* deformed, const RaycastView& view, const Palette& palette,
                const RaycastShading& shading, const RaycastLimits& limits);
  // The GPU times of the frame the batch last waited for.
  void readGpuTimes();

  Context& context_;
  GridGeometry source_;
  Index3 sourceShift_{0, 0, 0};
  std::size_t vertexCount_ = 0, tetCount_ = 0, nodeCount_ = 0, faceCount_ = 0;
  ComputePipeline refit_;
  ComputePipeline prepare_;
  ComputePipeline entries_;
  ComputePipeline raycast_;
  std::uint32_t slabSlices_ = 0;
  std::vector<Buffer> slabs_;
  std::uint64_t gridBytes_ = 0;
  // Uploaded once.
  Buffer tets_, neighbors_, rest_, faces_;
  // The BVH (topology uploaded once, boxes refitted per frame), the refit
  // order and its levels: [first, first + count) of the order per dispatch.
  Buffer nodes_, refitOrder_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> refitLevels_;
  // Per frame: the positions (mapped, two for alternating frames), staging
  // (host visible) and device copies of the rest.
  Buffer positions_[2];
  std::uint32_t frameIndex_ = 0;
  Buffer paramsStaging_, paletteStaging_;
  Buffer params_, palette_, factors_;
  Buffer entryBuffer_, image_, imageReadback_, tileFlags_, tiles_;
  Buffer dispatchSizes_;  // indirect dispatch sizes the entry passes write
  std::uint32_t tileCount_ = 0;
  std::uint32_t rayGroupsPerRow_ = 0;
  CommandBatch batch_;
  RaycastFrameTimes times_;
};

}  // namespace vox::gpu
