// Structs and binding numbers shared by the C++ host code (gpu/) and the GLSL
// kernels (shaders/*.comp). Plain 32-bit scalars only, so std430 and C++
// layouts agree; the C++ side checks sizes with static_assert.
#ifndef VOXMORPH_SHADER_INTERFACE_H
#define VOXMORPH_SHADER_INTERFACE_H

#ifdef __cplusplus
#include <cstdint>
namespace vox::shader {
using uint = std::uint32_t;
#endif

// ---------------------------------------------------------------- label_stats
// Per-label voxel counts and bounding boxes of a chunk of a label grid.
#define VOX_LABEL_STATS_BINDING_LABELS 0  // uint[]: two uint16 labels per word
#define VOX_LABEL_STATS_BINDING_COUNTS 1  // uint[labelCount]
#define VOX_LABEL_STATS_BINDING_BOXES 2   // uint[6 * labelCount]: min xyz, max xyz
#define VOX_LABEL_STATS_GROUP_SIZE 64
#define VOX_LABEL_STATS_VOXELS_PER_THREAD 64

struct LabelStatsPush {
  uint voxelCount;  // voxels in this chunk
  uint labelCount;  // labels >= labelCount are ignored
  uint nx;
  uint ny;
  uint startX;      // grid coordinates of the chunk's first voxel
  uint startY;
  uint startZ;
  uint pad;
};


// ---------------------------------------------------------------- rasterize
// Deformed-grid rasterization (gpu/kernels/rasterize.h) and field
// interpolation (gpu/kernels/field_interpolation.h) on a slab of lattice
// slices. CPU reference: geometry/raster/lattice_tets.h, rasterize.h.
// A task is one tet on one lattice slice, VOX_RASTER_ROWS_PER_TASK rows of
// it; the stages that follow a tet walk its scanline spans:
//   locate   (rasterize_locate.comp, tasks): state <- atomicMin(local tet)
//   resolve  (rasterize_resolve.comp, tasks, once per source window): the
//            samples a task's tet won get RESOLVED | source label
//   reduce   (rasterize_reduce.comp, voxel runs): majority of the k^3
//            sample labels, two uint16 labels per word
//   field    (interpolate_field.comp, tasks): the samples a task's tet won
//            get its barycentric interpolation (the rest keep the fill)
// A tet's map is loaded once per task and each sample is touched only by
// the task of the tet that won it.
#define VOX_RASTER_BINDING_STATE 0   // uint[]: per sample, slab lattice order
#define VOX_RASTER_BINDING_TETS 1    // RasterTet[]: the slab's tets, local index order
#define VOX_RASTER_BINDING_TASKS 2   // uint[2 * tasks]: local tet, (slab z) | (first row << 16)
#define VOX_RASTER_BINDING_MAPS 3    // RasterMap[] (resolve) or FieldMap[] (field), local tet order
#define VOX_RASTER_BINDING_SOURCE 4  // resolve: 4..4+VOX_RASTER_SOURCE_PARTS-1, uint[] window parts, 2 labels per word
#define VOX_FIELD_BINDING_OUTPUT 4   // field: float[] per sample
#define VOX_RASTER_REDUCE_BINDING_OUTPUT 1  // reduce: uint[], two uint16 labels per word
#define VOX_RASTER_SOURCE_PARTS 8
#define VOX_RASTER_SOURCE_PART_LABELS_LOG2 26  // labels per window part: 2^26 (128 MiB)
#define VOX_RASTER_NO_TET 0xFFFFFFFFu
#define VOX_RASTER_RESOLVED 0x80000000u        // | label
#define VOX_RASTER_TASK_GROUP_SIZE 64          // locate, resolve, field
#define VOX_RASTER_ROWS_PER_TASK 16
#define VOX_RASTER_REDUCE_GROUP_SIZE 64
#define VOX_RASTER_REDUCE_RUN 8                // output voxels per reduce invocation (even)
#define VOX_RASTER_MAX_SAMPLES 4               // k <= 4: k^3 <= 64 samples per voxel

// Face k of a tet (opposite vertex k): inward plane value at lattice point q
//   n.x * (q.x - a.x) + ((n.y * (q.y - a.y) + n.z * (q.z - a.z)) + d)
// (LatticeTet::planeValue); the GPU evaluates the bracket in this order
// without contraction and bounds each row at the root in x.
struct RasterFace {
  float nx;
  float ny;
  float nz;
  float d;
  int ax;
  int ay;
  int az;
  int pad;
};

struct RasterTet {
  RasterFace face[4];
  int loX;  // lattice box of candidate points (inclusive)
  int hiX;
  int loY;
  int hiY;
  int loZ;
  int hiZ;
  int pad0;
  int pad1;
};

// Source position of lattice point q through the tet (TetAffineMap<3>):
//   source(q) = s + round(f + L (q - a)), with L row-major.
struct RasterMap {
  int ax;
  int ay;
  int az;
  int sx;  // integer part of the source position at a
  int sy;
  int sz;
  float fx;  // fractional part, in [-1/2, 1/2)
  float fy;
  float fz;
  float l00;
  float l01;
  float l02;
  float l10;
  float l11;
  float l12;
  float l20;
  float l21;
  float l22;
};

// Field value at lattice point q through the tet (TetAffineMap<1>).
struct FieldMap {
  int ax;
  int ay;
  int az;
  float value;  // at a
  float gx;     // gradient per lattice step
  float gy;
  float gz;
  float pad;
};

struct RasterTaskPush {
  uint latticeNx;
  uint latticeNy;
  uint slabZ0;       // lattice slice of the slab's first sample slice
  uint taskBase;     // first task of this dispatch
  uint taskCount;    // tasks of this dispatch
  uint sourceNx;     // resolve: source grid dims
  uint sourceNy;
  uint sourceNz;
  uint windowFirst;  // resolve: source slices [windowFirst, windowEnd) are in the window
  uint windowEnd;
  uint pad0;
  uint pad1;
};

struct RasterReducePush {
  uint latticeNx;
  uint latticeNy;
  uint outputNx;    // output voxels per row (latticeNx / k)
  uint outputNy;
  uint voxelCount;  // output voxels of the slab
  uint runBase;     // first voxel run of this dispatch
  uint runCount;    // voxel runs of this dispatch
  uint pad;
};

#ifdef __cplusplus
static_assert(sizeof(RasterFace) == 32);
static_assert(sizeof(RasterTet) == 160);
static_assert(sizeof(RasterMap) == 72);
static_assert(sizeof(FieldMap) == 32);
static_assert(sizeof(RasterTaskPush) == 48);
static_assert(sizeof(RasterReducePush) == 32);
#endif

// -------------------------------------------------------------------- raycast
// Transfer-mesh-guided ray casting (gpu/kernels/raycast.h; CPU reference
// geometry/render/raycast_reference.h). All positions are in the render frame
// (geometry/render/raycast_scene.h): render cell c is a unit cube centred on
// the integer point c.
#define VOX_RAYCAST_GROUP_X 8
#define VOX_RAYCAST_GROUP_Y 8
#define VOX_RAYCAST_PREPARE_GROUP_SIZE 64
#define VOX_RAYCAST_MAX_SLABS 8     // label slabs (z-slabs of whole slices), one binding each
#define VOX_RAYCAST_MAX_CUTS 4      // three axis-aligned planes and one free plane
#define VOX_RAYCAST_BVH_STACK 64    // 2 * kBvhMaxDepth (geometry/render/boundary_bvh.h)
// Tolerances shared with the CPU reference (gpu/kernels/raycast.cpp checks
// that they equal geometry/render's kFaceHitTolerance, kInsideTolerance,
// kDegenerateTetRatio, kMaxEntryMarginCells and kFlatOccupancyGradient).
#define VOX_RAYCAST_FACE_HIT_TOLERANCE 1e-4
#define VOX_RAYCAST_INSIDE_TOLERANCE 1e-5
#define VOX_RAYCAST_DEGENERATE_TET_RATIO 1e-7
#define VOX_RAYCAST_MAX_ENTRY_MARGIN_CELLS 16.0
#define VOX_RAYCAST_FLAT_OCCUPANCY_GRADIENT 1e-3  // per source voxel: smooth normals fall back to the face's below

// raycast_prepare.comp: per-tet factors of eq. 5.1-5.2 from the deformed positions.
#define VOX_RAYCAST_PREPARE_BINDING_TETS 0       // uvec4[tetCount]: vertex indices
#define VOX_RAYCAST_PREPARE_BINDING_POSITIONS 1  // vec4[vertexCount]: render frame xyz
#define VOX_RAYCAST_PREPARE_BINDING_FACTORS 2    // vec4[4 * tetCount]: planes 1..3 (xyz, w), anchor (xyz)

// raycast_refit.comp: the boundary BVH's boxes for the deformed positions
// (CPU reference: refitBoundaryBvh in geometry/render/boundary_bvh.cpp). The
// rest tree's topology stays on the GPU; one dispatch boxes every leaf (its
// faces' vertices, padded like the host's boxes: VOX_RAYCAST_REFIT_PAD cells
// plus 2 VOX_RAYCAST_FACE_HIT_TOLERANCE of the box's extent), then one per
// depth joins the inner nodes' children, deepest first.
#define VOX_RAYCAST_REFIT_GROUP_SIZE 64
#define VOX_RAYCAST_REFIT_PAD 1e-3
#define VOX_RAYCAST_REFIT_BINDING_NODES 0      // RaycastNode[nodeCount]
#define VOX_RAYCAST_REFIT_BINDING_FACES 1      // uvec4[faceCount]: vertices a, b, c and the tet
#define VOX_RAYCAST_REFIT_BINDING_POSITIONS 2  // vec4[vertexCount]: render frame xyz
#define VOX_RAYCAST_REFIT_BINDING_ORDER 3      // uint[nodeCount]: the leaves, then the inner nodes, deepest first

// raycast_entries.comp: one invocation per boundary face; rasterizes the
// front faces into the entry buffer (uint[3 * width * height], three planes):
// the smallest hit parameter t >= 0 per pixel (float bits, pass 0), the
// lowest face index hit at that t (pass 1), and the number of front faces
// the pixel's ray hits (pass 0). Pass 0 also flags the image tiles
// (VOX_RAYCAST_GROUP_X x VOX_RAYCAST_GROUP_Y pixels, row by row) that hold a
// hit pixel and appends each flagged tile to the tile list: only those tiles
// run the ray pass, whose indirect dispatch size pass 0 sets too. Pass 2,
// before the others, sets their dispatch size: the chunks of the face that
// covers the most pixels. No step of the frame waits for the host.
#define VOX_RAYCAST_ENTRIES_GROUP_SIZE 64
// Pixels one invocation tests at most: lavapipe ends any invocation after
// 65535 loop iterations, so faces that cover more pixels are split over the
// dispatch's second dimension.
#define VOX_RAYCAST_ENTRIES_CHUNK_PIXELS 16384
#define VOX_RAYCAST_NEAR_DEPTH 1e-3  // faces are clipped to depth t >= this (mm)
#define VOX_RAYCAST_ENTRIES_BINDING_PARAMS 0
#define VOX_RAYCAST_ENTRIES_BINDING_FACES 1
#define VOX_RAYCAST_ENTRIES_BINDING_POSITIONS 2
#define VOX_RAYCAST_ENTRIES_BINDING_ENTRIES 3
#define VOX_RAYCAST_ENTRIES_BINDING_TILE_FLAGS 4  // uint[tile count]: 1 where a pixel is hit
#define VOX_RAYCAST_ENTRIES_BINDING_TILES 5       // uint[1 + tile count]: the ray pass's tile list (raycast.comp)
#define VOX_RAYCAST_ENTRIES_BINDING_DISPATCH 6    // uint[8]: indirect dispatch sizes, VOX_RAYCAST_DISPATCH_*
// Offsets (in uints) of the indirect dispatch sizes (x, y, z) in the dispatch buffer.
#define VOX_RAYCAST_DISPATCH_ENTRIES 0  // entry passes 0 and 1: face groups, chunks, 1
#define VOX_RAYCAST_DISPATCH_RAYS 4     // ray pass: tiles per row (at most the device's limit), rows, 1

// raycast.comp: one invocation per pixel of the flagged tiles, one work group
// per tile; the other pixels keep the background the image was filled with.
// Weights of the two lights of shared/shading.glsl (and shadeRay).
#define VOX_SHADE_HEADLIGHT 0.75
#define VOX_SHADE_FILL 0.4
#define VOX_SHADE_DEPTH 0.6   // darkening at the far end of the scene's depth

#define VOX_RAYCAST_BINDING_PARAMS 0     // RaycastParams
#define VOX_RAYCAST_BINDING_NODES 1      // RaycastNode[]: boundary BVH
#define VOX_RAYCAST_BINDING_FACES 2      // uvec4[faceCount]: outward vertices a, b, c and the tet
#define VOX_RAYCAST_BINDING_POSITIONS 3  // vec4[vertexCount]
#define VOX_RAYCAST_BINDING_FACTORS 4    // vec4[4 * tetCount] (raycast_prepare.comp)
#define VOX_RAYCAST_BINDING_NEIGHBORS 5  // ivec4[tetCount]: across the face opposite vertex k, -1 = boundary
#define VOX_RAYCAST_BINDING_REST 6       // vec4[3 * tetCount]: (r1 - r0, r0.x), (r2 - r0, r0.y), (r3 - r0, r0.z)
#define VOX_RAYCAST_BINDING_PALETTE 7    // uint[labelCount]: RGBA8 (r in the low byte), alpha 0 = hidden
#define VOX_RAYCAST_BINDING_ENTRIES 8    // uint[3 * width * height] (raycast_entries.comp)
#define VOX_RAYCAST_BINDING_IMAGE 9      // uint[width * height]: RGBA8, row 0 at the top
#define VOX_RAYCAST_BINDING_TILES 10     // uint[1 + tile count]: the flagged tiles' count, then their indices, one per work group
#define VOX_RAYCAST_BINDING_SLAB0 11     // uint[] x VOX_RAYCAST_MAX_SLABS: two uint16 labels per word

struct RaycastPreparePush {
  uint tetCount;
  uint pad0;
  uint pad1;
  uint pad2;
};

struct RaycastRefitPush {
  uint first;  // nodes order[first .. first + count) of the refit order
  uint count;
  uint pad0;
  uint pad1;
};

struct RaycastEntriesPush {
  uint faceCount;
  uint pass;  // 0: depth and count, 1: face at the smallest depth, 2: dispatch size
  uint maxGroupsX;  // the device's work group count limit in x (rows of the ray pass's dispatch)
  uint pad1;
};

struct RaycastNode {
  float lo[3];
  int rightOrFirst;  // inner: right child (left child is the next node); leaf: first face
  float hi[3];
  int count;         // faces in a leaf, 0 for an inner node
};

struct RaycastParams {
  float eye[4];      // camera centre
  float forward[4];  // ray of pixel (x, y): eye + t (forward + sx right + sy up)
  float right[4];
  float up[4];
  float cellsLo[4];  // box covered by the cells of the deformed grid
  float cellsHi[4];
  float cuts[4 * VOX_RAYCAST_MAX_CUTS];  // cell c removed iff dot(xyz, c) > w
  float light[4];    // unit vector towards the fill light (grid-frame axes)
  float headlight[4];  // unit vector towards the camera (grid-frame axes)
  float toCamera[12];  // rows of [forward right up]^-1: q - eye -> (t, t sx, t sy)
  float tanHalfFovY;
  float aspect;
  float ambient;
  int sourceShift[4];  // source voxel = round(mapped point) + sourceShift
  int sourceDims[4];
  uint width;
  uint height;
  uint cutCount;
  uint background;     // RGBA8
  uint sliceVoxels;    // nx * ny of the source grid
  uint slabSlices;     // z-slices per label slab
  uint labelCount;     // palette entries; larger labels are hidden
  uint maxWalkSteps;
  uint maxEntries;
  uint maxCells;
  float depthNear;     // depth along the view axis (mm, = ray t) of the scene box's
  float depthFar;      // nearest and farthest corners: the depth cue's range (none if far <= near)
  float cellSize[4];   // spacing of the deformed grid (mm): render-frame gradients to grid-frame axes
  float differenceSteps[4];  // occupancyDifferenceSteps of the source grid (voxels)
  uint smoothNormals;  // 1: SurfaceNormals::Smooth, 0: Faces (geometry/render/surface_normals.h)
};

#ifdef __cplusplus
static_assert(sizeof(RaycastPreparePush) == 16);
static_assert(sizeof(RaycastNode) == 32);
static_assert(sizeof(RaycastEntriesPush) == 16);
static_assert(sizeof(RaycastParams) == 368);
#endif

#ifdef __cplusplus
static_assert(sizeof(LabelStatsPush) == 32);
}  // namespace vox::shader
#endif

#endif
