// voxmorph.mesh and voxmorph.remesh: the M-MAd remesher of `voxmorph mesh`
// and `voxmorph remesh` on arrays (points, tets, labels) as meshio takes them.

#include "python/bindings.h"
#include "python/interruptible.h"

#include "geometry/error.h"
#include "geometry/remesh/adaptive_voxel_tetrahedralization.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh.h"
#include "geometry/remesh/remesh_complex.h"
#include "geometry/remesh/remesh_report.h"
#include "geometry/tet_mesh.h"
#include "geometry/world_frame.h"

#include <pybind11/stl.h>

#include <functional>

namespace vox::python {

namespace {

struct RemeshArguments {
  remesh::RemeshOptions options;
  OrganArgument organs;
  bool keepImaginary = false;
  bool distances = true;
};

RemeshArguments remeshArguments(double l, const py::object& organs, int iterations, int flipSmooth, const std::string& surface,
                                bool keepImaginary, bool distances, int threads) {
  if (!(l > 0.0) || !std::isfinite(l)) throw UsageError("l", "the target edge length must be a positive number of mm");
  if (surface != "hpss" && surface != "pss" && surface != "none")
    throw UsageError("surface", "must be 'hpss', 'pss' or 'none'; got '" + surface + "'");
  RemeshArguments a;
  a.options.targetLength = l;
  a.options.iterations = iterations;
  a.options.flipSmoothCycles = flipSmooth;
  a.options.projectOnInterfaces = surface != "none";
  a.options.hermite = surface == "hpss";
  if (threads < 1 || threads > 64) throw UsageError("threads", "must be an integer in [1, 64]");
  a.options.threads = threads;
  a.organs = organArgument(organs);
  a.keepImaginary = keepImaginary;
  a.distances = distances;
  return a;
}

// The remesher on `initial`, its labels named by the organ table, and its
// quality report against `initialTopology`; the mesh in `toWorld`'s world
// frame when given (a grid's).
py::tuple runRemesh(const TetMesh& initial, const std::function<remesh::MeshTopology()>& initialTopology, const RemeshArguments& a,
                    const std::string& source, const GridGeometry* toWorld) {
  auto [mesh, report] = interruptible([&] {
    remesh::RemeshStats stats;
    TetMesh output = remesh::remeshTetMesh(initial, a.options, &stats, a.keepImaginary, source);
    if (a.organs.table) {
      std::map<std::int32_t, std::string> names;
      for (const auto& [id, organ] : a.organs.table->organs()) names[id] = organ.name;
      setLabelNames(output, names);
    }
    remesh::ReportOptions reportOptions;
    reportOptions.distances = a.distances;
    reportOptions.threads = a.options.threads;
    reportOptions.named = a.organs.table.has_value();
    const remesh::RemeshReport r = remesh::buildRemeshReport(initial, initialTopology(), output, a.options.targetLength, stats, reportOptions);
    if (toWorld) tetMeshGridToWorld(output, *toWorld);
    return std::make_pair(std::move(output), remesh::reportJson(r));
  });
  py::array_t<double> points({py::ssize_t(mesh.vertexCount()), py::ssize_t(3)});
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v)
    for (int c = 0; c < 3; ++c) points.mutable_at(py::ssize_t(v), c) = mesh.positions[v][c];
  py::array_t<std::int32_t> tets({py::ssize_t(mesh.tetCount()), py::ssize_t(4)});
  if (mesh.tetCount() > 0) std::copy(mesh.tets.front().data(), mesh.tets.front().data() + 4 * mesh.tetCount(), tets.mutable_data());
  py::array_t<std::int32_t> labels(py::ssize_t(mesh.tetCount()), mesh.labels.data());
  return py::make_tuple(points, tets, labels, fromJson(report));
}

using Coordinates = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Indices = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;

TetMesh tetMeshFromArrays(const Coordinates& points, const Indices& tets, const Indices& labels) {
  if (points.ndim() != 2 || points.shape(1) != 3) throw InputError("points", "must be an array of shape (#V, 3)");
  if (tets.ndim() != 2 || tets.shape(1) != 4) throw InputError("tets", "must be an array of shape (#T, 4)");
  if (labels.ndim() != 1 || labels.shape(0) != tets.shape(0)) throw InputError("labels", "must hold one label per tet (#T)");
  TetMesh mesh;
  mesh.positions.resize(std::size_t(points.shape(0)));
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    mesh.positions[v] = Eigen::Vector3d(points.at(py::ssize_t(v), 0), points.at(py::ssize_t(v), 1), points.at(py::ssize_t(v), 2));
  mesh.tets.resize(std::size_t(tets.shape(0)));
  mesh.labels.resize(mesh.tets.size());
  const std::int64_t vertices = std::int64_t(mesh.positions.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    for (int c = 0; c < 4; ++c) {
      const std::int64_t i = tets.at(py::ssize_t(t), c);
      if (i < 0 || i >= vertices)
        throw InputError("tets", "tet " + std::to_string(t) + " refers to vertex " + std::to_string(i) + " of " + std::to_string(vertices));
      mesh.tets[t][std::size_t(c)] = std::int32_t(i);
    }
    const std::int64_t l = labels.at(py::ssize_t(t));
    if (l < -1 || l > std::numeric_limits<std::int32_t>::max()) throw InputError("labels", "tet " + std::to_string(t) + " has label " + std::to_string(l));
    mesh.labels[t] = std::int32_t(l);
  }
  mesh.validate("mesh");
  return mesh;
}

}  // namespace

void bindMeshing(py::module_& m) {
  const char* options = R"doc(
l: target edge length in mm (splits above 4/3 l, collapses below 4/5 l).
organs: OrganTable or path: label names in the report and the mesh.
iterations: split-collapse-flip-smooth rounds; flip_smooth: final flip-smooth cycles.
surface: interface model boundary vertices are projected on: 'hpss', 'pss' or 'none'.
keep_imaginary: also return the imaginary layer around the domain (label 0).
distances: compute the interface Hausdorff distances of the report.
threads: worker threads (as the CLI's --threads).
Returns (points #V x 3 float64 world mm, tets #T x 4 int32, labels #T int32, report dict):
meshio.Mesh(points, [("tetra", tets)], cell_data={"label": [labels]}) writes it.)doc";
  m.def(
      "mesh",
      [](const GridHandle& grid, double l, const py::object& organs, int iterations, int flipSmooth, const std::string& surface,
         bool keepImaginary, bool distances, int threads) {
        const RemeshArguments a = remeshArguments(l, organs, iterations, flipSmooth, surface, keepImaginary, distances, threads);
        const TetMesh initial = interruptible([&] {
          return remesh::tetrahedralizeVoxelsAdaptive(grid->grid, remesh::adaptiveOptionsForTarget(grid->grid.geometry(), l));
        });
        return runRemesh(initial, [&] { return remesh::computeGridTopology(grid->grid); }, a, grid->source, &grid->grid.geometry());
      },
      py::arg("grid"), py::arg("l"), py::kw_only(), py::arg("organs") = py::none(), py::arg("iterations") = remesh::RemeshOptions{}.iterations,
      py::arg("flip_smooth") = remesh::RemeshOptions{}.flipSmoothCycles, py::arg("surface") = "hpss", py::arg("keep_imaginary") = false,
      py::arg("distances") = true, py::arg("threads") = remesh::RemeshOptions{}.threads,
      (std::string("Meshes a label grid into a multi-material tet mesh (M-MAd), as `voxmorph mesh`.\n") + options).c_str());
  m.def(
      "remesh",
      [](const Coordinates& points, const Indices& tets, const Indices& labels, double l, const py::object& organs, int iterations,
         int flipSmooth, const std::string& surface, bool keepImaginary, bool distances, int threads) {
        const RemeshArguments a = remeshArguments(l, organs, iterations, flipSmooth, surface, keepImaginary, distances, threads);
        TetMesh input = tetMeshFromArrays(points, tets, labels);
        orientPositively(input);
        remesh::checkNoFlatTets(input, "mesh");
        return runRemesh(input, [&] { return remesh::computeMeshTopology(input); }, a, "mesh", nullptr);
      },
      py::arg("points"), py::arg("tets"), py::arg("labels"), py::arg("l"), py::kw_only(), py::arg("organs") = py::none(),
      py::arg("iterations") = remesh::RemeshOptions{}.iterations, py::arg("flip_smooth") = remesh::RemeshOptions{}.flipSmoothCycles,
      py::arg("surface") = "hpss", py::arg("keep_imaginary") = false, py::arg("distances") = true, py::arg("threads") = remesh::RemeshOptions{}.threads,
      (std::string("Remeshes a labeled tet mesh at a target edge length (M-MAd), as `voxmorph remesh`.\n"
                   "points: #V x 3 (mm), tets: #T x 4 vertex indices, labels: #T (> 0 materials, 0 an imaginary layer).\n") +
       options)
          .c_str());
}

}  // namespace vox::python
