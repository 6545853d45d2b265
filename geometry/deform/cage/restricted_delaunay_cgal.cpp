// The only translation unit that instantiates CGAL Mesh_3: one domain type
// (Labeled_mesh_domain_3 over a type-erased label function) serves both the
// surface meshes (envelope, cage) and the volume mesh (transfer mesh).
#include "geometry/deform/cage/restricted_delaunay.h"

#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/progress.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_3/Slivers_exuder.h>
#include <CGAL/Mesh_3/min_dihedral_angle.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/refine_mesh_3.h>

#include <algorithm>
#include <array>
#include <functional>
#include <numeric>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace vox {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Domain = CGAL::Labeled_mesh_domain_3<Kernel>;
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;
using Point = Kernel::Point_3;
using VertexHandle = Triangulation::Vertex_handle;

// Surface points are located by bisection to this fraction of the domain's
// bounding-box diagonal (a few micrometres on a whole body).
constexpr double kRelativeErrorBound = 1e-6;

Eigen::Vector3d toEigen(const Point& p) { return {p.x(), p.y(), p.z()}; }

Domain makeDomain(const SampledDomain& sampled, bool foregroundOnly) {
  // Mesh_3 falls back on CGAL's default generator (seeded from the clock)
  // in some initialization paths: reseed it so every run is the same.
  CGAL::get_default_random() = CGAL::Random(0);
  if (!sampled.labels || !sampled.labelAt) throw RuntimeFailure("restricted Delaunay meshing: domain without labels");
  const GridGeometry& g = sampled.labels->geometry();
  const Eigen::Vector3d lo = g.boxMin(), hi = g.boxMax();
  const CGAL::Bbox_3 box(lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z());
  std::function<int(const Point&)> label;
  if (foregroundOnly)
    label = [f = sampled.labelAt](const Point& p) { return f(toEigen(p)) > 0 ? 1 : 0; };
  else
    label = [f = sampled.labelAt](const Point& p) { return f(toEigen(p)); };
  return Domain(label, box, kRelativeErrorBound);
}

// Inserts surface points on every connected piece of the sampled labels
// (6-connected voxels of one label; with `foregroundOnly`, of any label > 0),
// on segments from a voxel centre of the piece to a neighbour outside it:
// where the piece is extreme along +-x, +-y, +-z, and one crossing per cube
// of side `spacingMm` along its boundary. Mesh_3's own initialization shoots
// random rays from one point and can miss pieces entirely (an arm cut free
// from the trunk, a foot), and a handful of points on a long body leaves no
// restricted facet to start refining from.
void seedEveryPiece(C3t3& c3t3, const Domain& domain, const LabelGrid& labels, bool foregroundOnly, double spacingMm) {
  const GridGeometry& g = labels.geometry();
  const auto pieceLabel = [&](std::int64_t v) -> int {
    const Label l = labels.labels()[v];
    return foregroundOnly ? int(l > 0) : int(l);
  };
  static constexpr int kSteps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<std::uint8_t> visited(std::size_t(g.voxelCount()), 0);
  std::vector<Index3> stack;  // voxels by (i, j, k): no divisions per voxel
  std::vector<std::pair<std::int64_t, std::int64_t>> crossings;  // (inside voxel, outside neighbour)
  std::unordered_set<std::uint64_t> usedCubes;
  const auto cubeKey = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d c = ((p - g.boxMin()) / spacingMm).array().floor();
    return (std::uint64_t(c.x()) << 42) ^ (std::uint64_t(c.y()) << 21) ^ std::uint64_t(c.z());
  };
  for (std::int64_t seed = 0; seed < g.voxelCount(); ++seed) {
    const int label = pieceLabel(seed);
    if (label == 0 || visited[seed]) continue;
    struct Extreme {
      std::int64_t inside = -1, outside = -1;
      double extent = -std::numeric_limits<double>::infinity();
    };
    std::array<Extreme, 6> extremes;
    stack.assign(1, g.ijk(seed));
    visited[seed] = 1;
    while (!stack.empty()) {
      const Index3 c = stack.back();
      stack.pop_back();
      const std::int64_t v = g.index(c[0], c[1], c[2]);
      for (int d = 0; d < 6; ++d) {
        const std::int64_t i = c[0] + kSteps[d][0], j = c[1] + kSteps[d][1], k = c[2] + kSteps[d][2];
        if (!g.contains(i, j, k)) continue;  // border voxels are outside by contract
        const std::int64_t n = g.index(i, j, k);
        if (pieceLabel(n) == label) {
          if (!visited[n]) {
            visited[n] = 1;
            stack.push_back({i, j, k});
          }
          continue;
        }
        const double along = double(kSteps[d][0] * c[0] + kSteps[d][1] * c[1] + kSteps[d][2] * c[2]);
        if (along > extremes[d].extent) extremes[d] = {v, n, along};
        if (usedCubes.insert(cubeKey(g.voxelCenter(c[0], c[1], c[2]))).second) crossings.emplace_back(v, n);
      }
    }
    for (const Extreme& x : extremes)
      if (x.inside >= 0) crossings.emplace_back(x.inside, x.outside);
  }

  const auto intersect = domain.construct_intersection_object();
  Triangulation& tr = c3t3.triangulation();
  for (const auto& [inside, outside] : crossings) {
    const Index3 a = g.ijk(inside), b = g.ijk(outside);
    const Eigen::Vector3d pa = g.voxelCenter(a[0], a[1], a[2]), pb = g.voxelCenter(b[0], b[1], b[2]);
    const auto hit = intersect(Kernel::Segment_3(Point(pa.x(), pa.y(), pa.z()), Point(pb.x(), pb.y(), pb.z())));
    if (std::get<2>(hit) == 0) continue;
    const VertexHandle vh = tr.insert(Triangulation::Point(std::get<0>(hit)));
    if (vh == VertexHandle()) continue;
    c3t3.set_dimension(vh, 2);
    c3t3.set_index(vh, std::get<1>(hit));
  }
  // Too few pieces to span 3D: let Mesh_3 add its usual random initial points.
  if (tr.dimension() != 3) {
    Criteria dummy(CGAL::parameters::facet_angle = 30.0);
    CGAL::Mesh_3::internal::init_c3t3(c3t3, domain, dummy, 20);
  }
}

int vertexIndex(std::unordered_map<VertexHandle, int>& index, std::vector<Eigen::Vector3d>& positions, VertexHandle v,
                const Triangulation& tr) {
  const auto [it, inserted] = index.try_emplace(v, int(positions.size()));
  if (inserted) positions.push_back(toEigen(tr.point(v).point()));
  return it->second;
}

// The refinement polls the calling thread's cancellation flag between steps
// (cancellation.h).
CGAL::parameters::internal::Mesh_3_options stopWhenCancelled() {
  return CGAL::parameters::mesh_3_options(CGAL::parameters::pointer_to_stop_atomic_boolean = &cancellationFlag());
}

// The exudation (CGAL's Slivers_exuder as refine_mesh_3 runs it, with no
// time limit and the given sliver bound), polling the cancellation flag
// after each cell it works on: refine_mesh_3's stop flag covers only the
// refinement, and the exudation of a body takes seconds. It also stops
// after as many pumped vertices as the triangulation has vertices: a
// machine-independent bound in place of the time limit. The exuder can
// cycle without end (a skeleton figure's articulated mesh pumped 435,000
// vertices of 5,000 with about 225 cells queued throughout); the transfer
// and articulated meshes of the AM pump about 0.18 per vertex, so the
// bound leaves them as they were.
struct ExudationBound {};
struct StopWhenCancelled {
  std::size_t* pumped;
  std::size_t bound;
  void after_cell_pumped(std::size_t) const {
    throwIfCancelled();
    if (++*pumped >= bound) throw ExudationBound{};  // after a whole pump: the complex is consistent
  }
};

void exude(C3t3& c3t3, double sliverBound) {
  using SliverCriterion = CGAL::Mesh_3::Min_dihedral_angle_criterion<Triangulation>;
  CGAL::Mesh_3::Slivers_exuder<C3t3, SliverCriterion, StopWhenCancelled> exuder(c3t3, SliverCriterion(sliverBound, c3t3.triangulation()));
  exuder.set_time_limit(0.0);
  std::size_t pumped = 0;
  try {
    exuder(StopWhenCancelled{&pumped, std::max<std::size_t>(1, c3t3.triangulation().number_of_vertices())});
  } catch (const ExudationBound&) {
  }
}

}  // namespace

TriMesh restrictedDelaunaySurface(const SampledDomain& sampled, const SurfaceCriteria& criteria) {
  reportProgress("surface meshing", 0.0);
  const Domain domain = makeDomain(sampled, true);
  const Criteria meshCriteria(CGAL::parameters::facet_angle = criteria.facetAngleDeg,
                              CGAL::parameters::facet_size = criteria.facetSizeMm,
                              CGAL::parameters::facet_distance = criteria.facetDistanceMm);
  C3t3 c3t3;
  seedEveryPiece(c3t3, domain, *sampled.labels, true, 4.0 * criteria.facetSizeMm);
  CGAL::refine_mesh_3(c3t3, domain, meshCriteria, CGAL::parameters::no_perturb(), CGAL::parameters::no_exude(),
                      CGAL::parameters::manifold(), CGAL::parameters::no_reset_c3t3(), stopWhenCancelled());
  throwIfCancelled();  // a cancelled refinement stops early, leaving a partial surface

  TriMesh surface;
  std::unordered_map<VertexHandle, int> index;
  const Triangulation& tr = c3t3.triangulation();
  for (auto it = c3t3.facets_in_complex_begin(); it != c3t3.facets_in_complex_end(); ++it) {
    const auto& facet = *it;
    // Orient each facet away from its inside cell: vertex_triple_index lists
    // a facet's vertices with the normal pointing into the cell, so the
    // order is reversed below.
    auto cell = facet.first;
    int opposite = facet.second;
    if (c3t3.subdomain_index(cell) == 0) {
      const auto mirror = tr.mirror_facet(facet);
      cell = mirror.first;
      opposite = mirror.second;
    }
    if (c3t3.subdomain_index(cell) == 0) continue;  // both sides outside: not a boundary facet
    std::array<int, 3> f;
    for (int j = 0; j < 3; ++j)
      f[j] = vertexIndex(index, surface.positions, cell->vertex(Triangulation::vertex_triple_index(opposite, j)), tr);
    surface.triangles.push_back({f[0], f[2], f[1]});
  }
  reportProgress("surface meshing", 1.0);
  return surface;
}

namespace {

// Mesh_3 sizing field read from a ScalarGrid (model of MeshDomainField_3).
// A constant grid (the thesis' initial F) answers its value without the
// interpolation: trilinear weights sum to 1 within a few double ulps, so the
// sampled float is that value exactly.
struct GridSizingField {
  using FT = Kernel::FT;
  using Point_3 = Point;
  using Index = Domain::Index;
  explicit GridSizingField(const ScalarGrid* g) : grid(g) {
    if (!g->values.empty() && std::adjacent_find(g->values.begin(), g->values.end(), std::not_equal_to<>()) == g->values.end())
      constant = g->values.front();
  }
  FT operator()(const Point_3& p, int, const Index&) const {
    return constant ? FT(*constant) : FT(grid->sample(toEigen(p)));
  }
  const ScalarGrid* grid;
  std::optional<float> constant;
};

}  // namespace

TetMesh restrictedDelaunayVolume(const SampledDomain& sampled, const VolumeCriteria& criteria) {
  if (!criteria.sizing) throw RuntimeFailure("restricted Delaunay meshing: no sizing field");
  reportProgress("volume meshing", 0.0);
  const Domain domain = makeDomain(sampled, false);
  const GridSizingField sizing(criteria.sizing);
  const Criteria meshCriteria(CGAL::parameters::facet_angle = criteria.facetAngleDeg,
                              CGAL::parameters::facet_size = sizing,
                              CGAL::parameters::facet_distance = criteria.facetDistanceMm,
                              CGAL::parameters::cell_radius_edge_ratio = criteria.radiusEdgeRatio,
                              CGAL::parameters::cell_size = sizing);
  C3t3 c3t3;
  // Seeds about two mean tet sizes apart: refinement fills in the rest.
  const double meanSize = std::accumulate(criteria.sizing->values.begin(), criteria.sizing->values.end(), 0.0) /
                          double(criteria.sizing->values.size());
  seedEveryPiece(c3t3, domain, *sampled.labels, false, 2.0 * meanSize);
  // Exudation stops at a time limit by default (the refinement's duration),
  // which would make the result depend on the machine's speed: no limit,
  // but only tets with a dihedral angle under 10 degrees are worked on
  // (exuding everything as far as possible triples the time on a body).
  CGAL::refine_mesh_3(c3t3, domain, meshCriteria, CGAL::parameters::no_perturb(), CGAL::parameters::no_exude(),
                      CGAL::parameters::no_reset_c3t3(), stopWhenCancelled());
  throwIfCancelled();
  if (criteria.exude) exude(c3t3, 10.0);

  TetMesh mesh;
  std::unordered_map<VertexHandle, int> index;
  const Triangulation& tr = c3t3.triangulation();
  for (auto cell = c3t3.cells_in_complex_begin(); cell != c3t3.cells_in_complex_end(); ++cell) {
    Tet t;
    for (int j = 0; j < 4; ++j) t[j] = vertexIndex(index, mesh.positions, cell->vertex(j), tr);
    mesh.tets.push_back(t);
    mesh.labels.push_back(std::int32_t(c3t3.subdomain_index(cell)));
  }
  if (criteria.keepOutside)
    for (auto cell : tr.finite_cell_handles()) {
      if (c3t3.is_in_complex(cell)) continue;
      Tet t;
      for (int j = 0; j < 4; ++j) t[j] = vertexIndex(index, mesh.positions, cell->vertex(j), tr);
      mesh.tets.push_back(t);
      mesh.labels.push_back(0);
    }
  reportProgress("volume meshing", 1.0);
  return mesh;
}

}  // namespace vox
