#pragma once
// The voxmorph Python module's pieces: the grid and organ table types, and
// the engines (deformation, posing, body parts, meshing, rendering), each
// bound by its own file onto the module.

#include "geometry/deform/pose/pose.h"
#include "geometry/label_grid.h"
#include "geometry/organ_table.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <optional>
#include <string>

namespace vox::python {

namespace py = pybind11;

// A label grid owned by Python; `source` names it in error messages (its
// file, or "grid"). Its labels are its own, or borrowed from the numpy
// array it was made from (`writeable` as that array is).
struct Grid {
  LabelGrid grid;
  std::string source = "grid";
  bool writeable = true;
};
using GridHandle = std::shared_ptr<Grid>;

GridHandle makeGrid(LabelGrid grid, std::string source);

// The labels of `owner` as a numpy array of shape (nx, ny, nz), x fastest
// (Fortran order, as nibabel's arrays), viewing the grid's storage (its own,
// or the array it borrows).
py::array labelView(const GridHandle& owner);

// `grid` as the engines that read its labels as a vector take it (the
// skeleton, the label groups of the deformation pipeline): itself when it
// owns its labels, else a copy made in `copy`.
const LabelGrid& ownedGrid(const LabelGrid& grid, std::optional<LabelGrid>& copy);

// A report's JSON text as Python objects (dicts, lists, numbers).
py::object fromJson(const std::string& json);

// Issues `message` as a RuntimeWarning; raises what the warnings machinery
// raised instead (a filter turning warnings into errors, or the
// KeyboardInterrupt of a Ctrl-C that arrives while it runs).
void warn(const std::string& message);

// A pose given as a dict (the JSON schema of docs/POSES.md) or a path, in
// the grid frame of `grid`; `source` names it in errors ("pose" or the path).
struct PoseArgument {
  Pose pose;
  std::string source;
};
PoseArgument poseArgument(const py::object& pose, const GridGeometry& grid);

// The organ table argument: None, an OrganTable, or a path.
struct OrganArgument {
  std::optional<OrganTable> table;
  std::string source = "organ table";
};
OrganArgument organArgument(const py::object& organs);

void bindErrors(py::module_& m);
void bindGrid(py::module_& m);
void bindDeform(py::module_& m);
void bindMeshing(py::module_& m);
void bindRender(py::module_& m);

}  // namespace vox::python
