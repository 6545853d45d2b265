#pragma once
// The one physical frame of everything voxmorph writes or reads besides
// grids (meshes, cages, poses, cutting planes, cameras): the image's world
// coordinates in mm, RAS+ (+x towards the subject's Right, +y Anterior, +z
// Superior), as nibabel computes them from a NIfTI's sform or qform. ITK and Slicer's files store
// LPS (x and y negated); the readers convert (MetaImage, NRRD), so a mesh
// written from any grid lies over that grid in nibabel, ITK, ParaView and
// Slicer (which shows RAS).
//
// The pipeline works in the grid frame (GridGeometry: origin + spacing .*
// ijk, axes along the grid's), which is the world frame rotated by the
// grid's `direction`:  world = direction * grid.  Conversions happen at the
// boundaries, where files are read and written.

#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <string>

namespace vox {

inline Eigen::Vector3d gridToWorld(const GridGeometry& g, const Eigen::Vector3d& p) { return g.direction * p; }
inline Eigen::Vector3d worldToGrid(const GridGeometry& g, const Eigen::Vector3d& p) { return g.direction.transpose() * p; }

// Positions mapped between the frames; where the map mirrors (det < 0, an
// image stored with one axis flipped) two vertices of every tet or triangle
// are swapped so that tets stay positively oriented and faces outward.
void tetMeshGridToWorld(TetMesh& mesh, const GridGeometry& g);
void tetMeshWorldToGrid(TetMesh& mesh, const GridGeometry& g);
void surfaceGridToWorld(TriMesh& mesh, const GridGeometry& g);
void surfaceWorldToGrid(TriMesh& mesh, const GridGeometry& g);

// True when the grid's axes run along the world axes (direction is a signed
// permutation): world-frame boxes are then grid-frame boxes.
bool axisAligned(const GridGeometry& g);

// "RAS" for the world axes the grid's i, j, k axes point to most closely,
// as nibabel.aff2axcodes names them (e.g. "LPS", "RAS", "LIP").
std::string orientationCode(const GridGeometry& g);

}  // namespace vox
