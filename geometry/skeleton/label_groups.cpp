#include "geometry/skeleton/label_groups.h"

#include "geometry/error.h"
#include "geometry/parallel.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <vector>

namespace vox {

namespace {

constexpr std::array<const char*, kLabelGroupCount> kNames = {"trunk", "head", "right_arm", "left_arm", "right_leg", "left_leg"};

LabelGroup limbPart(Limb limb, BodySide side) {
  if (limb == Limb::Arm) return side == BodySide::Left ? LabelGroup::LeftArm : LabelGroup::RightArm;
  return side == BodySide::Left ? LabelGroup::LeftLeg : LabelGroup::RightLeg;
}

// Assigns a side to every voxel of `pending` (a limb whose organ names carry
// no side): whole 6-connected pieces by their centroid, or voxel by voxel
// for pieces straddling the midline.
void assignSides(LabelGrid& groups, std::vector<std::uint8_t>& pending, Limb limb, double midlineX,
                 const LabelGroupOptions& options) {
  const GridGeometry& g = groups.geometry();
  const auto sideOf = [&](bool lowX) { return lowX == options.rightSideAtLowX ? BodySide::Right : BodySide::Left; };
  std::vector<std::int64_t> piece, stack;
  for (std::int64_t seed = 0; seed < g.voxelCount(); ++seed) {
    if (!pending[seed]) continue;
    piece.clear();
    stack.assign(1, seed);
    pending[seed] = 0;
    std::int64_t low = 0;
    while (!stack.empty()) {
      const std::int64_t v = stack.back();
      stack.pop_back();
      piece.push_back(v);
      const Index3 c = g.ijk(v);
      low += g.voxelCenter(c[0], c[1], c[2]).x() < midlineX;
      static constexpr int kSteps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
      for (const auto& s : kSteps) {
        const std::int64_t i = c[0] + s[0], j = c[1] + s[1], k = c[2] + s[2];
        if (!g.contains(i, j, k)) continue;
        const std::int64_t n = g.index(i, j, k);
        if (pending[n]) {
          pending[n] = 0;
          stack.push_back(n);
        }
      }
    }
    const double size = double(piece.size());
    const double minority = double(std::min<std::int64_t>(low, std::int64_t(piece.size()) - low));
    const bool perVoxel = minority >= options.straddleFraction * size;
    const BodySide pieceSide = sideOf(2 * low >= std::int64_t(piece.size()));
    for (const std::int64_t v : piece) {
      const Index3 c = g.ijk(v);
      const BodySide side = perVoxel ? sideOf(g.voxelCenter(c[0], c[1], c[2]).x() < midlineX) : pieceSide;
      groups.labels()[v] = Label(limbPart(limb, side));
    }
  }
}

}  // namespace

const char* labelGroupName(LabelGroup part) {
  const int i = int(part) - 1;
  return i >= 0 && i < kLabelGroupCount ? kNames[i] : "?";
}

LabelGroup labelGroupFromName(const std::string& name, const std::string& source) {
  std::string n;
  for (const unsigned char c : name) n += c == '-' ? '_' : char(std::tolower(c));
  // "arm_right" -> "right_arm"
  const auto us = n.find('_');
  if (us != std::string::npos) {
    const std::string a = n.substr(0, us), b = n.substr(us + 1);
    if (b == "left" || b == "right") n = b + "_" + a;
  }
  for (int i = 0; i < kLabelGroupCount; ++i)
    if (n == kNames[i]) return LabelGroup(i + 1);
  std::string accepted;
  for (const char* k : kNames) accepted += std::string(accepted.empty() ? "" : ", ") + k;
  throw InputError(source, "unknown body part '" + name + "' (expected one of " + accepted + ")");
}

OrganLabelGroup classifyOrganName(const std::string& name) {
  const std::vector<std::string> words = organNameWords(name);
  OrganLabelGroup part;
  if (anyWordStartsWith(words, {"arm", "humer", "uln", "radi", "wrist", "hand"})) part.limb = Limb::Arm;
  else if (anyWordStartsWith(words, {"leg", "femor", "femur", "tibi", "fibul", "patell", "ankle", "foot", "feet"}))
    part.limb = Limb::Leg;
  else if (anyWordStartsWith(words, {"head", "cranium", "brain", "mandible", "eye", "lens", "teeth", "nasal", "oral",
                                     "tongue", "saliva", "pituitary", "tonsil"}))
    part.limb = Limb::Head;
  const bool left = std::find(words.begin(), words.end(), "left") != words.end();
  const bool right = std::find(words.begin(), words.end(), "right") != words.end();
  if (left != right) part.side = left ? BodySide::Left : BodySide::Right;
  return part;
}

LabelGrid labelGroupGrid(const LabelGrid& grid, const OrganTable& organs, const LabelGroupOptions& options) {
  const GridGeometry& g = grid.geometry();
  std::vector<OrganLabelGroup> byLabel(std::size_t(grid.maxLabel()) + 1);
  for (std::size_t l = 1; l < byLabel.size(); ++l)
    if (const Organ* o = organs.find(int(l))) byLabel[l] = classifyOrganName(o->name);

  LabelGrid groups(g, 0);
  std::vector<std::uint8_t> pendingArm(std::size_t(g.voxelCount()), 0), pendingLeg(pendingArm.size(), 0);
  double trunkX = 0.0, allX = 0.0;
  std::int64_t trunkCount = 0, allCount = 0;
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const std::int64_t v = g.index(i, j, k);
        const Label l = grid.labels()[v];
        if (l == 0) continue;
        const OrganLabelGroup part = byLabel[l];
        const double x = g.voxelCenter(i, j, k).x();
        allX += x;
        ++allCount;
        switch (part.limb) {
          case Limb::Trunk:
            groups.labels()[v] = Label(LabelGroup::Trunk);
            trunkX += x;
            ++trunkCount;
            break;
          case Limb::Head: groups.labels()[v] = Label(LabelGroup::Head); break;
          case Limb::Arm:
          case Limb::Leg:
            if (part.side != BodySide::Unknown) groups.labels()[v] = Label(limbPart(part.limb, part.side));
            else (part.limb == Limb::Arm ? pendingArm : pendingLeg)[v] = 1;
            break;
        }
      }
  const double midlineX = trunkCount > 0 ? trunkX / double(trunkCount) : allCount > 0 ? allX / double(allCount) : 0.0;
  assignSides(groups, pendingArm, Limb::Arm, midlineX, options);
  assignSides(groups, pendingLeg, Limb::Leg, midlineX, options);
  return groups;
}

LabelGrid binaryGroupGrid(const LabelGrid& grid) {
  LabelGrid b(grid.geometry(), 0);
  std::transform(grid.labels().begin(), grid.labels().end(), b.labels().begin(), [](Label l) { return Label(l != 0); });
  return b;
}

std::vector<Label> nearestGroups(std::span<const Eigen::Vector3d> points, const LabelGrid& groups) {
  // A point in a foreground voxel's cell takes its value. Otherwise the
  // nearest foreground voxel has a background (or off-grid) 6-neighbour: a
  // step towards the point along an axis where it lies more than half a
  // voxel away would be nearer. So only those boundary voxels are searched
  // (the nearest centre; ties: the lowest voxel index), in boxes about the
  // point whose half-width r doubles until the nearest found lies within r:
  // every voxel outside the box is farther than r.
  const GridGeometry& g = groups.geometry();
  std::vector<Label> out(points.size(), 0);
  if (std::none_of(groups.labels().begin(), groups.labels().end(), [](Label l) { return l != 0; })) return out;
  const auto boundary = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return groups.atOr(i - 1, j, k) == 0 || groups.atOr(i + 1, j, k) == 0 || groups.atOr(i, j - 1, k) == 0 ||
           groups.atOr(i, j + 1, k) == 0 || groups.atOr(i, j, k - 1) == 0 || groups.atOr(i, j, k + 1) == 0;
  };
  parallelFor(std::int64_t(points.size()), 0, [&](std::int64_t p) {
    const Eigen::Vector3d& x = points[std::size_t(p)];
    if (!x.allFinite()) return;
    const Eigen::Vector3d c = g.continuousIndex(x);
    const std::int64_t i = std::lround(c.x()), j = std::lround(c.y()), k = std::lround(c.z());
    if (const Label inside = groups.atOr(i, j, k); inside != 0) {
      out[std::size_t(p)] = inside;
      return;
    }
    double best = std::numeric_limits<double>::infinity();
    std::int64_t nearest = -1;
    for (double r = 2.0 * g.spacing.maxCoeff();; r *= 2.0) {
      Index3 lo, hi;
      bool whole = true;
      for (int a = 0; a < 3; ++a) {
        const double reach = r / g.spacing[a];
        lo[a] = std::max<std::int64_t>(0, std::int64_t(std::ceil(c[a] - reach)));
        hi[a] = std::min<std::int64_t>(g.dims[a] - 1, std::int64_t(std::floor(c[a] + reach)));
        whole = whole && lo[a] == 0 && hi[a] == g.dims[a] - 1;
      }
      for (std::int64_t kk = lo[2]; kk <= hi[2]; ++kk)
        for (std::int64_t jj = lo[1]; jj <= hi[1]; ++jj)
          for (std::int64_t ii = lo[0]; ii <= hi[0]; ++ii) {
            if (groups.at(ii, jj, kk) == 0) continue;
            const double d = (g.voxelCenter(ii, jj, kk) - x).squaredNorm();
            const std::int64_t index = g.index(ii, jj, kk);
            if ((d < best || (d == best && index < nearest)) && boundary(ii, jj, kk)) {
              best = d;
              nearest = index;
            }
          }
      if ((nearest >= 0 && best <= r * r) || whole) break;
    }
    out[std::size_t(p)] = groups.labels()[std::size_t(nearest)];
  });
  return out;
}

}  // namespace vox
