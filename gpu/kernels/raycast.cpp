#include "gpu/kernels/raycast.h"

#include "geometry/error.h"
#include "geometry/render/surface_normals.h"
#include "shaders/shared/interface.h"

#include <Eigen/LU>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

namespace vox::gpu {

namespace {

using shader::RaycastEntriesPush;
using shader::RaycastNode;
using shader::RaycastParams;
using shader::RaycastPreparePush;
using shader::RaycastRefitPush;

static_assert(VOX_RAYCAST_BVH_STACK == 2 * kBvhMaxDepth);
static_assert(VOX_RAYCAST_FACE_HIT_TOLERANCE == kFaceHitTolerance);
static_assert(VOX_RAYCAST_INSIDE_TOLERANCE == kInsideTolerance);
static_assert(VOX_RAYCAST_DEGENERATE_TET_RATIO == kDegenerateTetRatio);
static_assert(VOX_RAYCAST_MAX_ENTRY_MARGIN_CELLS == kMaxEntryMarginCells);
static_assert(VOX_RAYCAST_FLAT_OCCUPANCY_GRADIENT == kFlatOccupancyGradient);

PipelineDesc raycastPipeline() {
  PipelineDesc d;
  d.shader = "raycast.comp";
  d.bindings.assign(VOX_RAYCAST_BINDING_SLAB0 + VOX_RAYCAST_MAX_SLABS, BindingKind::StorageBuffer);
  d.pushConstantBytes = 0;
  return d;
}

std::uint64_t checkedBinding(const Context& context, std::uint64_t bytes, const char* what) {
  if (bytes > context.maxBindingBytes())
    throw RuntimeFailure(std::string("ray caster: ") + what + " need " + std::to_string(bytes) + " bytes, more than one storage binding (" +
                         std::to_string(context.maxBindingBytes()) + " bytes)");
  return std::max<std::uint64_t>(bytes, 16);
}

template <class T>
Buffer uploadOnce(Context& context, const std::vector<T>& data, const char* what) {
  Buffer b(context, checkedBinding(context, data.size() * sizeof(T), what), MemoryIntent::Device);
  b.upload(data.data(), data.size() * sizeof(T));
  return b;
}

// Float boxes that contain the double boxes and the GPU's tolerant
// triangle test (kFaceHitTolerance of a face's extent).
void storeNode(const BvhNode& n, RaycastNode& out) {
  const double pad = 1e-3 + 2.0 * kFaceHitTolerance * (n.hi - n.lo).maxCoeff();
  for (int a = 0; a < 3; ++a) {
    out.lo[a] = std::nextafter(float(n.lo[a] - pad), -std::numeric_limits<float>::infinity());
    out.hi[a] = std::nextafter(float(n.hi[a] + pad), std::numeric_limits<float>::infinity());
  }
  out.rightOrFirst = n.rightOrFirst;
  out.count = n.count;
}

std::uint32_t packRgba(Rgb c, bool opaque) {
  return std::uint32_t(c.r) | (std::uint32_t(c.g) << 8) | (std::uint32_t(c.b) << 16) | (opaque ? 0xFF000000u : 0u);
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

RaycastKernel::RaycastKernel(Context& context, const LabelGrid& source, const RaycastMesh& mesh, RaycastKernelOptions options)
    : context_(context),
      source_(source.geometry()),
      sourceShift_(mesh.sourceShift),
      vertexCount_(mesh.vertexCount),
      tetCount_(mesh.tets.size()),
      nodeCount_(mesh.restBvh.size()),
      faceCount_(mesh.boundary.size()),
      refit_(context, {"raycast_refit.comp",
                       {BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::StorageBuffer},
                       sizeof(RaycastRefitPush)}),
      prepare_(context, {"raycast_prepare.comp",
                         {BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::StorageBuffer},
                         sizeof(RaycastPreparePush)}),
      entries_(context, {"raycast_entries.comp",
                         {BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::StorageBuffer,
                          BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::StorageBuffer},
                         sizeof(RaycastEntriesPush)}),
      raycast_(context, raycastPipeline()),
      batch_(context) {
  const GridGeometry& g = source.geometry();
  if (g.dims != mesh.source.dims || !g.spacing.isApprox(mesh.source.spacing) || !g.origin.isApprox(mesh.source.origin))
    throw RuntimeFailure("ray caster: the mesh was built for another grid");
  for (int a = 0; a < 3; ++a)
    if (g.dims[a] < 1 || g.dims[a] > std::numeric_limits<std::int32_t>::max() / 2)
      throw RuntimeFailure("ray caster: source grid dims out of range");
  // Label slabs: whole z-slices, as many as one binding holds.
  const std::uint64_t sliceBytes = std::uint64_t(g.sliceVoxels()) * sizeof(Label);
  const std::uint64_t binding = options.slabBytes ? std::min(options.slabBytes, context.maxBindingBytes()) : context.maxBindingBytes();
  if (sliceBytes > binding) throw RuntimeFailure("ray caster: one z-slice of the grid exceeds a storage binding");
  slabSlices_ = std::uint32_t(std::min<std::uint64_t>(binding / sliceBytes, std::uint64_t(g.dims[2])));
  const std::uint64_t slabCount = (std::uint64_t(g.dims[2]) + slabSlices_ - 1) / slabSlices_;
  if (slabCount > VOX_RAYCAST_MAX_SLABS)
    throw RuntimeFailure("ray caster: the grid (" + std::to_string(g.voxelCount()) + " voxels) needs " + std::to_string(slabCount) +
                         " label slabs, more than the " + std::to_string(VOX_RAYCAST_MAX_SLABS) + " the kernel binds");
  for (std::uint64_t s = 0; s < slabCount; ++s) {
    const std::uint64_t k0 = s * slabSlices_;
    const std::uint64_t slices = std::min<std::uint64_t>(slabSlices_, std::uint64_t(g.dims[2]) - k0);
    const std::uint64_t bytes = slices * sliceBytes;
    Buffer b(context, (bytes + 3) / 4 * 4, MemoryIntent::Device);
    b.upload(source.data() + k0 * std::uint64_t(g.sliceVoxels()), bytes);
    gridBytes_ += bytes;
    slabs_.push_back(std::move(b));
  }

  // Connectivity, neighbours, boundary faces and rest frames: once.
  std::vector<std::uint32_t> tets(4 * tetCount_);
  std::vector<std::int32_t> neighbors(4 * tetCount_);
  std::vector<float> rest(12 * tetCount_);
  for (std::size_t t = 0; t < tetCount_; ++t) {
    for (int k = 0; k < 4; ++k) {
      tets[4 * t + std::size_t(k)] = std::uint32_t(mesh.tets[t][std::size_t(k)]);
      neighbors[4 * t + std::size_t(k)] = mesh.neighbors[t][std::size_t(k)];
    }
    const auto& r = mesh.restFrames[t];
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) rest[12 * t + 4 * std::size_t(k) + std::size_t(a)] = float(r[std::size_t(k) + 1][a]);
      rest[12 * t + 4 * std::size_t(k) + 3] = float(r[0][k]);
    }
  }
  std::vector<std::uint32_t> faces(4 * mesh.boundary.size());
  for (std::size_t f = 0; f < mesh.boundary.size(); ++f) {
    for (int k = 0; k < 3; ++k) faces[4 * f + std::size_t(k)] = std::uint32_t(mesh.boundary[f].vertices[std::size_t(k)]);
    faces[4 * f + 3] = std::uint32_t(mesh.boundary[f].tet);
  }
  tets_ = uploadOnce(context, tets, "tets");
  neighbors_ = uploadOnce(context, neighbors, "tet neighbours");
  rest_ = uploadOnce(context, rest, "rest coordinates");
  faces_ = uploadOnce(context, faces, "boundary faces");

  // The BVH with its rest boxes, and the refit order: every leaf, then the
  // inner nodes by depth, deepest first (children follow their parent in
  // depth-first order, so one forward sweep gives the depths).
  std::vector<RaycastNode> nodes(nodeCount_);
  std::vector<int> depth(nodeCount_, 0);
  int deepest = 0;
  for (std::size_t n = 0; n < nodeCount_; ++n) {
    const BvhNode& b = mesh.restBvh[n];
    storeNode(b, nodes[n]);
    if (b.count == 0) {
      depth[n + 1] = depth[std::size_t(b.rightOrFirst)] = depth[n] + 1;
      deepest = std::max(deepest, depth[n] + 1);
    }
  }
  std::vector<std::uint32_t> order;
  order.reserve(nodeCount_);
  for (std::size_t n = 0; n < nodeCount_; ++n)
    if (mesh.restBvh[n].count > 0) order.push_back(std::uint32_t(n));
  refitLevels_.emplace_back(0u, std::uint32_t(order.size()));
  for (int d = deepest; d >= 0; --d) {
    const auto first = std::uint32_t(order.size());
    for (std::size_t n = 0; n < nodeCount_; ++n)
      if (depth[n] == d && mesh.restBvh[n].count == 0) order.push_back(std::uint32_t(n));
    if (order.size() > first) refitLevels_.emplace_back(first, std::uint32_t(order.size()) - first);
  }
  nodes_ = uploadOnce(context, nodes, "BVH nodes");
  refitOrder_ = uploadOnce(context, order, "BVH refit order");

  const std::uint64_t positionBytes = checkedBinding(context, 16 * std::uint64_t(vertexCount_), "positions");
  const std::uint64_t factorBytes = checkedBinding(context, 64 * std::uint64_t(tetCount_), "tet factors");
  for (Buffer& b : positions_) b = Buffer(context, positionBytes, MemoryIntent::Upload);
  paramsStaging_ = Buffer(context, sizeof(RaycastParams), MemoryIntent::Upload);
  rayGroupsPerRow_ = options.rayGroupsPerRow ? std::min(options.rayGroupsPerRow, context.info().maxWorkGroupCount[0])
                                             : context.info().maxWorkGroupCount[0];
  dispatchSizes_ = Buffer(context, 8 * sizeof(std::uint32_t), MemoryIntent::Device, VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT);
  params_ = Buffer(context, sizeof(RaycastParams), MemoryIntent::Device);
  factors_ = Buffer(context, factorBytes, MemoryIntent::Device);
}

RgbImage RaycastKernel::render(const RaycastFrame& frame, const RaycastView& view, const Palette& palette, const RaycastShading& shading,
                               const RaycastLimits& limits) {
  const auto t0 = std::chrono::steady_clock::now();
  castRays(frame, nullptr, view, palette, shading, limits);
  const int w = view.camera.width, h = view.camera.height;
  batch_.copy(image_, imageReadback_, 4 * std::uint64_t(w) * std::uint64_t(h));
  batch_.barrier();
  batch_.submitAndWait();
  readGpuTimes();
  RgbImage image(w, h);
  const auto* px = static_cast<const std::uint32_t*>(imageReadback_.mapped());
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = {std::uint8_t(px[i] & 0xFF), std::uint8_t((px[i] >> 8) & 0xFF), std::uint8_t((px[i] >> 16) & 0xFF)};
  times_.totalMs = msSince(t0);
  return image;
}

void RaycastKernel::renderTo(Image2D& target, const RaycastFrame& frame, const RaycastView& view, const Palette& palette,
                             const RaycastShading& shading, const RaycastLimits& limits) {
  const auto t0 = std::chrono::steady_clock::now();
  if (std::int64_t(target.width()) != view.camera.width || std::int64_t(target.height()) != view.camera.height)
    throw RuntimeFailure("ray caster: the target image's size differs from the camera's");
  castRays(frame, nullptr, view, palette, shading, limits);
  batch_.copy(image_, target);
  batch_.barrier();
  batch_.submit();
  times_.totalMs = msSince(t0);
}

void RaycastKernel::renderTo(Image2D& target, const RaycastFrame& frame, const std::vector<Eigen::Vector3d>& deformedPositions,
                             const RaycastView& view, const Palette& palette, const RaycastShading& shading, const RaycastLimits& limits) {
  const auto t0 = std::chrono::steady_clock::now();
  if (std::int64_t(target.width()) != view.camera.width || std::int64_t(target.height()) != view.camera.height)
    throw RuntimeFailure("ray caster: the target image's size differs from the camera's");
  castRays(frame, &deformedPositions, view, palette, shading, limits);
  batch_.copy(image_, target);
  batch_.barrier();
  batch_.submit();
  times_.totalMs = msSince(t0);
}

std::vector<BvhNode> RaycastKernel::downloadBvh() {
  wait();
  std::vector<RaycastNode> stored(nodeCount_);
  nodes_.download(stored.data(), sizeof(RaycastNode) * stored.size());
  std::vector<BvhNode> out(nodeCount_);
  for (std::size_t n = 0; n < nodeCount_; ++n) {
    for (int a = 0; a < 3; ++a) {
      out[n].lo[a] = stored[n].lo[a];
      out[n].hi[a] = stored[n].hi[a];
    }
    out[n].rightOrFirst = stored[n].rightOrFirst;
    out[n].count = stored[n].count;
  }
  return out;
}

void RaycastKernel::wait() {
  batch_.wait();
  readGpuTimes();
}

void RaycastKernel::readGpuTimes() {
  const auto& ts = batch_.timings();
  if (ts.size() == 5) {
    times_.prepareGpuMs = ts[2].ms - ts[1].ms;
    times_.entriesGpuMs = ts[3].ms - ts[2].ms;
    times_.raycastGpuMs = ts[4].ms - ts[3].ms;
  }
}

void RaycastKernel::castRays(const RaycastFrame& frame, const std::vector<Eigen::Vector3d>* deformed, const RaycastView& view,
                             const Palette& palette, const RaycastShading& shading, const RaycastLimits& limits) {
  const auto t0 = std::chrono::steady_clock::now();
  if ((deformed ? deformed->size() : frame.positions.size()) != vertexCount_)
    throw RuntimeFailure("ray caster: the frame does not belong to the mesh the kernel was built for");
  const int w = view.camera.width, h = view.camera.height;

  // The positions, in the render frame, straight into this frame's mapped
  // buffer (the same floats as float(frame.positions[v]) would be).
  const Buffer& positions = positions_[frameIndex_];
  frameIndex_ ^= 1u;
  auto* pos = static_cast<float*>(positions.mapped());
  if (deformed) {
    for (std::size_t v = 0; v < vertexCount_; ++v) {
      const Eigen::Vector3d r = frame.toRender((*deformed)[v]);
      for (int a = 0; a < 3; ++a) pos[4 * v + std::size_t(a)] = float(r[a]);
      pos[4 * v + 3] = 0.0f;
    }
  } else {
    for (std::size_t v = 0; v < vertexCount_; ++v) {
      for (int a = 0; a < 3; ++a) pos[4 * v + std::size_t(a)] = float(frame.positions[v][a]);
      pos[4 * v + 3] = 0.0f;
    }
  }
  // The previous frame may still run: it reads the other positions buffer,
  // and the buffers below, which this frame rewrites.
  const double positionsMs = msSince(t0);
  wait();
  const auto t1 = std::chrono::steady_clock::now();

  const Eigen::Vector3d steps = occupancyDifferenceSteps(source_);
  RaycastParams p{};
  for (int a = 0; a < 3; ++a) {
    p.eye[a] = float(view.eye[a]);
    p.forward[a] = float(view.forward[a]);
    p.right[a] = float(view.right[a]);
    p.up[a] = float(view.up[a]);
    p.cellsLo[a] = float(frame.cellsLo[a]);
    p.cellsHi[a] = float(frame.cellsHi[a]);
    p.light[a] = float(view.light[a]);
    p.headlight[a] = float(view.headlight[a]);
    p.cellSize[a] = float(frame.output.spacing[a]);
    p.differenceSteps[a] = float(steps[a]);
    p.sourceShift[a] = std::int32_t(sourceShift_[a]);
    p.sourceDims[a] = std::int32_t(source_.dims[a]);
  }
  if (view.cuts.size() > VOX_RAYCAST_MAX_CUTS) throw RuntimeFailure("ray caster: more than four cutting planes");
  // Camera coordinates for the entry pass: (t, t sx, t sy) = [F R U]^-1 (p - eye).
  Eigen::Matrix3d basis;
  basis << view.forward, view.right, view.up;
  const Eigen::Matrix3d toCamera = basis.inverse();
  for (int r = 0; r < 3; ++r)
    for (int a = 0; a < 3; ++a) p.toCamera[4 * r + a] = float(toCamera(r, a));
  for (std::size_t c = 0; c < view.cuts.size(); ++c)
    for (int a = 0; a < 4; ++a) p.cuts[4 * c + std::size_t(a)] = float(view.cuts[c][a]);
  p.tanHalfFovY = float(view.camera.tanHalfFovY);
  p.aspect = float(view.camera.aspect);
  p.ambient = float(shading.ambient);
  p.smoothNormals = shading.normals == SurfaceNormals::Smooth ? 1u : 0u;
  p.depthNear = float(view.depthNear);
  p.depthFar = float(view.depthFar);
  p.width = std::uint32_t(w);
  p.height = std::uint32_t(h);
  p.cutCount = std::uint32_t(view.cuts.size());
  p.background = packRgba(shading.background, true);
  p.sliceVoxels = std::uint32_t(source_.sliceVoxels());
  p.slabSlices = slabSlices_;
  p.labelCount = std::uint32_t(palette.size());
  p.maxWalkSteps = std::uint32_t(limits.maxWalkSteps);
  p.maxEntries = std::uint32_t(limits.maxEntries);
  p.maxCells = std::uint32_t(4 * (frame.output.dims[0] + frame.output.dims[1] + frame.output.dims[2]) + 64);
  std::memcpy(paramsStaging_.mapped(), &p, sizeof(p));

  const std::uint64_t paletteBytes = checkedBinding(context_, 4 * std::uint64_t(palette.size()), "palette");
  if (!palette_.valid() || palette_.size() < paletteBytes) {
    paletteStaging_ = Buffer(context_, paletteBytes, MemoryIntent::Upload);
    palette_ = Buffer(context_, paletteBytes, MemoryIntent::Device);
  }
  auto* pal = static_cast<std::uint32_t*>(paletteStaging_.mapped());
  for (std::size_t l = 0; l < palette.size(); ++l) pal[l] = packRgba(palette.color(Label(l)), palette.visible(Label(l)));

  const std::uint64_t imageBytes = checkedBinding(context_, 4 * std::uint64_t(w) * std::uint64_t(h), "the image");
  const std::uint64_t entryBytes = checkedBinding(context_, 3 * imageBytes, "the entry buffer");
  const auto tilesX = std::uint32_t((w + VOX_RAYCAST_GROUP_X - 1) / VOX_RAYCAST_GROUP_X);
  const auto tilesY = std::uint32_t((h + VOX_RAYCAST_GROUP_Y - 1) / VOX_RAYCAST_GROUP_Y);
  if (!image_.valid() || image_.size() != imageBytes) {
    image_ = Buffer(context_, imageBytes, MemoryIntent::Device);
    imageReadback_ = Buffer(context_, imageBytes, MemoryIntent::Readback);
    entryBuffer_ = Buffer(context_, entryBytes, MemoryIntent::Device);
    tileCount_ = tilesX * tilesY;
    tileFlags_ = Buffer(context_, 4 * std::uint64_t(tileCount_), MemoryIntent::Device);
    tiles_ = Buffer(context_, 4 * (1 + std::uint64_t(tileCount_)), MemoryIntent::Device);
  }
  times_.uploadMs = positionsMs + msSince(t1);

  batch_.timestamp("start");
  batch_.copy(paramsStaging_, params_, sizeof(RaycastParams));
  batch_.copy(paletteStaging_, palette_, 4 * std::uint64_t(palette.size()));
  batch_.timestamp("uploaded");
  for (const auto& [first, count] : refitLevels_) {
    batch_.dispatch(refit_,
                    {Binding::storage(nodes_), Binding::storage(faces_), Binding::storage(positions), Binding::storage(refitOrder_)},
                    RaycastRefitPush{first, count, 0, 0}, (count + VOX_RAYCAST_REFIT_GROUP_SIZE - 1) / VOX_RAYCAST_REFIT_GROUP_SIZE);
    batch_.barrier();
  }
  const RaycastPreparePush push{std::uint32_t(tetCount_), 0, 0, 0};
  batch_.dispatch(prepare_, {Binding::storage(tets_), Binding::storage(positions), Binding::storage(factors_)}, push,
                  std::uint32_t((tetCount_ + VOX_RAYCAST_PREPARE_GROUP_SIZE - 1) / VOX_RAYCAST_PREPARE_GROUP_SIZE));
  batch_.barrier();
  batch_.timestamp("prepared");
  // Entry buffer: depth planes start at +inf bits, faces at ~0, counts at 0.
  batch_.fill(entryBuffer_, 0xFFFFFFFFu, 0, 2 * imageBytes);
  batch_.fill(entryBuffer_, 0u, 2 * imageBytes, imageBytes);
  batch_.fill(tileFlags_, 0u);
  batch_.fill(tiles_, 0u, 0, 4);
  // Dispatch sizes: the entry passes' face groups and one chunk (pass 2 sets
  // the chunks), no ray work groups (pass 0 adds them).
  const auto faceGroups = std::uint32_t((faceCount_ + VOX_RAYCAST_ENTRIES_GROUP_SIZE - 1) / VOX_RAYCAST_ENTRIES_GROUP_SIZE);
  batch_.fill(dispatchSizes_, faceGroups, 4 * VOX_RAYCAST_DISPATCH_ENTRIES, 4);
  batch_.fill(dispatchSizes_, 1u, 4 * (VOX_RAYCAST_DISPATCH_ENTRIES + 1), 8);
  batch_.fill(dispatchSizes_, 0u, 4 * VOX_RAYCAST_DISPATCH_RAYS, 4);
  batch_.fill(dispatchSizes_, 1u, 4 * (VOX_RAYCAST_DISPATCH_RAYS + 1), 8);
  batch_.fill(image_, p.background);
  batch_.barrier();
  auto entriesPass = [&](std::uint32_t pass) -> RaycastEntriesPush { return {std::uint32_t(faceCount_), pass, rayGroupsPerRow_, 0}; };
  const std::initializer_list<Binding> entriesBindings = {Binding::storage(params_),      Binding::storage(faces_),
                                                          Binding::storage(positions),    Binding::storage(entryBuffer_),
                                                          Binding::storage(tileFlags_),   Binding::storage(tiles_),
                                                          Binding::storage(dispatchSizes_)};
  batch_.dispatch(entries_, entriesBindings, entriesPass(2), faceGroups);
  batch_.barrier();
  for (std::uint32_t pass = 0; pass < 2; ++pass) {
    batch_.dispatchIndirect(entries_, entriesBindings, entriesPass(pass), dispatchSizes_, 4 * VOX_RAYCAST_DISPATCH_ENTRIES);
    batch_.barrier();
  }
  batch_.timestamp("entries");

  // The flagged tiles: one work group each.
  const Buffer& s0 = slabs_[0];
  auto slab = [&](std::size_t i) { return Binding::storage(i < slabs_.size() ? slabs_[i] : s0); };
  batch_.dispatchIndirect(raycast_,
                          {Binding::storage(params_), Binding::storage(nodes_), Binding::storage(faces_), Binding::storage(positions),
                           Binding::storage(factors_), Binding::storage(neighbors_), Binding::storage(rest_), Binding::storage(palette_),
                           Binding::storage(entryBuffer_), Binding::storage(image_), Binding::storage(tiles_), slab(0), slab(1),
                           slab(2), slab(3), slab(4), slab(5), slab(6), slab(7)},
                          nullptr, 0, dispatchSizes_, 4 * VOX_RAYCAST_DISPATCH_RAYS);
  batch_.barrier();
  batch_.timestamp("raycast");
}

}  // namespace vox::gpu
