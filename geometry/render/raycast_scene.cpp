#include "geometry/render/raycast_scene.h"

#include "geometry/error.h"
#include "geometry/raster/rasterize.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vox {

RaycastMesh buildRaycastMesh(const TetMesh& restMesh, const GridGeometry& source, const std::string& name) {
  restMesh.validate(name);
  if (restMesh.tets.empty()) throw InputError(name, "has no tets");
  if (restMesh.tets.size() > std::size_t(std::numeric_limits<std::int32_t>::max() / 4))
    throw InputError(name, "has too many tets");
  TetMesh oriented;
  oriented.tets = restMesh.tets;
  oriented.labels = restMesh.labels;
  oriented.positions = restMesh.positions;
  for (std::size_t t = 0; t < oriented.tets.size(); ++t) {
    const Tet& q = oriented.tets[t];
    const auto& p = oriented.positions;
    const double scale = std::max({(p[q[1]] - p[q[0]]).norm(), (p[q[2]] - p[q[0]]).norm(), (p[q[3]] - p[q[0]]).norm()});
    if (std::abs(signedVolume(p, q)) <= 1e-12 * scale * scale * scale)
      throw InputError(name, "tet " + std::to_string(t) + " is degenerate (zero volume) at rest");
  }
  orientPositively(oriented);

  RaycastMesh m;
  m.source = source;
  for (int a = 0; a < 3; ++a) m.sourceShift[a] = source.dims[a] / 2;
  m.vertexCount = oriented.positions.size();
  m.neighbors = faceNeighbors(oriented, name);
  m.tets = std::move(oriented.tets);
  const Eigen::Vector3d shift(double(m.sourceShift[0]), double(m.sourceShift[1]), double(m.sourceShift[2]));
  std::vector<Eigen::Vector3d> rest(m.vertexCount);
  for (std::size_t v = 0; v < m.vertexCount; ++v) rest[v] = source.continuousIndex(oriented.positions[v]) - shift;
  m.restFrames.resize(m.tets.size());
  for (std::size_t t = 0; t < m.tets.size(); ++t) {
    const Tet& q = m.tets[t];
    m.restFrames[t] = {rest[q[0]], rest[q[1]] - rest[q[0]], rest[q[2]] - rest[q[0]], rest[q[3]] - rest[q[0]]};
    for (int k = 0; k < 4; ++k)
      if (m.neighbors[t][k] < 0) m.boundary.push_back({tetFace(q, k), std::int32_t(t)});
  }
  m.restBvh = buildBoundaryBvh(m.boundary, rest);
  return m;
}

Eigen::Vector3d RaycastFrame::toRender(const Eigen::Vector3d& p) const { return (p - renderOrigin).cwiseQuotient(output.spacing); }
Eigen::Vector3d RaycastFrame::toGrid(const Eigen::Vector3d& r) const { return renderOrigin + r.cwiseProduct(output.spacing); }

RaycastFrame placeRaycastFrame(const RaycastMesh& mesh, const std::vector<Eigen::Vector3d>& deformed) {
  if (deformed.size() != mesh.vertexCount)
    throw InputError("deformed positions", std::to_string(deformed.size()) + " positions for a transfer mesh of " +
                                               std::to_string(mesh.vertexCount) + " vertices");
  for (std::size_t v = 0; v < deformed.size(); ++v)
    if (!deformed[v].allFinite()) throw InputError("deformed positions", "vertex " + std::to_string(v) + " is not finite");
  RaycastFrame f;
  f.output = deformedGridGeometry(mesh.source, deformed);
  for (int a = 0; a < 3; ++a) f.cellShift[a] = f.output.dims[a] / 2;
  const Eigen::Vector3d shift(double(f.cellShift[0]), double(f.cellShift[1]), double(f.cellShift[2]));
  f.renderOrigin = f.output.origin + f.output.spacing.cwiseProduct(shift);
  const Eigen::Vector3d dims(double(f.output.dims[0]), double(f.output.dims[1]), double(f.output.dims[2]));
  f.cellsLo = -shift - Eigen::Vector3d::Constant(0.5);
  f.cellsHi = dims - shift - Eigen::Vector3d::Constant(0.5);
  return f;
}

RaycastFrame prepareRaycastFrame(const RaycastMesh& mesh, const std::vector<Eigen::Vector3d>& deformed) {
  RaycastFrame f = placeRaycastFrame(mesh, deformed);
  f.positions.resize(deformed.size());
  for (std::size_t v = 0; v < deformed.size(); ++v) f.positions[v] = f.toRender(deformed[v]);
  f.bvh = mesh.restBvh;
  refitBoundaryBvh(f.bvh, mesh.boundary, f.positions);
  return f;
}

TetFactors tetFactors(const Eigen::Vector3d& v0, const Eigen::Vector3d& v1, const Eigen::Vector3d& v2, const Eigen::Vector3d& v3) {
  // n_k: normal of the face opposite v_k (it contains v_0); delta_k =
  // 1 / ((v_k - v_0) . n_k), which is 1 / det for all three.
  const Eigen::Vector3d e1 = v1 - v0, e2 = v2 - v0, e3 = v3 - v0;
  const Eigen::Vector3d n1 = e2.cross(e3), n2 = e3.cross(e1), n3 = e1.cross(e2);
  const double det = e1.dot(n1);
  TetFactors f;
  f.anchor = v0;
  if (!(std::abs(det) > kDegenerateTetRatio * e1.norm() * e2.norm() * e3.norm())) {
    for (auto& p : f.planes) p = Eigen::Vector4d(0, 0, 0, -1);
    return f;
  }
  const double delta = 1.0 / det;
  f.planes[0] << delta * n1, 0.0;
  f.planes[1] << delta * n2, 0.0;
  f.planes[2] << delta * n3, 0.0;
  return f;
}

std::vector<TetFactors> computeTetFactors(const RaycastMesh& mesh, const RaycastFrame& frame) {
  std::vector<TetFactors> out(mesh.tets.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& q = mesh.tets[t];
    out[t] = tetFactors(frame.positions[q[0]], frame.positions[q[1]], frame.positions[q[2]], frame.positions[q[3]]);
  }
  return out;
}

RaycastView makeRaycastView(const RaycastFrame& frame, const Camera& camera, const CuttingPlanes& cuts) {
  RaycastView v;
  v.camera = cameraRays(camera);
  const Eigen::Vector3d& s = frame.output.spacing;
  v.eye = frame.toRender(v.camera.eye);
  v.forward = v.camera.forward.cwiseQuotient(s);
  v.right = v.camera.right.cwiseQuotient(s);
  v.up = v.camera.up.cwiseQuotient(s);
  for (const CuttingPlane& p : cuts.active()) {
    // n . x > d with x = renderOrigin + s .* c.
    v.cuts.emplace_back(p.normal[0] * s[0], p.normal[1] * s[1], p.normal[2] * s[2], p.offset - p.normal.dot(frame.renderOrigin));
  }
  // A headlight, and a fill light above and to the left of the camera: the
  // three face orientations a voxel shows get three different shades.
  v.headlight = -v.camera.forward;
  v.depthNear = camera.depthNear;
  v.depthFar = camera.depthFar;
  v.light = (-v.camera.forward + 0.6 * v.camera.up - 0.4 * v.camera.right).normalized();
  return v;
}

SurfaceNormals parseSurfaceNormals(const std::string& text, const std::string& what) {
  if (text == "smooth") return SurfaceNormals::Smooth;
  if (text == "faces") return SurfaceNormals::Faces;
  throw InputError(what, "\"" + text + "\" is neither smooth nor faces");
}

const char* surfaceNormalsName(SurfaceNormals normals) { return normals == SurfaceNormals::Smooth ? "smooth" : "faces"; }

}  // namespace vox
