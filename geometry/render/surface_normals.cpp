#include "geometry/render/surface_normals.h"

#include <cmath>

namespace vox {

namespace {

Eigen::Vector3d faceNormal(const RayResult& r) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[r.axis] = -double(r.step);
  return n;
}

// S(s): the occupancy interpolated trilinearly between voxel centres.
double smoothedOccupancy(const LabelGrid& source, const Index3& sourceShift, const Palette& palette, const Eigen::Vector3d& s) {
  const Eigen::Vector3d base = s.array().floor();
  const Eigen::Vector3d f = s - base;
  double sum = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const int i = corner & 1, j = (corner >> 1) & 1, k = corner >> 2;
    const Label l = source.atOr(std::int64_t(base[0]) + i + sourceShift[0], std::int64_t(base[1]) + j + sourceShift[1],
                                std::int64_t(base[2]) + k + sourceShift[2], 0);
    if (l >= palette.size() || !palette.visible(l)) continue;
    sum += (i ? f[0] : 1.0 - f[0]) * (j ? f[1] : 1.0 - f[1]) * (k ? f[2] : 1.0 - f[2]);
  }
  return sum;
}

}  // namespace

Eigen::Vector3d occupancyDifferenceSteps(const GridGeometry& source) {
  const double step = kOccupancyDifferenceStep * source.spacing.maxCoeff();  // mm
  Eigen::Vector3d h;
  for (int a = 0; a < 3; ++a) h[a] = step / source.spacing[a];
  return h;
}

Eigen::Vector3d occupancyGradient(const LabelGrid& source, const Index3& sourceShift, const Palette& palette, const Eigen::Vector3d& s) {
  const Eigen::Vector3d h = occupancyDifferenceSteps(source.geometry());
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (int k = -1; k <= 1; ++k)
    for (int j = -1; j <= 1; ++j)
      for (int i = -1; i <= 1; ++i) {
        if (i == 0 && j == 0 && k == 0) continue;
        const double o = smoothedOccupancy(source, sourceShift, palette, s + Eigen::Vector3d(i * h[0], j * h[1], k * h[2]));
        const double wi = 2 - std::abs(i), wj = 2 - std::abs(j), wk = 2 - std::abs(k);
        g += o * Eigen::Vector3d(i * wj * wk, wi * j * wk, wi * wj * k);
      }
  return g.cwiseQuotient(32.0 * h);
}

Eigen::Vector3d surfaceNormal(const RayResult& r, const LabelGrid& source, const RaycastMesh& mesh, const RaycastFrame& frame,
                              const std::vector<TetFactors>& factors, const RaycastView& view, const Palette& palette,
                              SurfaceNormals normals) {
  if (normals == SurfaceNormals::Faces || r.tet < 0) return faceNormal(r);
  const Eigen::Vector3d& spacing = frame.output.spacing;
  // The ray came through a removed cell: the cut face is flat.
  Eigen::Vector3d before(double(r.cell[0]), double(r.cell[1]), double(r.cell[2]));
  before[r.axis] -= double(r.step);
  for (const Eigen::Vector4d& cut : view.cuts)
    if (cut.head<3>().dot(before) > cut[3]) return cut.head<3>().cwiseQuotient(spacing).normalized();

  const TetFactors& tf = factors[std::size_t(r.tet)];
  const auto& rest = mesh.restFrames[std::size_t(r.tet)];
  const Eigen::Vector3d q = r.point - tf.anchor;
  Eigen::Matrix3d lhs, edges;  // rows: planes[k].xyz; columns: rest edges
  Eigen::Vector3d lambda;
  for (int k = 0; k < 3; ++k) {
    lhs.row(k) = tf.planes[std::size_t(k)].head<3>().transpose();
    lambda[k] = lhs.row(k).dot(q) + tf.planes[std::size_t(k)][3];
    edges.col(k) = rest[std::size_t(k + 1)];
  }
  const Eigen::Vector3d s = rest[0] + edges * lambda;
  const Eigen::Vector3d gs = occupancyGradient(source, mesh.sourceShift, palette, s);
  if (!(gs.norm() >= kFlatOccupancyGradient)) return faceNormal(r);
  const Eigen::Vector3d gx = (lhs.transpose() * (edges.transpose() * gs)).cwiseQuotient(spacing);
  if (!(gx.norm() > 0.0)) return faceNormal(r);
  Eigen::Vector3d n = -gx.normalized();
  // Towards the camera: the ray's direction in grid-frame axes is
  // (point - eye) .* spacing.
  if (n.dot((r.point - view.eye).cwiseProduct(spacing)) > 0.0) n = -n;
  return n;
}

}  // namespace vox
