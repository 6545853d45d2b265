// CGAL Surface_mesh_simplification for the cage: QEM edge collapse that
// refuses collapses creating self-intersections.
#include "geometry/deform/cage/cage_builder.h"

// GCC 12 reports the Eigen 4x4 quadrics that CGAL's Garland-Heckbert
// policies copy around as maybe uninitialized (they are set before use).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "geometry/error.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Edge_collapse_visitor_base.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Bounded_normal_change_filter.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <cmath>
#include <unordered_map>
#include <vector>

namespace vox {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using VertexIndex = Mesh::Vertex_index;
using FaceIndex = Mesh::Face_index;
namespace SMS = CGAL::Surface_mesh_simplification;

// Stops once the vertex count reaches the target. Collapses keep the Euler
// characteristic chi, and on a closed triangle mesh F = 2E/3, so
// V = E - F + chi = E/3 + chi.
struct VertexCountStop {
  std::int64_t eulerCharacteristic;
  std::int64_t target;
  template <typename Profile>
  bool operator()(const double&, const Profile&, std::size_t, std::size_t currentEdges) const {
    return std::int64_t(currentEdges) / 3 + eulerCharacteristic <= target;
  }
};

// Faces bucketed in a uniform grid of cubes. A face is registered in every
// cube its bounding box overlaps; when a collapse moves a vertex, its faces
// are registered again, so a query sees every face whose current box
// overlaps the queried box (plus stale entries, filtered by the true box).
class FaceGrid {
public:
  FaceGrid(const Mesh& mesh, double cellSize) : mesh_(mesh), cell_(cellSize), stamp_(mesh.number_of_faces(), 0) {
    for (const FaceIndex f : mesh.faces()) add(f);
  }

  CGAL::Bbox_3 box(FaceIndex f) const {
    CGAL::Bbox_3 b;
    for (const VertexIndex v : CGAL::vertices_around_face(mesh_.halfedge(f), mesh_)) b += mesh_.point(v).bbox();
    return b;
  }

  void add(FaceIndex f) {
    forCells(box(f), [&](std::uint64_t key) { cells_[key].push_back(f); });
  }

  // Calls visit(f) once for each live face that may overlap `b`.
  template <typename Visit>
  void query(const CGAL::Bbox_3& b, Visit&& visit) {
    ++query_;
    forCells(b, [&](std::uint64_t key) {
      const auto it = cells_.find(key);
      if (it == cells_.end()) return;
      for (const FaceIndex f : it->second) {
        if (stamp_[f] == query_ || mesh_.is_removed(f)) continue;
        stamp_[f] = query_;
        if (CGAL::do_overlap(b, box(f))) visit(f);
      }
    });
  }

private:
  template <typename Fn>
  void forCells(const CGAL::Bbox_3& b, Fn&& fn) const {
    const auto lo = [&](double x) { return std::int64_t(std::floor(x / cell_)); };
    for (std::int64_t k = lo(b.zmin()); k <= lo(b.zmax()); ++k)
      for (std::int64_t j = lo(b.ymin()); j <= lo(b.ymax()); ++j)
        for (std::int64_t i = lo(b.xmin()); i <= lo(b.xmax()); ++i)
          fn((std::uint64_t(i & 0x1FFFFF) << 42) | (std::uint64_t(j & 0x1FFFFF) << 21) | std::uint64_t(k & 0x1FFFFF));
  }

  const Mesh& mesh_;
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<FaceIndex>> cells_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t query_ = 0;
};

// Do triangle (a, b, c) and face f intersect other than at the vertices
// they share? Faces sharing one vertex intersect when an edge opposite the
// shared vertex crosses the other face (as in PMP::self_intersections).
bool intersectsFace(const Mesh& mesh, const std::array<VertexIndex, 3>& tv, const std::array<Point, 3>& tp, FaceIndex f) {
  std::array<VertexIndex, 3> fv;
  int n = 0;
  for (const VertexIndex v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) fv[n++] = v;
  int shared = 0, ti = -1, fi = -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (tv[i] == fv[j]) ++shared, ti = i, fi = j;
  const Kernel::Triangle_3 t(tp[0], tp[1], tp[2]);
  const Kernel::Triangle_3 g(mesh.point(fv[0]), mesh.point(fv[1]), mesh.point(fv[2]));
  if (shared == 0) return CGAL::do_intersect(t, g);
  if (shared == 1)
    return CGAL::do_intersect(Kernel::Segment_3(tp[(ti + 1) % 3], tp[(ti + 2) % 3]), g) ||
           CGAL::do_intersect(Kernel::Segment_3(mesh.point(fv[(fi + 1) % 3]), mesh.point(fv[(fi + 2) % 3])), t);
  return false;  // a shared edge: folds are the normal-change filter's business
}

// Rejects collapses whose new triangles would cross a face outside the star
// of the collapsed edge; otherwise defers to Bounded_normal_change_filter.
struct NoSelfIntersectionFilter {
  FaceGrid* grid;
  SMS::Bounded_normal_change_filter<> normals;

  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(const Profile& profile, boost::optional<typename Profile::Point> op) const {
    op = normals(profile, op);
    if (!op) return op;
    const Mesh& mesh = profile.surface_mesh();
    const VertexIndex v0 = profile.v0(), v1 = profile.v1();
    // profile.triangles(): the faces incident to the edge first, then the
    // rest of the star with the collapsing vertex in second position.
    std::vector<std::pair<std::array<VertexIndex, 3>, std::array<Point, 3>>> created;
    CGAL::Bbox_3 box = op->bbox();
    auto it = profile.triangles().begin();
    if (profile.left_face_exists()) ++it;
    if (profile.right_face_exists()) ++it;
    for (; it != profile.triangles().end(); ++it) {
      created.push_back({{it->v0, VertexIndex(), it->v2}, {mesh.point(it->v0), *op, mesh.point(it->v2)}});
      box += mesh.point(it->v0).bbox() + mesh.point(it->v2).bbox();
    }
    bool crossing = false;
    grid->query(box, [&](FaceIndex f) {
      if (crossing) return;
      for (const VertexIndex v : CGAL::vertices_around_face(mesh.halfedge(f), mesh))
        if (v == v0 || v == v1) return;  // in the star: replaced by the collapse
      for (const auto& [vertices, points] : created)
        if (intersectsFace(mesh, vertices, points, f)) {
          crossing = true;
          return;
        }
    });
    if (crossing) return boost::none;
    return op;
  }
};

// Registers the faces around each vertex a collapse has moved.
struct RegisterMovedFaces : SMS::Edge_collapse_visitor_base<Mesh> {
  FaceGrid* grid;
  const Mesh* mesh;
  template <typename Profile>
  void OnCollapsed(const Profile&, const VertexIndex& v) {
    for (const FaceIndex f : CGAL::faces_around_target(mesh->halfedge(v), *mesh))
      if (f != Mesh::null_face()) grid->add(f);
  }
};

}  // namespace

TriMesh simplifyQem(const TriMesh& surface, int targetVertices) {
  Mesh mesh;
  std::vector<VertexIndex> vertices;
  vertices.reserve(surface.vertexCount());
  for (const Eigen::Vector3d& p : surface.positions) vertices.push_back(mesh.add_vertex(Point(p.x(), p.y(), p.z())));
  for (const Tri& t : surface.triangles)
    if (mesh.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]) == Mesh::null_face())
      throw RuntimeFailure("QEM simplification: the surface is not a 2-manifold");
  const std::int64_t chi = std::int64_t(mesh.number_of_vertices()) - std::int64_t(mesh.number_of_edges()) +
                           std::int64_t(mesh.number_of_faces());

  // Cubes a few input edges wide: small enough to prune early queries,
  // while late (long-edged) faces span a few hundred of them at most.
  double edgeLength = 0.0;
  for (const auto e : mesh.edges())
    edgeLength += std::sqrt(CGAL::squared_distance(mesh.point(mesh.vertex(e, 0)), mesh.point(mesh.vertex(e, 1))));
  edgeLength /= double(std::max<std::size_t>(1, mesh.number_of_edges()));
  FaceGrid grid(mesh, std::max(4.0 * edgeLength, 1e-9));

  SMS::GarlandHeckbert_plane_policies<Mesh, Kernel> policies(mesh);
  const NoSelfIntersectionFilter filter{&grid, {}};
  RegisterMovedFaces visitor;
  visitor.grid = &grid;
  visitor.mesh = &mesh;
  SMS::edge_collapse(mesh, VertexCountStop{chi, targetVertices},
                     CGAL::parameters::get_cost(policies.get_cost())
                         .get_placement(policies.get_placement())
                         .filter(filter)
                         .visitor(visitor));

  TriMesh out;
  std::vector<std::int32_t> index(mesh.number_of_vertices() + mesh.number_of_removed_vertices(), -1);
  for (const VertexIndex v : mesh.vertices()) {
    index[v] = std::int32_t(out.positions.size());
    const Point& p = mesh.point(v);
    out.positions.emplace_back(p.x(), p.y(), p.z());
  }
  for (const FaceIndex f : mesh.faces()) {
    Tri t;
    int k = 0;
    for (const VertexIndex v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) t[k++] = index[v];
    out.triangles.push_back(t);
  }
  return out;
}

}  // namespace vox
