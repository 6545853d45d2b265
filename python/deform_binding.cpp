// voxmorph.deform, voxmorph.Posing and voxmorph.parts: the deformation run of
// `voxmorph deform`, the viewer's per-frame posing session and the body parts
// of `voxmorph parts`, on Grid objects.

#include "python/bindings.h"
#include "python/interruptible.h"

#include "geometry/deform/pose/pose_editor.h"
#include "geometry/deform/pose/pose_frame.h"
#include "geometry/deform/report/deformation_report.h"
#include "geometry/deform/run/deform_run.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/input_provenance.h"
#include "geometry/io/output_path.h"
#include "geometry/raster/raster_engines.h"
#include "geometry/skeleton/skeleton.h"
#include "geometry/world_frame.h"
#include "gpu/raster_engines.h"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <memory>
#include <vector>

namespace vox::python {

namespace {

// Warnings the run gives, shown as Python warnings once it returns.
struct Warnings {
  std::vector<std::string> messages;
  std::function<void(const std::string&)> sink() {
    return [this](const std::string& m) { messages.push_back(m); };
  }
  void emit() const {
    for (const std::string& m : messages) warn(m);
  }
};

DeformGridRequest::VolumeTarget volumeTarget(const py::object& preserve, bool& on) {
  on = false;
  if (py::isinstance<py::bool_>(preserve) || preserve.is_none()) {
    on = !preserve.is_none() && preserve.cast<bool>();
    return DeformGridRequest::VolumeTarget::Deformed;
  }
  const std::string target = py::str(preserve).cast<std::string>();
  if (target != "deformed" && target != "rest")
    throw UsageError("preserve_volumes", "must be True, False, 'deformed' or 'rest'; got '" + target + "'");
  on = true;
  return target == "rest" ? DeformGridRequest::VolumeTarget::Rest : DeformGridRequest::VolumeTarget::Deformed;
}

// A path argument (str or os.PathLike) as text; "" for anything else.
std::string pathArgument(const py::object& argument) {
  const bool path = py::isinstance<py::str>(argument) || py::hasattr(argument, "__fspath__");
  return path ? py::str(py::module_::import("os").attr("fspath")(argument)).cast<std::string>() : std::string();
}

// The report's provenance for a call from Python: the process's command
// line (the interpreter and sys.argv), the working directory, and the
// digests of the inputs given as files (grid, organ table, pose) or as text
// (a pose dict, by its JSON text). A Grid in memory has no file to digest:
// the report's "input" names it (the file it was read from, or "grid").
Provenance deformProvenance(const py::object& grid, const py::object& organs, const py::object& pose) {
  const py::module_ sys = py::module_::import("sys");
  std::vector<std::string> words{py::str(sys.attr("executable")).cast<std::string>()};
  for (const py::handle a : py::list(py::getattr(sys, "argv", py::list()))) words.push_back(py::str(a).cast<std::string>());
  std::vector<const char*> argv;
  for (const std::string& w : words) argv.push_back(w.c_str());
  Provenance p = makeProvenance(shellCommandLine(int(argv.size()), argv.data()),
                                {{"grid", pathArgument(grid)}, {"organs", pathArgument(organs)}, {"pose", pathArgument(pose)}});
  if (py::isinstance<py::dict>(pose)) addTextInput(p, "pose", "pose (dict)", py::module_::import("json").attr("dumps")(pose).cast<std::string>());
  return p;
}

py::tuple deform(const py::object& gridArgument, const py::object& pose, const py::object& organsArgument, const py::object& preserveVolumes,
                 bool skinCover, const py::object& prepared, const std::string& output, bool cpu, int samples, bool rigidBones, bool articulated, double boneGap, bool force,
                 double maxBodyChange, double maxBoneChange, double maxBoneOverlap, double maxTissueOverlap, bool allowGrowth, std::int64_t maxMemoryMb) {
  if (!prepared.is_none() && py::isinstance<Grid>(gridArgument))
    throw py::value_error("prepared: a prepared state is checked against the grid file it was made from; give the grid as that path, not a Grid");
  DeformGridRequest request;
  if (!prepared.is_none()) request.prepared = py::str(prepared).cast<std::string>();
  request.preserveVolumes = false;
  request.volumeTarget = volumeTarget(preserveVolumes, request.preserveVolumes);
  request.coverSkin = skinCover;
  const OrganArgument organs = organArgument(organsArgument);
  request.organs = organs.table;
  request.organsSource = organs.source;
  request.samples = samples;
  request.rigidBones = rigidBones;
  request.articulated = articulated;
  if (boneGap != DeformGridRequest{}.boneGapMm && !articulated) throw py::value_error("bone_gap: needs articulated=True");
  if (!(boneGap >= 0.0 && boneGap <= 100.0)) throw py::value_error("bone_gap: " + std::to_string(boneGap) + " mm is not in [0, 100]");
  request.boneGapMm = boneGap;
  request.force = force;
  request.maxBodyChangePercent = maxBodyChange;
  request.maxBoneChangePercent = maxBoneChange;
  request.maxBoneOverlapPercent = maxBoneOverlap;
  request.maxTissueOverlapPercent = maxTissueOverlap;
  request.allowGrowth = allowGrowth;
  request.maxMemoryMb = maxMemoryMb;
  checkOutputPath(output, OutputKind::Grid, "output");

  // The CLI's run on the Grid in memory (read in place, kept alive by the
  // argument), or on the grid file it reads as the CLI does; G' comes back
  // in memory, and is also written to `output` when given.
  GridHandle held;
  if (py::isinstance<Grid>(gridArgument)) {
    held = gridArgument.cast<GridHandle>();
    request.inputGrid = &held->grid;
    request.input = held->source;
  } else {
    request.input = py::str(gridArgument).cast<std::string>();
  }
  request.output = output;
  LabelGrid posed;
  request.posedGrid = &posed;
  const GridGeometry frame = held ? held->grid.geometry() : openGridSlices(request.input)->geometry();
  PoseArgument p = poseArgument(pose, frame);
  request.pose = std::move(p.pose);
  request.poseSource = p.source;
  request.provenance = deformProvenance(gridArgument, organsArgument, pose);
  Warnings warnings;
  request.warn = warnings.sink();
  checkDeformGridRequest(request);

  DeformationReport report = interruptible([&] {
    const std::unique_ptr<RasterEngines> engines = gpu::makeRasterEngines(cpu, request.warn);
    return deformGrid(request, *engines);
  });
  warnings.emit();
  for (const std::string& w : deformationWarnings(report)) warn(w);
  return py::make_tuple(makeGrid(std::move(posed), output.empty() ? "posed grid" : output), fromJson(deformationReportJson(report)));
}

// The posing session: the viewer's PoseEditor on a Grid.
class Posing {
public:
  Posing(const GridHandle& grid, const py::object& pose, const py::object& organsArgument) : grid_(grid) {
    const OrganArgument organs = organArgument(organsArgument);
    PoseArgument p = poseArgument(pose, grid->grid.geometry());
    editor_ = interruptible([&] { return std::make_unique<PoseEditor>(grid->grid, organs.table, p.pose, p.source); });
  }

  void setPose(const py::object& pose) {
    PoseArgument p = poseArgument(pose, grid_->grid.geometry());
    runInterruptible([&] { editor_->loadPose(p.pose, p.source); });
  }

  void setJoints(const py::dict& joints) {
    py::dict pose;
    pose["joints"] = joints;
    setPose(pose);
  }

  py::dict frame() {
    runInterruptible([&] { editor_->update(); });
    const PoseFigures& f = editor_->figures();
    py::dict d;
    d["positions"] = worldPositions(editor_->transferMeshPositions());
    py::dict volumes;
    const double vv = grid_->grid.geometry().voxelVolume();
    for (std::size_t l = 1; l < f.restVoxels.size() && l < f.deformedVoxels.size(); ++l) {
      if (f.restVoxels[l] <= 0.0) continue;
      py::dict v;
      v["rest_mm3"] = f.restVoxels[l] * vv;
      v["deformed_mm3"] = f.deformedVoxels[l] * vv;
      v["change_percent"] = 100.0 * (f.deformedVoxels[l] / f.restVoxels[l] - 1.0);
      volumes[py::int_(l)] = v;
    }
    d["label_volumes"] = volumes;
    d["inverted_tets"] = f.tmInverted;
    d["vertices_outside_cage"] = f.tmOutsideCage;
    d["bones_through_each_other"] = f.bonesThroughEachOther ? py::object(py::str(*f.bonesThroughEachOther)) : py::object(py::none());
    d["deform_ms"] = f.deformMs;
    return d;
  }

  GridHandle rasterize(int samples, bool cpu) {
    Warnings warnings;
    LabelGrid posed = interruptible([&] {
      editor_->update();
      const std::unique_ptr<RasterEngines> engines = gpu::makeRasterEngines(cpu, warnings.sink());
      const std::unique_ptr<SlabRasterizer> engine =
          makeRasterizer(*engines, RasterSource{.grid = &grid_->grid}, editor_->pipeline().transferMesh(), editor_->transferMeshPositions(),
                         samples, 0);
      return rasterizeAllSlabs(*engine);
    });
    warnings.emit();
    return makeGrid(std::move(posed), "posed grid");
  }

  py::tuple transferMesh() const {
    const TetMesh& tm = editor_->pipeline().transferMesh();
    py::array_t<std::int32_t> tets({py::ssize_t(tm.tetCount()), py::ssize_t(4)});
    std::copy(tm.tets.begin()->data(), tm.tets.begin()->data() + 4 * tm.tetCount(), tets.mutable_data());
    py::array_t<std::int32_t> labels(py::ssize_t(tm.tetCount()), tm.labels.data());
    return py::make_tuple(worldPositions(tm.positions), tets, labels);
  }

  py::object pose() const { return fromJson(poseToJson(editor_->pose())); }

private:
  py::array_t<double> worldPositions(const std::vector<Eigen::Vector3d>& grid) const {
    py::array_t<double> out({py::ssize_t(grid.size()), py::ssize_t(3)});
    auto w = out.mutable_unchecked<2>();
    for (std::size_t i = 0; i < grid.size(); ++i) {
      const Eigen::Vector3d p = gridToWorld(grid_->grid.geometry(), grid[i]);
      for (int a = 0; a < 3; ++a) w(py::ssize_t(i), a) = p[a];
    }
    return out;
  }

  GridHandle grid_;
  std::unique_ptr<PoseEditor> editor_;
};

py::tuple parts(const GridHandle& grid, const py::object& organsArgument, const py::object& userParts) {
  const OrganArgument organs = organArgument(organsArgument);
  if (!organs.table) throw UsageError("organs", "body parts come from the bones: give the organ table that names them");
  skeleton::requireBones(*organs.table, organs.source);
  std::optional<LabelGrid> user;
  std::string partsSource = "body parts";
  if (!userParts.is_none()) {
    const Grid& u = userParts.cast<const Grid&>();
    user = u.grid;
    partsSource = u.source;
  }
  std::optional<LabelGrid> copy;
  skeleton::Skeleton s = interruptible([&] {
    return skeleton::buildSkeleton(ownedGrid(grid->grid, copy), *organs.table, {grid->source, organs.source, partsSource}, std::move(user));
  });
  const py::object report = fromJson(skeleton::skeletonReportJson(s, grid->grid.geometry(), grid->source, ""));
  return py::make_tuple(makeGrid(std::move(s.parts.parts), "body parts"), report["joints"]);
}

}  // namespace

PoseArgument poseArgument(const py::object& pose, const GridGeometry& grid) {
  PoseArgument a;
  if (py::isinstance<py::dict>(pose)) {
    a.source = "pose";
    a.pose = parsePose(py::module_::import("json").attr("dumps")(pose).cast<std::string>(), a.source);
  } else {
    a.source = py::str(pose).cast<std::string>();
    a.pose = readPose(a.source);
  }
  a.pose = poseInGridFrame(a.pose, grid, a.source);
  return a;
}

void bindDeform(py::module_& m) {
  m.def("deform", &deform, py::arg("grid"), py::arg("pose"), py::kw_only(), py::arg("organs") = py::none(),
        py::arg("preserve_volumes") = false, py::arg("skin_cover") = true, py::arg("prepared") = py::none(), py::arg("output") = "", py::arg("cpu") = false,
        py::arg("samples") = 1, py::arg("rigid_bones") = false, py::arg("articulated") = false,
        py::arg("bone_gap") = DeformGridRequest{}.boneGapMm, py::arg("force") = false,
        py::arg("max_body_change") = DeformGridRequest{}.maxBodyChangePercent,
        py::arg("max_bone_change") = DeformGridRequest{}.maxBoneChangePercent,
        py::arg("max_bone_overlap") = DeformGridRequest{}.maxBoneOverlapPercent,
        py::arg("max_tissue_overlap") = DeformGridRequest{}.maxTissueOverlapPercent, py::arg("allow_growth") = false,
        py::arg("max_memory") = 0, R"doc(
Re-poses a label grid, as `voxmorph deform` does, and returns (posed Grid, report dict).

grid: a Grid, or the path of a grid file (then read as the CLI reads it).
pose: the pose as a dict (the JSON schema of docs/POSES.md: "joints", "selections",
    "separations"; world-frame mm) or the path of a pose file.
organs: OrganTable or its path: masses in the report, label groups for separations,
    and the bones a joint pose needs.
preserve_volumes: False; True or 'deformed' fills the gaps the pose opens inside the body
    and relabels boundary voxels so each label keeps the volume the deformation gives it;
    'rest' keeps its rest volume (organ masses).
skin_cover: with preserve_volumes, the tissue the pose lays bare (no skin within a voxel,
    not bare at rest) is relabelled the nearest skin label; False leaves it bare (the CLI's
    --no-skin-cover). The report's "skin_cover" counts it.
prepared: a rest state saved by `voxmorph prepare` (.vxprep path): the skeleton, cage,
    envelope and transfer mesh are taken from it instead of rebuilt; the result is
    byte-identical. The grid must then be given as the path it was prepared from; a state
    made from another grid, organ table or options raises ValueError naming what differs.
output: also write the posed grid to this file (atomically: nothing is left on error or
    Ctrl-C); by default it is only returned.
cpu: rasterize with the CPU reference instead of the GPU (the GPU falls back to the CPU
    with a RuntimeWarning when none is usable).
samples: k, k^3 samples per output voxel (majority label).
rigid_bones, articulated, bone_gap, force, max_body_change, max_bone_change, max_bone_overlap,
    max_tissue_overlap, allow_growth, max_memory: as the CLI's --rigid-bones, --articulated,
    --bone-gap (mm; another than the default needs articulated), --force, --max-body-change
    (%), --max-bone-change (%), --max-bone-overlap (%: a joint pose pressing two parts'
    bones through each other), --max-tissue-overlap (%: two parts' tissue through each
    other, of the body), --allow-growth and --max-memory (MB; 0: in core).

The report dict is the CLI's JSON report (--report); its provenance lists the inputs given
as paths (and a pose dict's JSON text) with their SHA-256, while a Grid in memory, which has
no file, is named by the report's "input" alone. The grid is read where it lies and the
posed grid comes back from memory: no scratch file is written. Bad input raises ValueError (or
OSError for unreadable files) with the CLI's one-line message; a physically wrong
result is refused with ValueError unless force=True. The GIL is released during the
work and Ctrl-C interrupts it.)doc");

  py::class_<Posing>(m, "Posing", R"doc(
An interactive posing session on a grid (the viewer's): the deformation pipeline is
built once, then each frame() is ARAP -> Green coordinates -> propagation on the
transfer mesh, without rasterizing the grid.

Posing(grid, pose, organs=None)
    pose: the setup pose (dict or path): its separations shape the pre-processing; a
        joint pose (which needs organs naming the bones) builds the skeleton.)doc")
      .def(py::init<const GridHandle&, const py::object&, const py::object&>(), py::arg("grid"), py::arg("pose"),
           py::arg("organs") = py::none())
      .def("set_pose", &Posing::setPose, py::arg("pose"),
           "Replaces the selections with a pose's (dict or path; joints compiled against the session's skeleton).")
      .def("set_joints", &Posing::setJoints, py::arg("joints"),
           "Sets joint angles, e.g. {'right_shoulder': {'abduction': 60}} (degrees).")
      .def("frame", &Posing::frame, R"doc(
Brings the transfer mesh to the current pose and returns the live figures: a dict of
positions (#V x 3 transfer-mesh vertices, world mm), label_volumes ({label: {rest_mm3,
deformed_mm3, change_percent}} from the mesh's Jacobians), inverted_tets,
vertices_outside_cage and deform_ms.)doc")
      .def("rasterize", &Posing::rasterize, py::arg("samples") = 1, py::arg("cpu") = false,
           "The posed full-resolution grid of the current pose (a Grid), without the refinement or volume correction of deform().")
      .def_property_readonly("transfer_mesh", &Posing::transferMesh,
                             "The rest transfer mesh: (points #V x 3 world mm, tets #T x 4 int32, labels #T int32).")
      .def_property_readonly("pose", &Posing::pose, "The current pose as a dict (grid frame; saving it gives a pose file).");

  m.def("parts", &parts, py::arg("grid"), py::arg("organs"), py::arg("parts") = py::none(), R"doc(
The body parts of a grid from its bones (the organ table names them): every foreground
voxel gets the part of its nearest bone measured inside the body, as `voxmorph parts`.
Returns (parts Grid, joints): the joints (centre, axes, ranges; world mm) as dicts.
parts: a corrected body-part Grid to use instead of the assignment.)doc");
}

}  // namespace vox::python
