// voxmorph.Grid, voxmorph.OrganTable and the module's exceptions.

#include "python/bindings.h"
#include "python/interruptible.h"

#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/grid_stream.h"
#include "geometry/label_stats.h"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstring>
#include <filesystem>
#include <limits>

namespace vox::python {

namespace {

// An organ table with the path it was read from (its name in errors).
struct Organs {
  OrganTable table;
  std::string source;
};

bool mentions(const char* message, const char* what) { return std::strstr(message, what) != nullptr; }

// Where a file could not be opened, read or written, the fault is the
// system's: OSError (FileNotFoundError for a missing file); every other
// fault of the input: ValueError. The message is the CLI's line.
void raiseError(const char* message, bool inputFault) {
  if (mentions(message, "No such file or directory")) {
    PyErr_SetString(PyExc_FileNotFoundError, message);
  } else if (mentions(message, "cannot open") || mentions(message, "cannot read") || mentions(message, "read error") ||
             mentions(message, "cannot create") || mentions(message, "write failed") || mentions(message, "(it is a directory)")) {
    PyErr_SetString(PyExc_OSError, message);
  } else {
    PyErr_SetString(inputFault ? PyExc_ValueError : PyExc_RuntimeError, message);
  }
}

// Copies (and widens) an integer array of labels into a new grid's storage:
// numpy converts in one pass, straight into the grid.
void copyLabels(const py::array& labels, const GridHandle& grid) {
  const py::module_ np = py::module_::import("numpy");
  if (labels.size() > 0) {
    const py::object min = labels.attr("min")(), max = labels.attr("max")();
    if (min.cast<double>() < 0.0 || max.cast<double>() > double(std::numeric_limits<Label>::max()))
      throw InputError("labels", "values span " + py::str(min).cast<std::string>() + ".." + py::str(max).cast<std::string>() +
                                     "; labels must lie in 0..65535");
  }
  np.attr("copyto")(labelView(grid), labels, py::arg("casting") = "unsafe");
}

// The geometry of a grid of `dims` voxels (named `source` in errors) from
// nibabel's affine, or from a spacing alone (axis-aligned, origin 0).
GridGeometry geometryOf(const Index3& dims, const std::optional<Eigen::Vector3d>& spacing, const std::optional<Eigen::Matrix4d>& affine,
                        const std::string& source) {
  GridGeometry g;
  if (affine) {
    if ((affine->row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9)
      throw InputError("affine", "the last row of a voxel-to-world affine is 0 0 0 1");
    g = geometryFromAffine("affine", dims, affine->topLeftCorner<3, 3>(), affine->topRightCorner<3, 1>());
    if (spacing && (*spacing - g.spacing).cwiseAbs().maxCoeff() > 1e-6 * g.spacing.maxCoeff())
      throw InputError("spacing", "disagrees with the affine's voxel axes (give one of the two)");
  } else {
    g.dims = dims;
    if (spacing) g.spacing = *spacing;
  }
  g.validate(source);
  return g;
}

// A uint16 array in Fortran order (x fastest: nibabel's array of a uint16
// image) is laid out as a grid's labels: the grid borrows it, keeping the
// array alive, and reads it in place.
bool borrowable(const py::array& labels) {
  return py::isinstance<py::array_t<Label, py::array::f_style>>(labels) && (labels.flags() & py::detail::npy_api::NPY_ARRAY_ALIGNED_) != 0;
}

GridHandle gridFromArray(const py::array& labels, const std::optional<Eigen::Vector3d>& spacing,
                         const std::optional<Eigen::Matrix4d>& affine) {
  const char kind = labels.dtype().kind();
  if (kind != 'i' && kind != 'u' && kind != 'b')
    throw InputError("labels", "a " + py::str(labels.dtype()).cast<std::string>() +
                                   " array; labels are integers (nibabel: np.asarray(img.dataobj), not img.get_fdata())");
  if (labels.ndim() != 3) throw InputError("labels", "a label grid is a 3-D array; got " + std::to_string(labels.ndim()) + " dimensions");
  const Index3 dims{labels.shape(0), labels.shape(1), labels.shape(2)};
  const GridGeometry geometry = geometryOf(dims, spacing, affine, "labels");
  if (!borrowable(labels)) {
    GridHandle grid = makeGrid(LabelGrid(geometry), "grid");
    copyLabels(labels, grid);
    return grid;
  }
  // The grid (or the one it is moved to) drops the array where it dies,
  // maybe on a worker thread: with the GIL.
  std::shared_ptr<const void> keep(new py::object(labels), [](const py::object* array) {
    py::gil_scoped_acquire gil;
    delete array;
  });
  GridHandle grid = makeGrid(LabelGrid(geometry, static_cast<const Label*>(labels.data()), std::move(keep)), "grid");
  grid->writeable = labels.writeable();
  return grid;
}

// Per-label statistics as columns (a dict pandas.DataFrame takes).
py::dict statistics(const Grid& g, const py::object& organsArgument) {
  const OrganArgument organs = organArgument(organsArgument);
  const LabelStats stats = interruptible([&] { return computeLabelStats(g.grid); });
  const double vv = g.grid.geometry().voxelVolume();
  py::list label, name, voxels, volume, density, mass;
  for (std::size_t l = 0; l < stats.counts.size(); ++l) {
    if (stats.counts[l] == 0) continue;
    label.append(l);
    voxels.append(stats.counts[l]);
    volume.append(double(stats.counts[l]) * vv);
    if (!organs.table) continue;
    const Organ* organ = l > 0 ? organs.table->find(int(l)) : nullptr;
    name.append(organ ? py::object(py::str(organ->name)) : py::object(py::none()));
    density.append(organ ? py::object(py::float_(organ->density)) : py::object(py::none()));
    mass.append(organ ? py::object(py::float_(organs.table->mass(int(l), stats.counts[l], vv))) : py::object(py::none()));
  }
  py::dict columns;
  columns["label"] = label;
  if (organs.table) columns["name"] = name;
  columns["voxels"] = voxels;
  columns["volume_mm3"] = volume;
  if (organs.table) {
    columns["density_g_cm3"] = density;
    columns["mass_g"] = mass;
  }
  return columns;
}

}  // namespace

GridHandle makeGrid(LabelGrid grid, std::string source) {
  auto g = std::make_shared<Grid>();
  g->grid = std::move(grid);
  g->source = std::move(source);
  return g;
}

py::array labelView(const GridHandle& owner) {
  const LabelGrid& grid = owner->grid;
  const Index3& d = grid.dims();
  const auto s = py::ssize_t(sizeof(Label));
  py::array view(py::dtype::of<Label>(), {py::ssize_t(d[0]), py::ssize_t(d[1]), py::ssize_t(d[2])},
                 {s, s * py::ssize_t(d[0]), s * py::ssize_t(d[0] * d[1])}, grid.data(), py::cast(owner));
  if (!owner->writeable) view.attr("setflags")(py::arg("write") = false);
  return view;
}

const LabelGrid& ownedGrid(const LabelGrid& grid, std::optional<LabelGrid>& copy) {
  if (!grid.borrowed()) return grid;
  copy.emplace(grid);
  return *copy;
}

py::object fromJson(const std::string& json) { return py::module_::import("json").attr("loads")(json); }

void warn(const std::string& message) {
  if (PyErr_WarnEx(PyExc_RuntimeWarning, message.c_str(), 1) != 0) throw py::error_already_set();
}

OrganArgument organArgument(const py::object& organs) {
  OrganArgument a;
  if (organs.is_none()) return a;
  if (py::isinstance<Organs>(organs)) {
    const Organs& o = organs.cast<const Organs&>();
    a.table = o.table;
    a.source = o.source;
    return a;
  }
  a.source = py::str(organs).cast<std::string>();
  a.table = OrganTable::read(a.source);
  return a;
}

void bindErrors(py::module_& m) {
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      raiseError(e.what(), true);
    } catch (const RuntimeFailure& e) {
      raiseError(e.what(), false);
    }
  });
}

void bindGrid(py::module_& m) {
  py::class_<Organs>(m, "OrganTable", R"doc(
An organ table: label -> organ name, tissue (media) number and density (g/cm^3),
in the format of the ICRP 110 "organs.dat" files (ID, name words, tissue, density).

OrganTable(path) reads one; a malformed table raises ValueError naming the file
and line, a missing one FileNotFoundError.)doc")
      .def(py::init([](const std::filesystem::path& file) {
             const std::string path = file.string();
             return Organs{OrganTable::read(path), path};
           }),
           py::arg("path"),
           "Reads an organ table file.")
      .def("__len__", [](const Organs& o) { return o.table.organs().size(); })
      .def("__contains__", [](const Organs& o, int id) { return o.table.find(id) != nullptr; })
      .def(
          "__getitem__",
          [](const Organs& o, int id) {
            const Organ* organ = o.table.find(id);
            if (!organ) throw py::key_error(std::to_string(id));
            py::dict d;
            d["id"] = organ->id;
            d["name"] = organ->name;
            d["tissue"] = organ->tissue;
            d["density_g_cm3"] = organ->density;
            return d;
          },
          py::arg("id"), "The organ of a label: a dict of id, name, tissue and density_g_cm3 (KeyError when absent).")
      .def_property_readonly(
          "names",
          [](const Organs& o) {
            py::dict names;
            for (const auto& [id, organ] : o.table.organs()) names[py::int_(id)] = organ.name;
            return names;
          },
          "Organ names by label (a dict).")
      .def_readonly("path", &Organs::source, "The file the table was read from.")
      .def("__repr__", [](const Organs& o) { return "<voxmorph.OrganTable " + o.source + ": " + std::to_string(o.table.organs().size()) + " organs>"; });

  py::class_<Grid, GridHandle>(m, "Grid", R"doc(
A segmented volume: labels (uint16) on a voxel grid with its spacing (mm) and its
voxel-to-world affine (nibabel's: world = affine @ [i, j, k, 1], RAS mm).

Grid(labels, spacing=None, affine=None)
    labels: a 3-D integer array indexed [i, j, k] (nibabel's np.asarray(img.dataobj)).
        A uint16 array in Fortran order (x fastest) is the grid's storage: the grid
        borrows it, keeps it alive and reads it in place, no copy. Any other integer
        array is copied once, widened to uint16, into the grid's own storage
        (Grid.zeros and Grid.read fill that storage without an intermediate array).
    spacing: voxel size in mm (3 numbers); default the affine's, else 1 mm.
    affine: 4 x 4 voxel-to-world matrix (img.affine); default diag(spacing).
Grid.read(path) reads any supported format (.nii, .nii.gz, .mha, .mhd, .nrrd, .nhdr, .inr).

.labels is a numpy view of the grid's storage, its own or the array it borrows (no
copy; writes go to the grid; read-only when the borrowed array is), shape
(nx, ny, nz), Fortran order.)doc")
      .def(py::init(&gridFromArray), py::arg("labels"), py::arg("spacing") = py::none(), py::arg("affine") = py::none())
      .def_static(
          "zeros",
          [](const Index3& shape, const std::optional<Eigen::Vector3d>& spacing, const std::optional<Eigen::Matrix4d>& affine) {
            return makeGrid(LabelGrid(geometryOf(shape, spacing, affine, "shape")), "grid");
          },
          py::arg("shape"), py::arg("spacing") = py::none(), py::arg("affine") = py::none(),
          "A grid of label 0 of the given shape (nx, ny, nz), to fill through .labels in place.")
      .def_static(
          "read",
          [](const std::filesystem::path& file) {
            const std::string path = file.string();
            return makeGrid(interruptible([&] { return readGrid(path); }), path);
          },
          py::arg("path"),
          "Reads a label grid file (NIfTI, MetaImage, NRRD, INR). Corrupt or refused files raise ValueError naming the file "
          "and the fault; unreadable ones OSError.")
      .def(
          "write", [](const Grid& g, const std::filesystem::path& path) { runInterruptible([&] { writeGrid(path.string(), g.grid); }); },
          py::arg("path"),
          "Writes the grid (format from the extension), atomically: an interrupted write leaves no file.")
      .def_property_readonly(
          "labels", [](const GridHandle& g) { return labelView(g); },
          "The labels, shape (nx, ny, nz), uint16: a view of the grid's storage (no copy), or of the array it borrows.")
      .def_property_readonly("affine", [](const Grid& g) { return Eigen::Matrix4d(g.grid.geometry().indexToWorld()); },
                             "4 x 4 voxel-to-world matrix (mm, RAS; nibabel's affine).")
      .def_property_readonly(
          "spacing", [](const Grid& g) { return py::make_tuple(g.grid.spacing()[0], g.grid.spacing()[1], g.grid.spacing()[2]); },
          "Voxel size in mm, (sx, sy, sz).")
      .def_property_readonly("shape", [](const Grid& g) { return py::make_tuple(g.grid.dims()[0], g.grid.dims()[1], g.grid.dims()[2]); },
                             "(nx, ny, nz).")
      .def_readonly("source", &Grid::source, "The file the grid was read from, or 'grid'.")
      .def("statistics", &statistics, py::arg("organs") = py::none(), R"doc(
Per-label voxel counts and volumes, with names, densities and masses when an
organ table is given (an OrganTable or its path): a dict of equal-length columns
(label, name, voxels, volume_mm3, density_g_cm3, mass_g) that pandas.DataFrame takes.
Labels the table does not name get None for name, density and mass.)doc")
      .def("__repr__", [](const Grid& g) {
        const Index3& d = g.grid.dims();
        return "<voxmorph.Grid " + std::to_string(d[0]) + " x " + std::to_string(d[1]) + " x " + std::to_string(d[2]) + " (" + g.source + ")>";
      });
}

}  // namespace vox::python
