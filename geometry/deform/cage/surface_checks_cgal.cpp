// CGAL Polygon_mesh_processing for the surface checks: self-intersections
// need exact predicates.
#include "geometry/deform/cage/surface_checks.h"

#include "geometry/error.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <iterator>
#include <vector>

namespace vox {

std::size_t countSelfIntersections(const TriMesh& surface) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
  Mesh mesh;
  std::vector<Mesh::Vertex_index> vertices;
  vertices.reserve(surface.vertexCount());
  for (const Eigen::Vector3d& p : surface.positions) vertices.push_back(mesh.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z())));
  for (const Tri& t : surface.triangles)
    if (mesh.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]) == Mesh::null_face())
      throw RuntimeFailure("self-intersection test: the surface is not a 2-manifold");
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(pairs));
  return pairs.size();
}

}  // namespace vox
