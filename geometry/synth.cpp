#include "geometry/synth.h"

#include "geometry/error.h"

#include <cmath>
#include <functional>

namespace vox {

SynthKind synthKindFromName(const std::string& name) {
  if (name == "spheres") return SynthKind::NestedSpheres;
  if (name == "junctions") return SynthKind::JunctionSphere;
  if (name == "stick") return SynthKind::StickFigure;
  throw InputError("synth", "unknown kind '" + name + "' (expected spheres, junctions or stick)");
}

const char* synthKindName(SynthKind kind) {
  switch (kind) {
    case SynthKind::NestedSpheres: return "spheres";
    case SynthKind::JunctionSphere: return "junctions";
    case SynthKind::StickFigure: return "stick";
  }
  return "?";
}

namespace {

// Fills a grid by evaluating `f` at every voxel centre in normalized
// coordinates (the longest axis spans [0, 1]).
LabelGrid fill(Index3 dims, double spacing, const std::function<Label(double, double, double)>& f) {
  GridGeometry g;
  g.dims = dims;
  g.spacing = Eigen::Vector3d::Constant(spacing);
  LabelGrid grid(g);
  const double n = double(std::max({dims[0], dims[1], dims[2]}));
  for (std::int64_t k = 0; k < dims[2]; ++k)
    for (std::int64_t j = 0; j < dims[1]; ++j)
      for (std::int64_t i = 0; i < dims[0]; ++i)
        grid.at(i, j, k) = f((double(i) + 0.5) / n, (double(j) + 0.5) / n, (double(k) + 0.5) / n);
  return grid;
}

bool inBox(double x, double y, double z, double x0, double x1, double y0, double y1, double z0, double z1) {
  return x >= x0 && x < x1 && y >= y0 && y < y1 && z >= z0 && z < z1;
}

}  // namespace

LabelGrid synthesize(SynthKind kind, int size) {
  if (size < 8) throw InputError("synth", "size must be at least 8 voxels");
  const std::int64_t n = size;
  switch (kind) {
    case SynthKind::NestedSpheres:
      return fill({n, n, n}, 1.0, [](double x, double y, double z) -> Label {
        const double r = std::sqrt((x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5) + (z - 0.5) * (z - 0.5));
        return r < 0.15 ? 3 : r < 0.3 ? 2 : r < 0.42 ? 1 : 0;
      });
    case SynthKind::JunctionSphere:
      // Upper half: three 120-degree sectors (1, 2, 3); lower half: two halves
      // (4, 5). Their junction curves meet at the centre and on the surface.
      return fill({n, n, n}, 1.0, [](double x, double y, double z) -> Label {
        const double dx = x - 0.5, dy = y - 0.5, dz = z - 0.5;
        if (dx * dx + dy * dy + dz * dz >= 0.42 * 0.42) return 0;
        if (dz < 0) return dx < 0 ? 4 : 5;
        const double a = std::atan2(dy, dx) + M_PI;  // [0, 2 pi]
        return Label(1 + std::min(2, int(a / (2.0 * M_PI / 3.0))));
      });
    case SynthKind::StickFigure: {
      // A figure standing along z, arms hanging along the trunk's sides and
      // touching it (no background between them), as in the ICRP phantoms.
      const std::int64_t nx = std::max<std::int64_t>(8, n * 6 / 10), ny = std::max<std::int64_t>(8, n * 3 / 10);
      return fill({nx, ny, n}, 2.0, [](double x, double y, double z) -> Label {
        const double cx = 0.3, cy = 0.15;
        const double trunkHalfW = 0.12, trunkHalfD = 0.07, armW = 0.05;
        const double dy = y - cy;
        // Head and neck.
        const double hz = z - 0.89, hx = x - cx;
        if (hx * hx + dy * dy + hz * hz < 0.075 * 0.075) return 2;
        if (inBox(x, y, z, cx - 0.03, cx + 0.03, cy - 0.03, cy + 0.03, 0.78, 0.84)) return 2;
        // Trunk with a heart.
        if (inBox(x, y, z, cx - trunkHalfW, cx + trunkHalfW, cy - trunkHalfD, cy + trunkHalfD, 0.45, 0.8)) {
          const double hx2 = x - (cx + 0.03), hz2 = z - 0.68;
          return hx2 * hx2 + dy * dy + hz2 * hz2 < 0.04 * 0.04 ? 7 : 1;
        }
        // Arms touch the trunk: x ranges start exactly at the trunk's sides.
        const double armY0 = cy - 0.04, armY1 = cy + 0.04;
        for (int side = 0; side < 2; ++side) {
          const double x0 = side == 0 ? cx - trunkHalfW - armW : cx + trunkHalfW;
          if (inBox(x, y, z, x0, x0 + armW, armY0, armY1, 0.42, 0.79)) {
            const double bx = x - (x0 + armW / 2), by = dy;
            return bx * bx + by * by < 0.012 * 0.012 ? Label(8 + side) : Label(3 + side);
          }
        }
        // Legs with a gap between them.
        if (inBox(x, y, z, cx - 0.1, cx - 0.015, cy - 0.05, cy + 0.05, 0.03, 0.45)) return 5;
        if (inBox(x, y, z, cx + 0.015, cx + 0.1, cy - 0.05, cy + 0.05, 0.03, 0.45)) return 6;
        return 0;
      });
    }
  }
  throw InputError("synth", "unknown kind");
}

OrganTable synthOrganTable(SynthKind kind) {
  OrganTable t;
  auto add = [&](int id, const char* name, double density) { t.add({id, name, 1, density}); };
  switch (kind) {
    case SynthKind::NestedSpheres:
      add(1, "Outer shell", 1.0);
      add(2, "Middle shell", 1.5);
      add(3, "Core", 2.0);
      break;
    case SynthKind::JunctionSphere:
      for (int l = 1; l <= 5; ++l) add(l, ("Sector " + std::to_string(l)).c_str(), 1.0 + 0.1 * l);
      break;
    case SynthKind::StickFigure:
      add(1, "Trunk", 1.05);
      add(2, "Head", 1.05);
      add(3, "Muscle, arms, right", 1.05);
      add(4, "Muscle, arms, left", 1.05);
      add(5, "Muscle, legs, right", 1.05);
      add(6, "Muscle, legs, left", 1.05);
      add(7, "Heart", 1.06);
      add(8, "Humerus, right", 1.9);
      add(9, "Humerus, left", 1.9);
      break;
  }
  return t;
}

}  // namespace vox
