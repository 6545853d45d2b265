#include "geometry/synth.h"

#include "geometry/error.h"

#include <cmath>
#include <functional>

namespace vox {

SynthKind synthKindFromName(const std::string& name) {
  if (name == "spheres") return SynthKind::NestedSpheres;
  if (name == "junctions") return SynthKind::JunctionSphere;
  if (name == "stick") return SynthKind::StickFigure;
  if (name == "skeleton") return SynthKind::SkeletonFigure;
  throw InputError("synth", "unknown kind '" + name + "' (expected spheres, junctions, stick or skeleton)");
}

const char* synthKindName(SynthKind kind) {
  switch (kind) {
    case SynthKind::NestedSpheres: return "spheres";
    case SynthKind::JunctionSphere: return "junctions";
    case SynthKind::StickFigure: return "stick";
    case SynthKind::SkeletonFigure: return "skeleton";
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

// A cylinder along z through (cx, cy) of radius r between z0 and z1.
bool inRod(double x, double y, double z, double cx, double cy, double r, double z0, double z1) {
  return (x - cx) * (x - cx) + (y - cy) * (y - cy) < r * r && z >= z0 && z < z1;
}

bool inBall(double x, double y, double z, double cx, double cy, double cz, double r) {
  return (x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz) < r * r;
}

// Labels of the skeleton figure (synthOrganTable names them).
enum SkeletonLabel : Label {
  kTrunkTissue = 1, kHeadTissue, kArmMuscle, kLegMuscle, kBrain, kHumerus, kForearmBones, kHandBones, kClavicle, kScapula,
  kCervical, kThoracic, kLumbar, kSacrum, kPelvis, kSternum, kFemur, kLowerLegBones, kFootBones, kCranium, kRibs, kArmSkin, kTrunkSkin
};

// The stick figure's outline (head, neck, trunk, arms touching the trunk,
// legs with a gap) with bones inside: spine, sternum and pelvis on the
// midline, shoulder girdles, and per limb three bones separated by joint
// gaps; humeri and femora end in ball heads, their distal ends widen from
// side to side (epicondyles, condyles). Below the shoulders arms and trunk
// touch skin on skin (a voxel of each), as in the ICRP phantoms; `voxel` is
// the voxel size in normalized units.
Label skeletonFigure(double x, double y, double z, double voxel) {
  const SkeletonFigureBones b;
  const double cx = 0.3, cy = 0.15;
  // Head and neck.
  if (inBall(x, y, z, cx, cy, 0.89, 0.075)) {
    const double r = std::sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - 0.89) * (z - 0.89));
    return r < 0.05 ? kBrain : r < 0.062 ? kCranium : kHeadTissue;
  }
  if (inBox(x, y, z, cx - 0.03, cx + 0.03, cy - 0.03, cy + 0.03, 0.78, 0.84))
    return inRod(x, y, z, cx, 0.165, 0.012, 0.785, 0.83) ? kCervical : kHeadTissue;
  // Trunk: spine behind, sternum in front, pelvis and sacrum low, girdles high.
  if (inBox(x, y, z, cx - 0.12, cx + 0.12, cy - 0.07, cy + 0.07, 0.45, 0.8)) {
    if (inRod(x, y, z, cx, 0.185, 0.014, 0.62, 0.775)) return kThoracic;
    if (inRod(x, y, z, cx, 0.185, 0.014, 0.5, 0.61)) return kLumbar;
    if (inBox(x, y, z, 0.28, 0.32, 0.17, 0.2, 0.455, 0.49)) return kSacrum;
    if (inBox(x, y, z, 0.21, 0.39, 0.11, 0.16, 0.46, 0.5)) return kPelvis;
    if (inBox(x, y, z, 0.29, 0.31, 0.09, 0.105, 0.63, 0.76)) return kSternum;
    if (inBox(x, y, z, 0.19, 0.28, 0.1, 0.12, 0.77, 0.785) || inBox(x, y, z, 0.32, 0.41, 0.1, 0.12, 0.77, 0.785)) return kClavicle;
    if (inBox(x, y, z, 0.19, 0.25, 0.195, 0.21, 0.66, 0.77) || inBox(x, y, z, 0.35, 0.41, 0.195, 0.21, 0.66, 0.77)) return kScapula;
    // Ribs: elliptic hoops every 0.03 between the sternum and the spine.
    const double e = ((x - cx) / 0.1) * ((x - cx) / 0.1) + ((y - cy) / 0.058) * ((y - cy) / 0.058);
    if (z >= 0.6 && z < 0.76 && std::fmod(z - 0.6, 0.03) < 0.01 && e >= 0.8 && e < 1.0) return kRibs;
    if (z < 0.7 && (x < cx - 0.12 + voxel || x >= cx + 0.12 - voxel) && y >= 0.11 && y < 0.19) return kTrunkSkin;
    return kTrunkTissue;
  }
  for (int side = 0; side < 2; ++side) {
    // Arm: humerus (ball head, shaft, epicondyles), forearm bones, hand.
    const double ax = b.humeralHeadX[side];
    if (inBox(x, y, z, ax - 0.035, ax + 0.035, 0.11, 0.19, 0.42, 0.79)) {
      if (inBall(x, y, z, ax, b.humeralHeadY, b.humeralHeadZ, b.humeralHeadRadius) || inRod(x, y, z, ax, cy, 0.01, 0.635, b.humeralHeadZ) ||
          inBox(x, y, z, ax - 0.025, ax + 0.025, 0.142, 0.158, 0.62, 0.64))
        return kHumerus;
      if (inRod(x, y, z, ax, cy, 0.01, 0.475, 0.605)) return kForearmBones;
      if (inBox(x, y, z, ax - 0.012, ax + 0.012, 0.13, 0.17, 0.43, 0.462)) return kHandBones;
      const bool againstTrunk = side == 0 ? x >= ax + 0.035 - voxel : x < ax - 0.035 + voxel;
      return againstTrunk && z >= 0.45 && z < 0.7 ? kArmSkin : kArmMuscle;
    }
    // Leg: femur (ball head, shaft, condyles), lower-leg bones, foot.
    const double lx = b.femoralHeadX[side];
    if (inBox(x, y, z, lx - 0.0425, lx + 0.0425, 0.1, 0.2, 0.03, 0.45)) {
      if (inBall(x, y, z, lx, b.femoralHeadY, b.femoralHeadZ, b.femoralHeadRadius) || inRod(x, y, z, lx, cy, 0.012, 0.28, b.femoralHeadZ) ||
          inBox(x, y, z, lx - 0.03, lx + 0.03, 0.135, 0.165, 0.26, 0.285))
        return kFemur;
      if (inRod(x, y, z, lx, cy, 0.012, 0.075, 0.245)) return kLowerLegBones;
      if (inBox(x, y, z, lx - 0.02, lx + 0.02, 0.105, 0.195, 0.035, 0.06)) return kFootBones;
      return kLegMuscle;
    }
  }
  return 0;
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
    case SynthKind::SkeletonFigure: {
      const std::int64_t nx = std::max<std::int64_t>(8, n * 6 / 10), ny = std::max<std::int64_t>(8, n * 3 / 10);
      const double voxel = 1.0 / double(n);
      return fill({nx, ny, n}, 2.0, [voxel](double x, double y, double z) { return skeletonFigure(x, y, z, voxel); });
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
    case SynthKind::SkeletonFigure:
      add(kTrunkTissue, "Residual tissue, trunk", 0.95);
      add(kHeadTissue, "Residual tissue, head", 0.95);
      add(kArmMuscle, "Muscle, arms", 1.05);
      add(kLegMuscle, "Muscle, legs", 1.05);
      add(kBrain, "Brain", 1.04);
      add(kHumerus, "Humeri, cortical", 1.92);
      add(kForearmBones, "Ulnae and radii, cortical", 1.92);
      add(kHandBones, "Wrists and hand bones, cortical", 1.92);
      add(kClavicle, "Clavicles, cortical", 1.92);
      add(kScapula, "Scapulae, cortical", 1.92);
      add(kCervical, "Cervical spine, cortical", 1.92);
      add(kThoracic, "Thoracic spine, cortical", 1.92);
      add(kLumbar, "Lumbar spine, cortical", 1.92);
      add(kSacrum, "Sacrum, cortical", 1.92);
      add(kPelvis, "Pelvis, cortical", 1.92);
      add(kSternum, "Sternum, cortical", 1.92);
      add(kFemur, "Femora, cortical", 1.92);
      add(kLowerLegBones, "Tibiae, fibulae and patellae, cortical", 1.92);
      add(kFootBones, "Ankles and foot bones, cortical", 1.92);
      add(kCranium, "Cranium, cortical", 1.92);
      add(kRibs, "Ribs, cortical", 1.92);
      add(kArmSkin, "Skin, arms", 1.09);
      add(kTrunkSkin, "Skin, trunk", 1.09);
      break;
  }
  return t;
}

}  // namespace vox
