#pragma once
// Checks on triangle surfaces used as cages and envelopes: closed
// 2-manifold, consistent and outward orientation, self-intersections; and
// inside tests of points and voxel centres against a closed surface.

#include "geometry/label_grid.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace vox {

struct SurfaceCheck {
  std::size_t vertices = 0, edges = 0, faces = 0;
  std::size_t boundaryEdges = 0;        // edges with one incident face (holes)
  std::size_t nonManifoldEdges = 0;     // edges with more than two incident faces
  std::size_t nonManifoldVertices = 0;  // vertices whose faces form more than one fan
  std::size_t misorientedEdges = 0;     // edges both of whose faces run them the same way
  std::size_t isolatedVertices = 0;     // vertices used by no face
  std::size_t degenerateFaces = 0;      // faces of zero area
  std::size_t components = 0;           // edge-connected components of faces
  int genus = 0;                        // sum over components, for closed manifolds
  double volume = 0.0;                  // signed enclosed volume (mm^3), > 0 for outward normals
  std::size_t selfIntersections = 0;    // intersecting face pairs (checkSurface only)

  bool closedManifold() const {
    return boundaryEdges == 0 && nonManifoldEdges == 0 && nonManifoldVertices == 0 && misorientedEdges == 0;
  }
  // Usable as a cage: a closed, outward-oriented 2-manifold without self-intersections.
  bool validCage() const {
    return closedManifold() && isolatedVertices == 0 && degenerateFaces == 0 && selfIntersections == 0 && volume > 0.0;
  }
};

// Combinatorial and orientation checks (everything but selfIntersections).
SurfaceCheck checkSurfaceTopology(const TriMesh& surface);

// Pairs of faces that intersect other than along a shared edge or vertex
// (CGAL Polygon_mesh_processing, exact predicates). The surface must be a
// 2-manifold (checkSurfaceTopology); throws RuntimeFailure otherwise.
std::size_t countSelfIntersections(const TriMesh& surface);

// checkSurfaceTopology, plus self-intersections when the surface is a
// 2-manifold (a non-manifold surface is rejected before that).
SurfaceCheck checkSurface(const TriMesh& surface);

// Validates a cage read from `source` (an OBJ/OFF file): throws
// InputError(source, ...) naming the first fault: bad indices or
// coordinates, open boundary, non-manifold edge or vertex, inconsistent or
// inverted orientation, unused vertices, degenerate faces, self-intersections.
void validateCage(const TriMesh& cage, const std::string& source);

// Reads a cage from an OBJ, OFF or PLY file and validates it (validateCage):
// a file that cannot be used as a cage is an InputError naming it.
TriMesh readCage(const std::string& path);

// Inside test against a closed oriented surface: the winding number along
// the +x ray, counted on the faces' projections onto the yz plane with
// simulation of simplicity, so a ray through an edge or vertex is counted
// once. A point is inside when its winding number is not zero.
class SurfaceInsideTest {
public:
  explicit SurfaceInsideTest(const TriMesh& surface);

  bool contains(const Eigen::Vector3d& p) const;
  // One byte per voxel of `geometry` (x fastest): 1 where the centre is inside.
  std::vector<std::uint8_t> voxelMask(const GridGeometry& geometry) const;

private:
  struct Crossing {
    double x;
    int winding;  // +1 entering (face normal towards -x), -1 leaving
  };
  // Crossings of the line {(t, y, z)} with the surface, unsorted.
  void crossings(double y, double z, std::vector<Crossing>& out) const;

  TriMesh surface_;
  Eigen::Vector2d lo_, cellSize_;  // bucket grid over the yz bounding box
  int cells_[2] = {0, 0};
  std::vector<std::vector<std::int32_t>> buckets_;  // faces overlapping each cell
};

// Foreground voxels (label != 0) whose centres lie outside the closed
// surface: the outliers the propagation solve places (thesis 4.2.2).
std::int64_t countForegroundOutside(const TriMesh& surface, const LabelGrid& grid);

}  // namespace vox
