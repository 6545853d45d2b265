#include "geometry/remesh/interface_surfaces.h"

#include "geometry/cancellation.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace vox::remesh {

void InterfaceSurfaces::SpatialIndex::build(std::vector<Sample> in, double cellSize) {
  cell = cellSize;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Sample& s : in) {
    lo = lo.cwiseMin(s.p.cast<double>());
    hi = hi.cwiseMax(s.p.cast<double>());
  }
  if (in.empty()) lo = hi = Eigen::Vector3d::Zero();
  // Keep the cell array modest: coarser cells for huge extents.
  for (;;) {
    for (int a = 0; a < 3; ++a) dims[a] = std::max<std::int64_t>(1, std::int64_t((hi[a] - lo[a]) / cell) + 1);
    if (dims[0] * dims[1] * dims[2] <= std::int64_t(1) << 26) break;
    cell *= 2.0;
  }
  origin = lo;
  auto cellOf = [&](const Sample& s) {
    std::int64_t c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp<std::int64_t>(std::int64_t((double(s.p[a]) - origin[a]) / cell), 0, dims[a] - 1);
    return c[0] + dims[0] * (c[1] + dims[1] * c[2]);
  };
  start.assign(std::size_t(dims[0] * dims[1] * dims[2] + 1), 0);
  for (const Sample& s : in) ++start[std::size_t(cellOf(s) + 1)];
  for (std::size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  samples.resize(in.size());
  std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
  for (const Sample& s : in) samples[std::size_t(fill[std::size_t(cellOf(s))]++)] = s;
}

template <typename F>
void InterfaceSurfaces::SpatialIndex::near(const Eigen::Vector3d& p, const F& visit) const {
  if (samples.empty()) return;
  std::int64_t c[3];
  for (int a = 0; a < 3; ++a) c[a] = std::int64_t(std::floor((p[a] - origin[a]) / cell));
  for (std::int64_t z = std::max<std::int64_t>(0, c[2] - 1); z <= std::min(dims[2] - 1, c[2] + 1); ++z)
    for (std::int64_t y = std::max<std::int64_t>(0, c[1] - 1); y <= std::min(dims[1] - 1, c[1] + 1); ++y)
      for (std::int64_t x = std::max<std::int64_t>(0, c[0] - 1); x <= std::min(dims[0] - 1, c[0] + 1); ++x) {
        const std::int64_t k = x + dims[0] * (y + dims[1] * z);
        for (std::int64_t i = start[std::size_t(k)]; i < start[std::size_t(k) + 1]; ++i) visit(samples[std::size_t(i)]);
      }
}

InterfaceSurfaces::InterfaceSurfaces(const RemeshComplex& complex, double radius, bool hermite)
    : radius_(radius), hermite_(hermite) {
  std::vector<Sample> surface, curve;
  const auto& P = complex.positions();
  // 2-junctions: each boundary facet once, normal from the lower label.
  std::vector<std::pair<std::int32_t, std::int32_t>> boundaryEdges;
  for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (!complex.tetAlive(t) || complex.isDummyTet(t)) continue;
    const std::int32_t lt = complex.label(t);
    for (int k = 0; k < 4; ++k) {
      const std::int32_t n = complex.neighbor(t, k);
      const std::int32_t ln = complex.label(n);
      if (ln == lt || ln == kDummyLabel || lt == kDummyLabel) continue;
      const bool dummy = complex.isDummyTet(n);
      if (!dummy && lt > ln) continue;
      const Tri f = tetFace(complex.tet(t), k);
      const Eigen::Vector3d a = P[std::size_t(f[0])], b = P[std::size_t(f[1])], c = P[std::size_t(f[2])];
      Eigen::Vector3d nrm = (b - a).cross(c - a);  // outward of t
      const double area2 = nrm.norm();
      if (!(area2 > 0.0)) continue;
      nrm /= area2;
      const std::int32_t x = std::min(lt, ln), y = std::max(lt, ln);
      if (lt > ln) nrm = -nrm;
      auto [it, inserted] = surfaceIds_.try_emplace({x, y}, std::int32_t(surfaceIds_.size()));
      surface.push_back({((a + b + c) / 3.0).cast<float>(), nrm.cast<float>(), float(0.5 * area2), it->second});
      for (int e = 0; e < 3; ++e)
        boundaryEdges.push_back({std::min(f[std::size_t(e)], f[std::size_t((e + 1) % 3)]),
                                 std::max(f[std::size_t(e)], f[std::size_t((e + 1) % 3)])});
    }
  }
  // 1-junctions: boundary edges with three or more labels around them.
  sortCancellable(boundaryEdges.begin(), boundaryEdges.end());
  boundaryEdges.erase(std::unique(boundaryEdges.begin(), boundaryEdges.end()), boundaryEdges.end());
  EdgeRing ring;
  std::size_t walked = 0;
  for (const auto& [a, b] : boundaryEdges) {
    if (++walked % 4096 == 0) throwIfCancelled();
    const std::int32_t t = complex.findEdgeTet(a, b);
    complex.edgeRing(a, b, t, ring);
    LabelSet s;
    for (std::int32_t q : ring.tets) s.insert(complex.label(q));
    if (s.size() < 3 || s.contains(kDummyLabel) || s.overflow()) continue;
    const Eigen::Vector3d d = P[std::size_t(b)] - P[std::size_t(a)];
    const double len = d.norm();
    if (!(len > 0.0)) continue;
    auto [it, inserted] = curveIds_.try_emplace(std::vector<std::int32_t>(s.begin(), s.end()), std::int32_t(curveIds_.size()));
    curve.push_back({(0.5 * (P[std::size_t(a)] + P[std::size_t(b)])).cast<float>(), (d / len).cast<float>(), float(len),
                     it->second});
  }
  throwIfCancelled();
  surfaceIndex_.build(std::move(surface), 2.0 * radius_);
  throwIfCancelled();
  curveIndex_.build(std::move(curve), 2.0 * radius_);
}

bool InterfaceSurfaces::projectOnSurface(std::int32_t x, std::int32_t y, const Eigen::Vector3d& normal,
                                         Eigen::Vector3d& p) const {
  auto it = surfaceIds_.find({std::min(x, y), std::max(x, y)});
  if (it == surfaceIds_.end()) return false;
  const std::int32_t id = it->second;
  const Eigen::Vector3d hint = x < y ? normal : Eigen::Vector3d(-normal);
  const double inv = 1.0 / (radius_ * radius_), reach2 = 4.0 * radius_ * radius_;
  Eigen::Vector3d q = p;
  for (int iteration = 0; iteration < 3; ++iteration) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero(), h = Eigen::Vector3d::Zero();
    double wsum = 0.0;
    surfaceIndex_.near(q, [&](const Sample& s) {
      if (s.id != id) return;
      const Eigen::Vector3d sp = s.p.cast<double>(), sn = s.n.cast<double>();
      if (sn.dot(hint) <= 0.0) return;
      const double d2 = (sp - q).squaredNorm();
      if (d2 > reach2) return;
      const double w = double(s.weight) * std::exp(-d2 * inv);
      c += w * sp;
      n += w * sn;
      h += w * (q - sn * sn.dot(q - sp));
      wsum += w;
    });
    if (!(wsum > 0.0) || !(n.norm() > 0.0)) return iteration > 0 ? (p = q, true) : false;
    if (hermite_) {
      q = h / wsum;
    } else {
      c /= wsum;
      n.normalize();
      q -= n * (q - c).dot(n);
    }
  }
  p = q;
  return true;
}

bool InterfaceSurfaces::projectOnCurve(const LabelSet& labels, Eigen::Vector3d& p) const {
  auto it = curveIds_.find(std::vector<std::int32_t>(labels.begin(), labels.end()));
  if (it == curveIds_.end()) return false;
  const std::int32_t id = it->second;
  const double inv = 1.0 / (radius_ * radius_), reach2 = 4.0 * radius_ * radius_;
  Eigen::Vector3d q = p;
  for (int iteration = 0; iteration < 2; ++iteration) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    double wsum = 0.0;
    curveIndex_.near(q, [&](const Sample& s) {
      if (s.id != id) return;
      const Eigen::Vector3d sp = s.p.cast<double>(), sd = s.n.cast<double>();
      const double d2 = (sp - q).squaredNorm();
      if (d2 > reach2) return;
      const double w = double(s.weight) * std::exp(-d2 * inv);
      c += w * sp;
      m += w * sd * sd.transpose();
      wsum += w;
    });
    if (!(wsum > 0.0)) return iteration > 0 ? (p = q, true) : false;
    c /= wsum;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m);
    const Eigen::Vector3d dir = eig.eigenvectors().col(2);
    q = c + dir * dir.dot(q - c);
  }
  p = q;
  return true;
}

}  // namespace vox::remesh
