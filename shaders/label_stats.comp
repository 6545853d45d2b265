#version 460
// Per-label voxel counts and bounding boxes (CPU reference:
// geometry/label_stats.cpp). Each invocation scans a run of consecutive voxels
// and issues one set of atomics per run of equal labels within a row. Labels
// are read eight at a time (one uvec4); a block equal to the current run and
// not crossing a row end is consumed whole, which is the common case in
// segmented volumes (long runs of air and of each organ).
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"

layout(local_size_x = VOX_LABEL_STATS_GROUP_SIZE) in;

layout(std430, binding = VOX_LABEL_STATS_BINDING_LABELS) readonly buffer Labels { uvec4 labelBlocks[]; };
layout(std430, binding = VOX_LABEL_STATS_BINDING_COUNTS) buffer Counts { uint counts[]; };
layout(std430, binding = VOX_LABEL_STATS_BINDING_BOXES) buffer Boxes { uint boxes[]; };
layout(push_constant) uniform Push { LabelStatsPush pc; };

void flushRun(uint label, uint n, uint x0, uint x1, uint y, uint z) {
  if (n == 0u || label >= pc.labelCount) return;
  atomicAdd(counts[label], n);
  const uint b = 6u * label;
  atomicMin(boxes[b + 0u], x0);
  atomicMin(boxes[b + 1u], y);
  atomicMin(boxes[b + 2u], z);
  atomicMax(boxes[b + 3u], x1);
  atomicMax(boxes[b + 4u], y);
  atomicMax(boxes[b + 5u], z);
}

uint runLabel;
uint runStart;
uint runLength;
uint x, y, z;

void stepVoxel(uint l) {
  if (l != runLabel) {
    flushRun(runLabel, runLength, runStart, x - 1u, y, z);
    runLabel = l;
    runStart = x;
    runLength = 0u;
  }
  ++runLength;
  ++x;
  if (x == pc.nx) {  // a run never crosses a row
    flushRun(runLabel, runLength, runStart, x - 1u, y, z);
    runLength = 0u;
    runStart = 0u;
    x = 0u;
    if (++y == pc.ny) {
      y = 0u;
      ++z;
    }
  }
}

uint labelOf(uvec4 block, uint s) {
  const uint word = block[s >> 1];
  return (s & 1u) == 0u ? (word & 0xFFFFu) : (word >> 16);
}

void main() {
  const uint first = gl_GlobalInvocationID.x * VOX_LABEL_STATS_VOXELS_PER_THREAD;
  if (first >= pc.voxelCount) return;
  const uint last = min(first + VOX_LABEL_STATS_VOXELS_PER_THREAD, pc.voxelCount);

  const uint t = pc.startX + first;
  x = t % pc.nx;
  const uint rows = pc.startY + t / pc.nx;
  y = rows % pc.ny;
  z = pc.startZ + rows / pc.ny;

  runLabel = labelOf(labelBlocks[first >> 3], 0u);
  runStart = x;
  runLength = 0u;
  for (uint v = first; v < last; v += 8u) {
    const uvec4 block = labelBlocks[v >> 3];
    const uint n = min(8u, last - v);
    if (n == 8u && x + 8u < pc.nx && all(equal(block, uvec4(runLabel | (runLabel << 16))))) {
      runLength += 8u;
      x += 8u;
      continue;
    }
    for (uint s = 0u; s < n; ++s) stepVoxel(labelOf(block, s));
  }
  flushRun(runLabel, runLength, runStart, x - 1u, y, z);
}
