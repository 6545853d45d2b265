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
#include "geometry/remesh/sizing_field.h"
#include "geometry/tet_mesh.h"
#include "geometry/world_frame.h"

#include <pybind11/stl.h>

#include <cstdio>
#include <functional>
#include <memory>
#include <optional>

namespace vox::python {

namespace {

struct RemeshArguments {
  remesh::RemeshOptions options;
  OrganArgument organs;
  bool keepImaginary = false;
  bool distances = true;
  // Adaptive sizing (eq. 2.2): l_B and l_I, 0 for uniform; the field, built
  // on the input in its frame, that options.sizing points to.
  double sizeBoundary = 0.0, sizeInterior = 0.0;
  std::shared_ptr<const remesh::SizingField> sizing;
};

// The remesher's tuning as the CLI's options of the same names.
struct Tuning {
  int iterations, flipSmooth;
  std::string surface;
  double hausdorff, steinerAngle;
};

void checkNumberIn(const char* name, double value, double lo, double hi, const char* unit) {
  if (!(value >= lo && value <= hi)) {
    char text[160];
    std::snprintf(text, sizeof text, "must be a number of %s in [%g, %g]; got %g", unit, lo, hi, value);
    throw UsageError(name, text);
  }
}

// `l` None with `size_boundary` and `size_interior`: adaptive sizing, l = l_B.
RemeshArguments remeshArguments(const std::optional<double>& l, const std::optional<double>& sizeBoundary,
                                const std::optional<double>& sizeInterior, const py::object& organs, const Tuning& tuning,
                                bool keepImaginary, bool distances, int threads) {
  if (sizeBoundary.has_value() != sizeInterior.has_value())
    throw UsageError(sizeBoundary ? "size_interior" : "size_boundary", "adaptive sizing takes both size_boundary and size_interior");
  if (sizeBoundary && l) throw UsageError("l", "is not taken with adaptive sizing (size_boundary, size_interior); pass l=None");
  if (!sizeBoundary && !l) throw UsageError("l", "a target edge length is required (or size_boundary with size_interior)");
  RemeshArguments a;
  if (sizeBoundary) {
    checkNumberIn("size_boundary", *sizeBoundary, 1e-9, 100000, "mm");
    checkNumberIn("size_interior", *sizeInterior, 1e-9, 100000, "mm");
    if (*sizeInterior < *sizeBoundary) {
      char text[160];
      std::snprintf(text, sizeof text, "l_I = %g mm is shorter than size_boundary l_B = %g mm", *sizeInterior, *sizeBoundary);
      throw UsageError("size_interior", text);
    }
    a.sizeBoundary = *sizeBoundary;
    a.sizeInterior = *sizeInterior;
  }
  const double length = l ? *l : *sizeBoundary;
  if (!(length > 0.0) || !std::isfinite(length)) throw UsageError("l", "the target edge length must be a positive number of mm");
  const std::string& surface = tuning.surface;
  if (surface != "hpss" && surface != "pss" && surface != "none")
    throw UsageError("surface", "must be 'hpss', 'pss' or 'none'; got '" + surface + "'");
  checkNumberIn("hausdorff", tuning.hausdorff, 0.0, 10.0, "l");
  checkNumberIn("steiner_angle", tuning.steinerAngle, 0.0, 60.0, "degrees");
  a.options.targetLength = length;
  a.options.hausdorff = tuning.hausdorff;
  a.options.steiner.angle = tuning.steinerAngle;
  a.options.iterations = tuning.iterations;
  a.options.flipSmoothCycles = tuning.flipSmooth;
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
    remesh::RemeshReport r = remesh::buildRemeshReport(initial, initialTopology(), output, a.options.targetLength, stats, reportOptions);
    if (a.sizing) {
      r.sizingMin = a.sizing->minimum();
      r.sizingMax = a.sizing->maximum();
    }
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
l: target edge length in mm (splits above 4/3 l, collapses below 4/5 l); None with adaptive sizing.
size_boundary, size_interior: adaptive sizing (eq. 2.2), l_B on the label interfaces and l_I
  farthest from them (mm, l_I >= l_B): l = (l_I - l_B) D + l_B, D the normalized distance.
organs: OrganTable or path: label names in the report and the mesh.
iterations: split-collapse-flip-smooth rounds; flip_smooth: final flip-smooth cycles.
surface: interface model boundary vertices are projected on: 'hpss', 'pss' or 'none'.
hausdorff: interface bound in units of l (0: none), as --hausdorff.
steiner_angle: sliver removal, split an edge of each tet still under this angle (degrees; 0 skips it).
keep_imaginary: also return the imaginary layer around the domain (label 0).
distances: compute the interface Hausdorff distances of the report.
threads: worker threads (as the CLI's --threads).
Returns (points #V x 3 float64 world mm, tets #T x 4 int32, labels #T int32, report dict):
meshio.Mesh(points, [("tetra", tets)], cell_data={"label": [labels]}) writes it.)doc";
  m.def(
      "mesh",
      [](const GridHandle& grid, std::optional<double> l, std::optional<double> sizeBoundary, std::optional<double> sizeInterior,
         const py::object& organs, int iterations, int flipSmooth, const std::string& surface, double hausdorff, double steinerAngle,
         bool keepImaginary, bool distances, int threads) {
        RemeshArguments a = remeshArguments(l, sizeBoundary, sizeInterior, organs, {iterations, flipSmooth, surface, hausdorff, steinerAngle},
                                            keepImaginary, distances, threads);
        const TetMesh initial = interruptible([&] {
          const GridGeometry& g = grid->grid.geometry();
          if (a.sizeBoundary == 0.0) return remesh::tetrahedralizeVoxelsAdaptive(grid->grid, remesh::adaptiveOptionsForTarget(g, a.options.targetLength));
          a.sizing = std::make_shared<remesh::SizingField>(remesh::interfaceSizingField(grid->grid, a.sizeBoundary, a.sizeInterior));
          a.options.sizing = a.sizing.get();
          return remesh::tetrahedralizeVoxelsAdaptive(grid->grid, remesh::adaptiveOptionsForSizing(g, a.options.targetLength, a.sizing->maximum()));
        });
        return runRemesh(initial, [&] { return remesh::computeGridTopology(grid->grid); }, a, grid->source, &grid->grid.geometry());
      },
      py::arg("grid"), py::arg("l") = py::none(), py::kw_only(), py::arg("size_boundary") = py::none(), py::arg("size_interior") = py::none(),
      py::arg("organs") = py::none(), py::arg("iterations") = remesh::RemeshOptions{}.iterations,
      py::arg("flip_smooth") = remesh::RemeshOptions{}.flipSmoothCycles, py::arg("surface") = "hpss",
      py::arg("hausdorff") = remesh::RemeshOptions{}.hausdorff, py::arg("steiner_angle") = remesh::RemeshOptions{}.steiner.angle,
      py::arg("keep_imaginary") = false, py::arg("distances") = true, py::arg("threads") = remesh::RemeshOptions{}.threads,
      (std::string("Meshes a label grid into a multi-material tet mesh (M-MAd), as `voxmorph mesh`.\n") + options).c_str());
  m.def(
      "remesh",
      [](const Coordinates& points, const Indices& tets, const Indices& labels, std::optional<double> l, std::optional<double> sizeBoundary,
         std::optional<double> sizeInterior, const py::object& organs, int iterations, int flipSmooth, const std::string& surface,
         double hausdorff, double steinerAngle, bool keepImaginary, bool distances, int threads) {
        RemeshArguments a = remeshArguments(l, sizeBoundary, sizeInterior, organs, {iterations, flipSmooth, surface, hausdorff, steinerAngle},
                                            keepImaginary, distances, threads);
        TetMesh input = tetMeshFromArrays(points, tets, labels);
        orientPositively(input);
        remesh::checkNoFlatTets(input, "mesh");
        if (a.sizeBoundary > 0.0) {
          a.sizing = interruptible([&] {
            return std::make_shared<remesh::SizingField>(remesh::interfaceSizingField(input, a.sizeBoundary, a.sizeInterior));
          });
          a.options.sizing = a.sizing.get();
        }
        return runRemesh(input, [&] { return remesh::computeMeshTopology(input); }, a, "mesh", nullptr);
      },
      py::arg("points"), py::arg("tets"), py::arg("labels"), py::arg("l") = py::none(), py::kw_only(),
      py::arg("size_boundary") = py::none(), py::arg("size_interior") = py::none(), py::arg("organs") = py::none(),
      py::arg("iterations") = remesh::RemeshOptions{}.iterations, py::arg("flip_smooth") = remesh::RemeshOptions{}.flipSmoothCycles,
      py::arg("surface") = "hpss", py::arg("hausdorff") = remesh::RemeshOptions{}.hausdorff,
      py::arg("steiner_angle") = remesh::RemeshOptions{}.steiner.angle, py::arg("keep_imaginary") = false, py::arg("distances") = true,
      py::arg("threads") = remesh::RemeshOptions{}.threads,
      (std::string("Remeshes a labeled tet mesh at a target edge length (M-MAd), as `voxmorph remesh`.\n"
                   "points: #V x 3 (mm), tets: #T x 4 vertex indices, labels: #T (> 0 materials, 0 an imaginary layer).\n") +
       options)
          .c_str());
}

}  // namespace vox::python
