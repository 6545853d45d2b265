#pragma once
// The normals a visible voxel is lit with (RaycastShading::normals,
// raycast_scene.h): the CPU reference of surfaceNormal in shaders/raycast.comp.
//
// Smooth normals are minus the gradient of the smoothed occupancy of the rest
// grid. Occupancy O(v) is 1 where voxel v's label is visible in the palette,
// 0 where it is hidden or v lies outside the grid: hiding organs moves the
// surface to what remains visible. S(s) interpolates O trilinearly between
// voxel centres (continuous in the rest coordinate s), and the gradient is
// the 3D Sobel operator on S sampled at s + (i h_x, j h_y, k h_z),
// i, j, k in {-1, 0, 1}:
//   g_x(s) = sum_{i,j,k} i w_j w_k S(s + (i h_x, j h_y, k h_z)) / (32 h_x),
// w_0 = 2, w_{+-1} = 1 (likewise g_y, g_z): central differences averaged
// across the other two axes. The steps are the same length in mm along every
// axis, kOccupancyDifferenceStep of the widest spacing: on a grid of 8 mm
// slices and 2 mm pixels, a skin that steps back a few pixels per slice
// leans by its mean slope instead of alternating between facing the camera
// and facing up or down (the thin dark lines of face shading), and with taps
// a slice apart the normal turns across a whole slice rather than in a band
// at each step. 26 samples of 8 voxels each, read from the label grid on
// the fly: no normal volume, no memory beyond the labels the ray caster holds.
//
// The rest coordinate of the render-frame point p in tet T is
// s(p) = r0 + R lambda(p), R = [r1 - r0, r2 - r0, r3 - r0] (RaycastMesh::
// restFrames) and lambda(p) = L (p - anchor) + w (TetFactors: the rows of L
// are planes[k].xyz). A gradient is a covector, so it goes back through the
// transpose of the Jacobian ds/dp = R L: grad_p = L^T R^T grad_s, the
// inverse transpose of the tet's rest-to-posed map applied to grad_s, which
// keeps the normal perpendicular to the posed surface. The render frame is
// the output grid's index space, so grad_x = grad_p ./ spacing in the grid
// frame, where the lights are.
//
// Cutting planes remove render cells by their centres (cutting_planes.h), so
// a cut face is a staircase of cells whose occupancy says nothing of the
// cut: a visible cell that the ray enters from a cell a plane removed is lit
// with that plane's normal, and the cut face shades flat.

#include "geometry/label_grid.h"
#include "geometry/render/palette.h"
#include "geometry/render/raycast_reference.h"
#include "geometry/render/raycast_scene.h"

#include <Eigen/Core>

#include <vector>

namespace vox {

// Length of the Sobel steps h, in widest voxel spacings (the same mm along
// every axis): one slice across the slices. Measured in docs/BENCHMARKS.md
// ("Smooth shading"): shorter steps shade each slice's step as a band,
// longer ones blur shells a few mm thick over hidden organs.
inline constexpr double kOccupancyDifferenceStep = 1.0;

// The Sobel steps h along each axis, in voxels of `source`.
Eigen::Vector3d occupancyDifferenceSteps(const GridGeometry& source);

// g(s) above: the gradient of the smoothed occupancy at rest coordinate `s`
// (source index space shifted by `sourceShift`, RaycastMesh), per voxel.
Eigen::Vector3d occupancyGradient(const LabelGrid& source, const Index3& sourceShift, const Palette& palette, const Eigen::Vector3d& s);

// Unit normal, grid-frame axes, of the surface the hit `r` shows, facing the
// camera. Faces: the crossed face's normal (-step along `axis`). Smooth: the
// normal of the cutting plane that removed the cell the ray came from, if
// one did; else -grad_x of the smoothed occupancy at r.point mapped through
// r.tet, turned towards the camera; the face normal where the occupancy is
// flat (|g| < kFlatOccupancyGradient).
Eigen::Vector3d surfaceNormal(const RayResult& r, const LabelGrid& source, const RaycastMesh& mesh, const RaycastFrame& frame,
                              const std::vector<TetFactors>& factors, const RaycastView& view, const Palette& palette,
                              SurfaceNormals normals);

}  // namespace vox
