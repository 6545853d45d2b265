#pragma once
// CPU reference of the transfer-mesh-guided ray caster (thesis chapter 5):
// the same algorithm as shaders/raycast.comp, in double precision. Tests
// compare the GPU kernel with it.
//
// Per pixel:
//  1. Clip the ray to the cells of G' and to the kept side of the cutting
//     planes (conservatively: half a cell of slack).
//  2. Find the first front-facing boundary face of the deformed TM it hits
//     (boundary BVH here; the GPU kernel rasterizes the faces into an entry
//     buffer); no hit means background.
//  3. Walk G''s cells with the 3D DDA (Algorithm 2), starting before the
//     entry point: a voxel whose centre is inside the TM may be crossed
//     before the ray reaches the TM surface, by up to half a cell diagonal
//     from the entry face's plane (a longer stretch of ray when it meets the
//     face at a grazing angle; capped at 16 half diagonals). For each cell
//     whose centre is kept by the cutting planes, locate the centre by
//     walking from the current tet through face neighbours, across the face
//     with the most negative barycentric coordinate (eq. 5.1-5.2) among those
//     with a neighbour; map it to the source grid by barycentric
//     interpolation of the rest coordinates, and fetch the label. The first
//     visible label is shaded with the normal RaycastShading::normals picks
//     (geometry/render/surface_normals.h): the smoothed occupancy's, or the
//     crossed cell face's.
//  4. When a centre cannot be located, the walk left the mesh. If the ray's
//     own point in that cell (the middle of its stretch in the cell) is inside
//     the mesh, the centre is outside (the ray grazes the surface) or across a
//     concavity from where the walk went: the walk follows the ray to that
//     point, then tries the centre again from there. Otherwise the ray is
//     outside (e.g. it passed between two limbs): past the current entry
//     point, the walk restarts from the next boundary face through which the
//     ray re-enters the mesh once the ray has (almost) reached it. Once the ray
//     has been outside for two cells past its latest entry it jumps to the
//     next entry, or stops when there is none.
// Limitation: the renderer can miss a voxel of G' (show what lies behind it,
// or nothing), never invent one. It misses a voxel whose centre is inside the
// TM when the ray crosses it only outside the TM, beyond the margins above
// (rays grazing the TM surface: silhouettes, and surfaces nearly parallel to
// the ray in index space such as the tops of 8 mm slices seen from the side),
// or when the walk cannot reach its centre from the ray through face
// neighbours (tets touching only along an edge). Measured: at most 0.05% of
// the pixels of 320x240 views of the AM phantom, 0.09% of 160x120 views of a
// synthetic figure; tests/geometry/render_raycast_test.cpp checks the stated
// bound, 0.2% of the pixels, and that each difference is a missed voxel.
// A camera inside the TM sees only what lies beyond the ray's next entry.

#include "geometry/label_grid.h"
#include "geometry/render/palette.h"
#include "geometry/render/raycast_scene.h"
#include "geometry/rgb_image.h"

#include <cstdint>

namespace vox {

struct RaycastStats {
  std::uint64_t rays = 0;
  std::uint64_t hits = 0;          // rays that found a visible voxel
  std::uint64_t cells = 0;         // DDA cells visited
  std::uint64_t walkSteps = 0;     // tets visited by point location
  std::uint64_t entryQueries = 0;  // boundary BVH queries
  std::uint64_t failedWalks = 0;   // locations that left the mesh or ran out of steps
};

// What one ray found.
struct RayResult {
  bool hit = false;
  Index3 cell{0, 0, 0};     // render-frame cell of the visible voxel
  Label label = 0;
  int axis = 0;             // axis of the crossed cell face
  int step = 0;             // +-1: the ray's direction along that axis
  double t = 0.0;           // ray parameter of the cell's entry: depth along the view axis, mm
  Eigen::Vector3d point{0, 0, 0};  // render frame: where the ray enters the cell (ray parameter t)
  std::int32_t tet = -1;    // tet containing the cell centre
};

RayResult traceRayReference(const LabelGrid& source, const RaycastMesh& mesh, const RaycastFrame& frame,
                            const std::vector<TetFactors>& factors, const RaycastView& view, const Palette& palette,
                            const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, const RaycastLimits& limits,
                            RaycastStats* stats = nullptr);

// Shades a ray result lit with `normal` (unit, grid-frame axes, facing the
// camera; surfaceNormal in surface_normals.h): label colour times
// surfaceShade (shaders/shared/shading.glsl).
Rgb shadeRay(const RayResult& r, const Eigen::Vector3d& normal, const RaycastView& view, const Palette& palette,
             const RaycastShading& shading);

// Per label (indexed by label), the pixels of every stride-th row and column
// whose ray shows it: what a legend lists as visible.
std::vector<std::uint64_t> visibleLabelPixels(const LabelGrid& source, const RaycastMesh& mesh, const RaycastFrame& frame,
                                              const RaycastView& view, const Palette& palette, int stride);

// The whole image (rows in parallel on the available cores).
RgbImage raycastReference(const LabelGrid& source, const RaycastMesh& mesh, const RaycastFrame& frame, const RaycastView& view,
                          const Palette& palette, const RaycastShading& shading = {}, const RaycastLimits& limits = {},
                          RaycastStats* stats = nullptr);

}  // namespace vox
