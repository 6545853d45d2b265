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
// slices. CPU reference: geometry/deform/lattice_tets.h, rasterize.h.
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

#ifdef __cplusplus
static_assert(sizeof(LabelStatsPush) == 32);
}  // namespace vox::shader
#endif

#endif
