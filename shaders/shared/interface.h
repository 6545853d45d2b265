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
// Stages: locate (rasterize_locate.comp: sample -> lowest containing tet, by
// atomicMin over per-tet scanline spans), resolve (rasterize_resolve.comp:
// tet -> source voxel -> label for one source window), reduce
// (rasterize_reduce.comp: last window, majority of k^3 samples, uint16 pack);
// interpolate_field.comp replaces resolve + reduce for fields.
// Bindings: every stage binds the sample states first; then locate binds the
// slab's tets and tasks, the other stages the per-tet maps, their output and
// (resolve, reduce) the source window.
#define VOX_RASTER_BINDING_STATE 0         // uint[]: per sample, slab lattice order
#define VOX_RASTER_LOCATE_BINDING_TETS 1   // RasterTet[]: the slab's tets, local index order
#define VOX_RASTER_LOCATE_BINDING_TASKS 2  // uint[2 * tasks]: local tet, (slab z) | (first row << 16)
#define VOX_RASTER_BINDING_MAPS 1          // RasterMap[] (rasterize) or FieldMap[] (field), local tet order
#define VOX_RASTER_BINDING_OUTPUT 2        // uint[]: two uint16 labels per word, or float[] field values
#define VOX_RASTER_BINDING_SOURCE 3        // 3..3+VOX_RASTER_SOURCE_PARTS-1: uint[] window parts, 2 labels per word
#define VOX_RASTER_SOURCE_PARTS 8
#define VOX_RASTER_SOURCE_PART_LABELS_LOG2 26  // labels per window part: 2^26 (128 MiB)
#define VOX_RASTER_NO_TET 0xFFFFFFFFu
#define VOX_RASTER_RESOLVED 0x80000000u        // | label
#define VOX_RASTER_LOCATE_GROUP_SIZE 64
#define VOX_RASTER_ROWS_PER_TASK 4
#define VOX_RASTER_GROUP_SIZE 64               // resolve, reduce, interpolate
#define VOX_RASTER_MAX_SAMPLES 4               // k <= 4: k^3 <= 64 samples per voxel

// Face k of a tet (opposite vertex k): inward plane value at lattice point q
//   n.x * (q.x - a.x) + ((n.y * (q.y - a.y) + n.z * (q.z - a.z)) + d)
// evaluated in this order without contraction (LatticeTet::planeValue).
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

struct RasterLocatePush {
  uint latticeNx;
  uint latticeNy;
  uint slabZ0;     // lattice slice of the slab's first sample slice
  uint taskBase;   // first task of this dispatch
  uint taskCount;  // tasks of this dispatch
  uint pad0;
  uint pad1;
  uint pad2;
};

struct RasterResolvePush {
  uint latticeNx;
  uint latticeNy;
  uint slabZ0;        // lattice slice of the slab's first sample slice
  uint samples;       // k
  uint outputNx;      // output voxels per row (latticeNx / k)
  uint outputNy;
  uint itemBase;      // first sample (resolve) or voxel pair (reduce) of this dispatch
  uint itemCount;     // samples (resolve) or voxel pairs (reduce) of this dispatch
  uint voxelCount;    // output voxels of the slab (reduce)
  uint sourceNx;
  uint sourceNy;
  uint sourceNz;
  uint windowFirst;   // source slices [windowFirst, windowEnd) are in the window
  uint windowEnd;
  uint pad0;
  uint pad1;
};

struct FieldInterpolatePush {
  uint latticeNx;
  uint latticeNy;
  uint slabZ0;
  uint itemBase;
  uint itemCount;
  float fill;
  uint pad0;
  uint pad1;
};

#ifdef __cplusplus
static_assert(sizeof(RasterFace) == 32);
static_assert(sizeof(RasterTet) == 160);
static_assert(sizeof(RasterMap) == 72);
static_assert(sizeof(FieldMap) == 32);
static_assert(sizeof(RasterLocatePush) == 32);
static_assert(sizeof(RasterResolvePush) == 64);
static_assert(sizeof(FieldInterpolatePush) == 32);
#endif

#ifdef __cplusplus
static_assert(sizeof(LabelStatsPush) == 32);
}  // namespace vox::shader
#endif

#endif
