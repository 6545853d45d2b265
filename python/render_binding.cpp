// voxmorph.render: the transfer-mesh-guided ray casting of `voxmorph render`
// into an RGB numpy array.

#include "python/bindings.h"
#include "python/interruptible.h"

#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/error.h"
#include "geometry/label_stats.h"
#include "geometry/render/camera.h"
#include "geometry/render/cutting_planes.h"
#include "geometry/render/palette.h"
#include "geometry/render/raycast_reference.h"
#include "geometry/render/raycast_scene.h"
#include "geometry/render/rest_transfer_mesh.h"
#include "gpu/context.h"
#include "gpu/kernels/raycast.h"

#include <pybind11/stl.h>

#include <cstring>

namespace vox::python {

namespace {

py::array_t<std::uint8_t> render(const GridHandle& gridHandle, const py::object& poseArgumentValue, const py::object& organsArgument,
                                 const std::string& cameraText, const std::vector<std::string>& cutTexts, const std::pair<int, int>& size,
                                 const std::string& hide, const std::string& shadingName, bool cpu) {
  const LabelGrid& grid = gridHandle->grid;
  RaycastShading shading;
  shading.normals = parseSurfaceNormals(shadingName, "shading");
  int width = 0, height = 0;
  parseImageSize(std::to_string(size.first) + "x" + std::to_string(size.second), width, height);
  CuttingPlanes cuts;
  for (const std::string& c : cutTexts) cuts.add(c);
  const OrganArgument organs = organArgument(organsArgument);
  std::optional<PoseArgument> pose;
  if (!poseArgumentValue.is_none()) pose = poseArgument(poseArgumentValue, grid.geometry());
  std::vector<std::string> warnings;

  RgbImage image = interruptible([&] {
    Palette palette = organs.table ? Palette::fromOrgans(*organs.table, grid.maxLabel()) : Palette(grid.maxLabel());
    if (!hide.empty()) palette.hide(hide, organs.table ? &*organs.table : nullptr);
    TetMesh restMesh;
    std::vector<Eigen::Vector3d> posed;
    if (!pose) {
      restMesh = boxTransferMesh(grid, gridHandle->source);
      posed = restMesh.positions;
    } else {
      std::optional<LabelGrid> copy;
      const LabelGrid& owned = ownedGrid(grid, copy);
      PipelineOptions options = skeleton::skeletalPoseOptions(pose->pose, pose->source, owned, organs.table,
                                                              {gridHandle->source, organs.source, "body parts"}, std::nullopt);
      options.envelope = false;
      DeformationPipeline pipeline(owned, options);
      pipeline.deform();
      restMesh = pipeline.transferMesh();
      posed = pipeline.deformedTransferMesh();
    }
    const RaycastMesh mesh = buildRaycastMesh(restMesh, grid.geometry(), gridHandle->source);
    const RaycastFrame frame = prepareRaycastFrame(mesh, posed);
    const Camera camera = parseCamera(cameraText, frame.toGrid(frame.cellsLo), frame.toGrid(frame.cellsHi), width, height);
    const RaycastView view = makeRaycastView(frame, camera, cuts);
    if (!cpu) {
      try {
        gpu::Context context;
        gpu::RaycastKernel kernel(context, grid, mesh);
        return kernel.render(frame, view, palette, shading);
      } catch (const RuntimeFailure& e) {
        warnings.push_back(std::string(e.what()) + "; using the CPU");
      }
    }
    return raycastReference(grid, mesh, frame, view, palette, shading);
  });
  for (const std::string& w : warnings) warn(w);
  py::array_t<std::uint8_t> rgb({py::ssize_t(image.height), py::ssize_t(image.width), py::ssize_t(3)});
  static_assert(sizeof(Rgb) == 3);
  std::memcpy(rgb.mutable_data(), image.pixels.data(), image.pixels.size() * 3);
  return rgb;
}

}  // namespace

void bindRender(py::module_& m) {
  m.def("render", &render, py::arg("grid"), py::kw_only(), py::arg("pose") = py::none(), py::arg("organs") = py::none(),
        py::arg("camera") = "", py::arg("cuts") = std::vector<std::string>{}, py::arg("size") = std::pair<int, int>(640, 480),
        py::arg("hide") = "", py::arg("shading") = surfaceNormalsName(RaycastShading{}.normals), py::arg("cpu") = false, R"doc(
Ray-casts a label grid as `voxmorph render`, and returns the image
as a (height, width, 3) uint8 RGB array (PIL.Image.fromarray takes it).

pose: a pose (dict or path): the grid is shown posed through its transfer mesh (the
    deformation's pre-processing and one frame), without rasterizing it; None: at rest.
organs: OrganTable or path: colours by organ name (and the bones of a joint pose).
camera: "azimuth=30,elevation=10,distance=2.5,fov=35" (degrees; distance in scene
    diagonals or with an mm suffix) or "eye=x,y,z,target=x,y,z,up=x,y,z,fov=35" (mm);
    "" fits the foreground. Azimuth 0 looks along +y with z up.
cuts: cutting planes as the CLI's --cut takes them: "x>120mm", "z<400", "plane=nx,ny,nz,d".
size: (width, height) in pixels.
hide: labels to hide, "5,7,10-20", or organ-name substrings with organs ("skin,adipose").
shading: "smooth" (normals from the smoothed occupancy of the visible labels; cut faces
    flat) or "faces" (each voxel face's own normal, voxel faces visible).
cpu: render with the CPU reference instead of the GPU (the GPU falls back to the CPU with
    a RuntimeWarning when none is usable).)doc");
}

}  // namespace vox::python
