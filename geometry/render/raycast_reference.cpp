#include "geometry/render/raycast_reference.h"

#include "geometry/parallel.h"
#include "geometry/render/surface_normals.h"
#include "shaders/shared/interface.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vox {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// 3D DDA over unit cells centred on integers (thesis Algorithm 2). Cell-face
// crossings are recomputed from the integer cell, so no error accumulates.
struct Dda {
  Eigen::Vector3d e, d, inv;
  int step[3] = {0, 0, 0};
  Eigen::Vector3d cell{0, 0, 0};  // integer values
  double tEnter = 0.0;
  int axis = 0;  // axis of the face through which the ray entered `cell`

  Dda(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) : e(origin), d(direction) {
    for (int a = 0; a < 3; ++a) {
      step[a] = d[a] > 0.0 ? 1 : (d[a] < 0.0 ? -1 : 0);
      inv[a] = step[a] != 0 ? 1.0 / d[a] : 0.0;
    }
  }
  double tNext(int a) const { return step[a] == 0 ? kInf : (cell[a] + 0.5 * step[a] - e[a]) * inv[a]; }
  double tExit() const { return std::min({tNext(0), tNext(1), tNext(2)}); }
  void start(double t0) {
    const Eigen::Vector3d p = e + t0 * d;
    for (int a = 0; a < 3; ++a) cell[a] = std::floor(p[a] + 0.5);
    tEnter = t0;
    // The face crossed last before t0 is the one the ray entered through.
    double last = -kInf;
    for (int a = 0; a < 3; ++a) {
      if (step[a] == 0) continue;
      const double tPrev = (cell[a] - 0.5 * step[a] - e[a]) * inv[a];
      if (tPrev > last) {
        last = tPrev;
        axis = a;
      }
    }
  }
  void advance() {
    int a = 0;
    double t = tNext(0);
    for (int b = 1; b < 3; ++b)
      if (tNext(b) < t) {
        t = tNext(b);
        a = b;
      }
    cell[a] += step[a];
    tEnter = t;
    axis = a;
  }
};

struct Tracer {
  const LabelGrid& source;
  const RaycastMesh& mesh;
  const RaycastFrame& frame;
  const std::vector<TetFactors>& factors;
  const RaycastView& view;
  const Palette& palette;
  const RaycastLimits& limits;
  RaycastStats& stats;

  // Visibility walk (thesis 5.2.3, "Neighborhood search"): true when `tet`
  // ends on a tet containing p; lambda then holds p's barycentric coordinates.
  bool locate(const Eigen::Vector3d& p, std::int32_t& tet, double lambda[4]) const {
    for (int s = 0; s < limits.maxWalkSteps; ++s) {
      ++stats.walkSteps;
      const TetFactors& f = factors[std::size_t(tet)];
      const Eigen::Vector3d q = p - f.anchor;
      lambda[1] = f.planes[0].head<3>().dot(q) + f.planes[0][3];
      lambda[2] = f.planes[1].head<3>().dot(q) + f.planes[1][3];
      lambda[3] = f.planes[2].head<3>().dot(q) + f.planes[2][3];
      lambda[0] = 1.0 - lambda[1] - lambda[2] - lambda[3];
      // Cross the face with the most negative coordinate among those with a
      // neighbour: on a non-convex mesh the most negative one may be a
      // boundary face while the point lies inside, behind another face.
      const auto& nb = mesh.neighbors[std::size_t(tet)];
      int k = -1;
      bool inside = true;
      for (int j = 0; j < 4; ++j) {
        if (lambda[j] >= -kInsideTolerance) continue;
        inside = false;
        if (nb[std::size_t(j)] >= 0 && (k < 0 || lambda[j] < lambda[k])) k = j;
      }
      if (inside) return true;
      if (k < 0) return false;
      tet = nb[std::size_t(k)];
    }
    return false;
  }

  Label fetch(std::int32_t tet, const double lambda[4]) const {
    const auto& r = mesh.restFrames[std::size_t(tet)];
    const Eigen::Vector3d s = r[0] + lambda[1] * r[1] + lambda[2] * r[2] + lambda[3] * r[3];
    const auto i = std::int64_t(std::floor(s[0] + 0.5)) + mesh.sourceShift[0];
    const auto j = std::int64_t(std::floor(s[1] + 0.5)) + mesh.sourceShift[1];
    const auto k = std::int64_t(std::floor(s[2] + 0.5)) + mesh.sourceShift[2];
    return source.atOr(i, j, k, 0);
  }

  FaceHit entryAfter(const Eigen::Vector3d& e, const Eigen::Vector3d& d, const FaceHit& after) const {
    ++stats.entryQueries;
    return firstEntryAfter(frame.bvh, mesh.boundary, frame.positions, e, d, after.t, after.face);
  }

  RayResult trace(const Eigen::Vector3d& e, const Eigen::Vector3d& d) const {
    ++stats.rays;
    RayResult res;
    // 1. Clip to the cells of G' and to the cutting planes' kept side.
    double tLo = 0.0, tHi = kInf;
    for (int a = 0; a < 3; ++a) {
      if (d[a] != 0.0) {
        double t0 = (frame.cellsLo[a] - e[a]) / d[a], t1 = (frame.cellsHi[a] - e[a]) / d[a];
        if (t0 > t1) std::swap(t0, t1);
        tLo = std::max(tLo, t0);
        tHi = std::min(tHi, t1);
      } else if (e[a] < frame.cellsLo[a] || e[a] > frame.cellsHi[a]) {
        return res;
      }
    }
    for (const Eigen::Vector4d& cut : view.cuts) {
      // A crossed cell's centre is within half a cell (per axis) of the ray.
      const Eigen::Vector3d n = cut.head<3>();
      const double nd = n.dot(d);
      const double bound = cut[3] + 0.5 * n.cwiseAbs().sum() - n.dot(e);
      if (nd > 0.0) tHi = std::min(tHi, bound / nd);
      else if (nd < 0.0) tLo = std::max(tLo, bound / nd);
      else if (bound < 0.0) return res;
    }
    if (!(tLo <= tHi)) return res;

    // 2. First entry into the deformed TM.
    FaceHit key = entryAfter(e, d, FaceHit{0.0, -1});
    if (!key.valid()) return res;
    const double margin = 0.5 * std::sqrt(3.0) / d.norm();
    // Cells whose centres are inside the TM can be crossed before the entry
    // point, by up to half a cell diagonal away from the entry face's plane:
    // along a ray that meets the face at a grazing angle, that is far.
    auto entryMargin = [&](const FaceHit& h) {
      const Tri& f = mesh.boundary[std::size_t(h.face)].vertices;
      const Eigen::Vector3d& a = frame.positions[std::size_t(f[0])];
      const Eigen::Vector3d n = (frame.positions[std::size_t(f[1])] - a).cross(frame.positions[std::size_t(f[2])] - a);
      const double grazing = std::abs(n.dot(d));  // |n . d| / |n| = |cos| |d|
      if (!(grazing > 0.0)) return kMaxEntryMarginCells * margin;
      return std::min(kMaxEntryMarginCells * margin, 0.5 * std::sqrt(3.0) * n.norm() / grazing);
    };
    std::int32_t tet = mesh.boundary[std::size_t(key.face)].tet;
    int entries = 1;
    FaceHit next;
    bool nextKnown = false;
    auto queryNext = [&] {
      if (!nextKnown) next = entryAfter(e, d, key);
      nextKnown = true;
    };
    double failStart = kInf;  // tEnter of the first cell of the current run of failed locations
    auto takeNext = [&] {
      key = next;
      tet = mesh.boundary[std::size_t(key.face)].tet;
      nextKnown = false;
      failStart = kInf;
      ++entries;
    };

    // 3. Cells in ray order.
    Dda dda(e, d);
    dda.start(std::max(key.t - entryMargin(key), tLo));
    const std::int64_t maxCells = 4 * (frame.output.dims[0] + frame.output.dims[1] + frame.output.dims[2]) + 64;
    for (std::int64_t n = 0; n < maxCells && dda.tEnter <= tHi; ++n) {
      ++stats.cells;
      const Eigen::Vector3d& c = dda.cell;
      bool removed = false;
      for (const Eigen::Vector4d& cut : view.cuts) removed |= cut.head<3>().dot(c) > cut[3];
      if (!removed) {
        double lambda[4];
        bool found = false, rayInside = false;
        const double mid = 0.5 * (dda.tEnter + dda.tExit());
        for (;;) {
          const std::int32_t start = tet;
          found = locate(c, tet, lambda);
          if (found) break;
          // 4. The walk left the mesh. If the ray itself is inside the mesh in
          // this cell, the centre is outside (the ray grazes the surface) or
          // across a concavity from where the walk went: walk along the ray
          // into the cell first, then to the centre.
          std::int32_t rayTet = start;
          if (mid > key.t && locate(e + mid * d, rayTet, lambda)) {
            rayInside = true;
            tet = rayTet;
            found = locate(c, rayTet, lambda);
            if (found) tet = rayTet;
            break;
          }
          // The ray is outside: retry from the next entry face once the ray
          // has (almost) reached it.
          if (dda.tEnter <= key.t) break;
          queryNext();
          if (!next.valid() || next.t - entryMargin(next) > dda.tExit() || entries >= limits.maxEntries) break;
          takeNext();
        }
        if (found) {
          failStart = kInf;
          const Label label = fetch(tet, lambda);
          if (palette.visible(label)) {
            res.hit = true;
            res.cell = {std::int64_t(c[0]), std::int64_t(c[1]), std::int64_t(c[2])};
            res.label = label;
            res.axis = dda.axis;
            res.step = dda.step[dda.axis];
            res.t = dda.tEnter;
            res.point = e + dda.tEnter * d;
            res.tet = tet;
            ++stats.hits;
            return res;
          }
        } else {
          ++stats.failedWalks;
          // A cell counts as outside only when the ray is outside in it, past
          // the entry point (before it, in the margin, failures are expected).
          if (rayInside) failStart = kInf;
          else if (failStart == kInf && dda.tEnter > key.t) failStart = dda.tEnter;
        }
      }
      if (failStart != kInf && dda.tExit() > std::max(failStart, key.t) + 2.0 * margin) {
        // Outside the mesh for two cells: jump to the next entry, if any.
        queryNext();
        if (!next.valid() || entries >= limits.maxEntries) return res;
        if (next.t - entryMargin(next) > dda.tExit()) {
          takeNext();
          dda.start(key.t - entryMargin(key));
          continue;
        }
      }
      dda.advance();
    }
    return res;
  }
};

}  // namespace

RayResult traceRayReference(const LabelGrid& source, const RaycastMesh& mesh, const RaycastFrame& frame,
                            const std::vector<TetFactors>& factors, const RaycastView& view, const Palette& palette,
                            const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, const RaycastLimits& limits,
                            RaycastStats* stats) {
  RaycastStats local;
  const Tracer tracer{source, mesh, frame, factors, view, palette, limits, stats ? *stats : local};
  return tracer.trace(origin, direction);
}

Rgb shadeRay(const RayResult& r, const Eigen::Vector3d& normal, const RaycastView& view, const Palette& palette,
             const RaycastShading& shading) {
  if (!r.hit) return shading.background;
  // shaders/shared/shading.glsl's surfaceShade: the normal under the
  // headlight and the fill light.
  const double head = std::max(0.0, normal.dot(view.headlight));
  const double side = std::max(0.0, normal.dot(view.light));
  const double light =
      std::min(1.0, shading.ambient + (1.0 - shading.ambient) * (VOX_SHADE_HEADLIGHT * head + VOX_SHADE_FILL * side));
  const double depth = view.depthFar > view.depthNear ? (r.t - view.depthNear) / (view.depthFar - view.depthNear) : 0.0;
  const double shade = light * (1.0 - VOX_SHADE_DEPTH * std::clamp(depth, 0.0, 1.0));
  const Rgb albedo = palette.color(r.label);
  auto q = [&](std::uint8_t c) { return std::uint8_t(std::min(255.0, std::floor(double(c) * shade + 0.5))); };
  return {q(albedo.r), q(albedo.g), q(albedo.b)};
}

RgbImage raycastReference(const LabelGrid& source, const RaycastMesh& mesh, const RaycastFrame& frame, const RaycastView& view,
                          const Palette& palette, const RaycastShading& shading, const RaycastLimits& limits,
                          RaycastStats* stats) {
  const std::vector<TetFactors> factors = computeTetFactors(mesh, frame);
  const int w = view.camera.width, h = view.camera.height;
  RgbImage image(w, h);
  // Rows are independent; each keeps its own statistics, summed at the end.
  std::vector<RaycastStats> perRow(static_cast<std::size_t>(h));
  parallelFor(h, 0, [&](std::int64_t y) {
    const Tracer tracer{source, mesh, frame, factors, view, palette, limits, perRow[std::size_t(y)]};
    for (int x = 0; x < w; ++x) {
      const RayResult r = tracer.trace(view.eye, view.direction(x, int(y)));
      const Eigen::Vector3d normal = r.hit ? surfaceNormal(r, source, mesh, frame, factors, view, palette, shading.normals)
                                           : Eigen::Vector3d::Zero();
      image.at(x, int(y)) = shadeRay(r, normal, view, palette, shading);
    }
  });
  if (stats) {
    for (const RaycastStats& s : perRow) {
      stats->rays += s.rays;
      stats->hits += s.hits;
      stats->cells += s.cells;
      stats->walkSteps += s.walkSteps;
      stats->entryQueries += s.entryQueries;
      stats->failedWalks += s.failedWalks;
    }
  }
  return image;
}

std::vector<std::uint64_t> visibleLabelPixels(const LabelGrid& source, const RaycastMesh& mesh, const RaycastFrame& frame,
                                              const RaycastView& view, const Palette& palette, int stride) {
  const std::vector<TetFactors> factors = computeTetFactors(mesh, frame);
  const int w = view.camera.width, h = view.camera.height;
  const int rows = (h + stride - 1) / stride;
  std::vector<std::vector<std::uint64_t>> perRow(std::size_t(rows), std::vector<std::uint64_t>(palette.size(), 0));
  std::vector<RaycastStats> stats(static_cast<std::size_t>(rows));
  const RaycastLimits limits;
  parallelFor(rows, 0, [&](std::int64_t r) {
    const Tracer tracer{source, mesh, frame, factors, view, palette, limits, stats[std::size_t(r)]};
    const int y = int(r) * stride;
    for (int x = 0; x < w; x += stride) {
      const RayResult hit = tracer.trace(view.eye, view.direction(x, y));
      if (hit.hit) ++perRow[std::size_t(r)][hit.label];
    }
  });
  std::vector<std::uint64_t> counts(palette.size(), 0);
  for (const auto& row : perRow)
    for (std::size_t l = 0; l < counts.size(); ++l) counts[l] += row[l];
  return counts;
}

}  // namespace vox
