#include "geometry/world_frame.h"

#include <Eigen/LU>

#include <cmath>
#include <utility>

namespace vox {

namespace {

template <class Mesh>
void mapPositions(Mesh& mesh, const Eigen::Matrix3d& m) {
  for (Eigen::Vector3d& p : mesh.positions) p = m * p;
}

bool mirrors(const GridGeometry& g) { return g.direction.determinant() < 0.0; }

}  // namespace

void tetMeshGridToWorld(TetMesh& mesh, const GridGeometry& g) {
  mapPositions(mesh, g.direction);
  if (mirrors(g))
    for (Tet& t : mesh.tets) std::swap(t[2], t[3]);
}

void tetMeshWorldToGrid(TetMesh& mesh, const GridGeometry& g) {
  mapPositions(mesh, g.direction.transpose());
  if (mirrors(g))
    for (Tet& t : mesh.tets) std::swap(t[2], t[3]);
}

void surfaceGridToWorld(TriMesh& mesh, const GridGeometry& g) {
  mapPositions(mesh, g.direction);
  if (mirrors(g))
    for (Tri& f : mesh.triangles) std::swap(f[1], f[2]);
}

void surfaceWorldToGrid(TriMesh& mesh, const GridGeometry& g) {
  mapPositions(mesh, g.direction.transpose());
  if (mirrors(g))
    for (Tri& f : mesh.triangles) std::swap(f[1], f[2]);
}

bool axisAligned(const GridGeometry& g) {
  for (int c = 0; c < 3; ++c) {
    int large = 0;
    for (int r = 0; r < 3; ++r) large += std::abs(g.direction(r, c)) > 1.0 - 1e-6;
    if (large != 1) return false;
  }
  return true;
}

std::string orientationCode(const GridGeometry& g) {
  static const char kPositive[] = "RAS", kNegative[] = "LPI";
  std::string code;
  for (int c = 0; c < 3; ++c) {
    int axis = 0;
    for (int r = 1; r < 3; ++r)
      if (std::abs(g.direction(r, c)) > std::abs(g.direction(axis, c))) axis = r;
    code += g.direction(axis, c) >= 0.0 ? kPositive[axis] : kNegative[axis];
  }
  return code;
}

}  // namespace vox
