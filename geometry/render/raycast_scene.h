#pragma once
// What the transfer-mesh-guided ray caster (thesis chapter 5) works on, shared
// by the CPU reference (raycast_reference.h) and the GPU kernel
// (gpu/kernels/raycast.h).
//
// Render frame: the index space of the deformed grid G' that the rasterizer
// fills (deformedGridGeometry in geometry/raster/rasterize.h),
// shifted by an integer so that its origin lies near the mesh: the centre of
// the render cell c (integer vector) is the centre of output voxel
// c + cellShift. Cells are unit cubes, so the 3D DDA of thesis Algorithm 2 is
// exact and cell centres are integers (exact in float on the GPU). Rest
// positions ("texture coordinates") live in the source index space shifted by
// sourceShift, so a mapped point s falls in source voxel round(s) + sourceShift.

#include "geometry/label_grid.h"
#include "geometry/render/boundary_bvh.h"
#include "geometry/render/camera.h"
#include "geometry/render/cutting_planes.h"
#include "geometry/rgb_image.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vox {

// Per-tet data that never changes: built once from the rest transfer mesh.
struct RaycastMesh {
  GridGeometry source;                                  // the grid the TM embeds
  Index3 sourceShift{0, 0, 0};                          // source voxel of rest coordinate 0
  std::size_t vertexCount = 0;                          // #V
  std::vector<Tet> tets;                                // #T, vertex indices
  std::vector<std::array<std::int32_t, 4>> neighbors;   // #T; [t][k] shares the face opposite vertex k, -1 = boundary
  // #T rest frames: rest coordinate of vertex 0 and the edges to vertices 1..3
  // (shifted source index space), for s = r0 + sum_k lambda_k (r_k - r0).
  std::vector<std::array<Eigen::Vector3d, 4>> restFrames;
  std::vector<BoundaryFace> boundary;                   // #B, in BVH leaf order
  std::vector<BvhNode> restBvh;                         // tree over `boundary` (rest boxes)
};

// Validates the mesh (InputError(source, ...) for bad indices, non-finite
// coordinates, degenerate rest tets, faces shared by more than two tets, or
// no boundary) and precomputes neighbours, rest frames and the boundary BVH.
// `name` names the mesh in error messages.
RaycastMesh buildRaycastMesh(const TetMesh& restMesh, const GridGeometry& source, const std::string& name = "transfer mesh");

// Per-frame geometry: the deformed positions in the render frame.
struct RaycastFrame {
  GridGeometry output;                    // the deformed grid G' (deformedGridGeometry)
  Index3 cellShift{0, 0, 0};              // output voxel of render cell 0
  Eigen::Vector3d renderOrigin{0, 0, 0};  // grid-frame position of render cell 0's centre
  std::vector<Eigen::Vector3d> positions; // #V, render frame
  std::vector<BvhNode> bvh;               // boundary BVH refitted to `positions` (CPU reference; the GPU refits its own)
  Eigen::Vector3d cellsLo{0, 0, 0};       // box covered by G''s cells, render frame
  Eigen::Vector3d cellsHi{0, 0, 0};

  Eigen::Vector3d toRender(const Eigen::Vector3d& gridFramePoint) const;
  Eigen::Vector3d toGrid(const Eigen::Vector3d& renderPoint) const;
};

// `deformedPositions`: #V, grid frame (mm). Throws InputError("deformed
// positions", ...) for a wrong count or non-finite coordinates.
RaycastFrame prepareRaycastFrame(const RaycastMesh& mesh, const std::vector<Eigen::Vector3d>& deformedPositions);
// The same frame without `positions` and `bvh` (left empty), for the GPU
// kernel that converts the deformed positions and refits the BVH itself
// (gpu::RaycastKernel::renderTo with deformed positions); same errors.
RaycastFrame placeRaycastFrame(const RaycastMesh& mesh, const std::vector<Eigen::Vector3d>& deformedPositions);

// Eq. 5.1-5.2 precomputed per deformed tet, relative to vertex 0 (the anchor):
// lambda_k(p) = planes[k].xyz . (p - anchor) + planes[k].w for k = 1..3 and
// lambda_0 = 1 - lambda_1 - lambda_2 - lambda_3, with planes[k].xyz =
// delta_k n_k (n_k the normal of the face opposite v_k, which contains v_0).
// A degenerate tet gets zero normals and w = -1: it contains no point.
struct TetFactors {
  std::array<Eigen::Vector4d, 3> planes;  // k = 1..3
  Eigen::Vector3d anchor;
};
std::vector<TetFactors> computeTetFactors(const RaycastMesh& mesh, const RaycastFrame& frame);
TetFactors tetFactors(const Eigen::Vector3d& v0, const Eigen::Vector3d& v1, const Eigen::Vector3d& v2, const Eigen::Vector3d& v3);

// Camera, cutting planes and light expressed in the render frame.
struct RaycastView {
  CameraRays camera;                      // grid frame
  Eigen::Vector3d eye{0, 0, 0};           // render frame
  Eigen::Vector3d forward{0, 0, 0};       // render-frame images of the camera basis:
  Eigen::Vector3d right{0, 0, 0};         // the ray of pixel (x, y) is
  Eigen::Vector3d up{0, 0, 0};            //   eye + t (forward + sx right + sy up)
  std::vector<Eigen::Vector4d> cuts;      // render frame: cell c is removed iff xyz . c > w
  Eigen::Vector3d light{0, 0, 1};         // unit vector towards the fill light, grid-frame axes
  Eigen::Vector3d headlight{0, -1, 0};    // unit vector towards the camera, grid-frame axes
  double depthNear = 0.0, depthFar = 0.0;  // the camera's depth-cue range (Camera::depthNear/Far)

  Eigen::Vector3d direction(int x, int y) const { return forward + camera.sx(x) * right + camera.sy(y) * up; }
};
RaycastView makeRaycastView(const RaycastFrame& frame, const Camera& camera, const CuttingPlanes& cuts);

// The normal a visible voxel is lit with (geometry/render/surface_normals.h
// gives the equations, shaders/shared/shading.glsl the lighting).
//  Smooth: the surface of the visible labels: minus the gradient of the
//    smoothed occupancy of the rest grid (1 where a voxel's label is visible,
//    0 elsewhere), at the point where the ray enters the visible cell,
//    carried to the posed frame by the containing tet's linear map; cut
//    faces flat; turned towards the camera.
//  Faces: the crossed voxel face's own normal, voxel faces visible.
enum class SurfaceNormals { Smooth, Faces };
inline constexpr double kFlatOccupancyGradient = 1e-3;  // per source voxel

// How a visible voxel is shaded: its normal (`normals`) under a headlight
// and a fill light plus ambient (shaders/shared/shading.glsl), times the
// label colour and a depth cue; misses get the background.
struct RaycastShading {
  Rgb background{22, 24, 29};
  double ambient = 0.35;
  SurfaceNormals normals = SurfaceNormals::Smooth;
};

// "smooth" or "faces"; anything else is an InputError naming `what`.
SurfaceNormals parseSurfaceNormals(const std::string& text, const std::string& what = "shading");
const char* surfaceNormalsName(SurfaceNormals normals);

// Bounds that keep every ray finite on any mesh (thesis: "a given number of
// iterations").
struct RaycastLimits {
  int maxWalkSteps = 512;  // tets visited per point location
  int maxEntries = 64;     // boundary faces through which one ray (re-)enters the mesh
};

// Barycentric tolerance of the point-in-tet test (closed tets): a point on a
// shared face is inside both tets.
inline constexpr double kInsideTolerance = 1e-5;
// A deformed tet whose |det(v1-v0, v2-v0, v3-v0)| is below this fraction of
// the product of its edge lengths from v0 is degenerate (float noise on the GPU).
inline constexpr double kDegenerateTetRatio = 1e-7;
// Cap of the margin before an entry point, in half cell diagonals
// (raycast_reference.h, step 3).
inline constexpr double kMaxEntryMarginCells = 16.0;

}  // namespace vox
