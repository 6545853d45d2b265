// The voxmorph Python module: the library's engines on numpy arrays
// (docs/PYTHON.md). Each long call releases the GIL and stops on Ctrl-C
// (interruptible.h); bad input raises ValueError or OSError with the CLI's
// one-line message.

#include "python/bindings.h"
#include "python/interruptible.h"

#include "geometry/provenance.h"

PYBIND11_MODULE(voxmorph, m) {
  m.doc() = R"doc(voxmorph: segmented volumes from numpy.

Grid (labels, spacing, affine; read and write any supported format), OrganTable,
deform (re-pose a grid), Posing (per-frame posing session), parts (body parts and
joints), mesh and remesh (M-MAd tet meshes as meshio arrays), render (RGB arrays).
See docs/PYTHON.md.)doc";
  m.attr("__version__") = vox::voxmorphVersion();
  vox::python::bindErrors(m);
  vox::python::bindGrid(m);
  vox::python::bindDeform(m);
  vox::python::bindMeshing(m);
  vox::python::bindRender(m);
}
