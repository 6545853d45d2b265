#include "geometry/skeleton/body_parts.h"

#include "geometry/cancellation.h"
#include "geometry/distance_transform.h"
#include "geometry/error.h"
#include "geometry/progress.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <functional>
#include <limits>

namespace vox::skeleton {

namespace {

constexpr std::array<const char*, kPartCount + 1> kPartNames = {
    "none",          "head",           "neck",           "trunk",           "pelvis",          "right_upper_arm",
    "right_forearm", "right_hand",     "left_upper_arm", "left_forearm",    "left_hand",       "right_thigh",
    "right_lower_leg", "right_foot",   "left_thigh",     "left_lower_leg",  "left_foot"};

struct Centroid {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::int64_t count = 0;
  void add(const Eigen::Vector3d& p) {
    sum += p;
    ++count;
  }
  void add(const Centroid& c) {
    sum += c.sum;
    count += c.count;
  }
  Eigen::Vector3d mean() const { return sum / double(std::max<std::int64_t>(count, 1)); }
};

// The 26 neighbour steps of a voxel with their lengths in mm.
struct Neighbourhood {
  std::array<std::array<int, 3>, 26> step{};
  std::array<float, 26> length{};

  explicit Neighbourhood(const Eigen::Vector3d& spacing) {
    int n = 0;
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          if (di == 0 && dj == 0 && dk == 0) continue;
          step[std::size_t(n)] = {di, dj, dk};
          length[std::size_t(n)] = float(spacing.cwiseProduct(Eigen::Vector3d(di, dj, dk)).norm());
          ++n;
        }
  }
};

Eigen::Vector3d centreOf(const GridGeometry& g, std::int64_t v) {
  const Index3 c = g.ijk(v);
  return g.voxelCenter(c[0], c[1], c[2]);
}

// Min-queue of 64-bit keys that never receive a key below the last one
// taken while they hold any (Dijkstra's keys grow): a radix heap (Ahuja,
// Mehlhorn, Orlin, Tarjan). Bucket b holds the keys whose highest bit
// differing from the last key taken is bit b - 1 (bucket 0: equal to it);
// taking the minimum empties the lowest non-empty bucket into lower ones, so
// each key moves at most 64 times and mostly stays in cache, where a binary
// heap of millions of entries misses at every level. It takes the keys in
// the same order as any min-queue.
class RadixHeap {
public:
  bool empty() const { return size_ == 0; }
  void push(std::uint64_t key) {
    buckets_[bucketOf(key)].push_back(key);
    ++size_;
  }
  std::uint64_t pop() {
    if (buckets_[0].empty()) {
      std::size_t b = 1;
      while (buckets_[b].empty()) ++b;
      last_ = *std::min_element(buckets_[b].begin(), buckets_[b].end());
      for (const std::uint64_t key : buckets_[b]) buckets_[bucketOf(key)].push_back(key);
      buckets_[b].clear();
    }
    const std::uint64_t key = buckets_[0].back();
    buckets_[0].pop_back();
    if (--size_ == 0) last_ = 0;  // an empty queue takes any key again
    return key;
  }

private:
  std::size_t bucketOf(std::uint64_t key) const { return key == last_ ? 0 : std::size_t(std::bit_width(key ^ last_)); }
  std::array<std::vector<std::uint64_t>, 65> buckets_;
  std::uint64_t last_ = 0;
  std::size_t size_ = 0;
};

// Multi-source Dijkstra on the voxel lattice. Entries pack the distance's
// float bits (non-negative floats order as their bit patterns) above the
// voxel index, so the queue holds 8 bytes per entry; a path only grows, so
// its keys grow too.
class GeodesicFront {
public:
  GeodesicFront(const GridGeometry& g, std::vector<float>& distance, std::vector<std::uint8_t>& owner)
      : g_(g), n_(g.spacing), distance_(distance), owner_(owner) {}

  void push(std::int64_t v) { heap_.push((std::uint64_t(std::bit_cast<std::uint32_t>(distance_[std::size_t(v)])) << 32) | std::uint64_t(v)); }

  // Settles voxels in order of distance. A popped voxel passes its owner on
  // when passes(v); a neighbour n takes it when enters(n) and the path is
  // shorter. Returns the voxels settled.
  template <class Passes, class Enters>
  std::int64_t run(const Passes& passes, const Enters& enters) {
    std::int64_t settled = 0;
    while (!heap_.empty()) {
      const std::uint64_t top = heap_.pop();
      const std::int64_t v = std::int64_t(top & 0xffffffffu);
      const float d = std::bit_cast<float>(std::uint32_t(top >> 32));
      if (d > distance_[std::size_t(v)]) continue;
      if ((++settled & 0xffff) == 0) throwIfCancelled();
      if (!passes(v)) continue;
      const Index3 c = g_.ijk(v);
      const std::uint8_t owner = owner_[std::size_t(v)] & kPartMask;
      for (std::size_t s = 0; s < 26; ++s) {
        const std::int64_t i = c[0] + n_.step[s][0], j = c[1] + n_.step[s][1], k = c[2] + n_.step[s][2];
        if (!g_.contains(i, j, k)) continue;
        const std::int64_t n = g_.index(i, j, k);
        const float nd = d + n_.length[s];
        if (nd < distance_[std::size_t(n)] && enters(n)) {
          distance_[std::size_t(n)] = nd;
          owner_[std::size_t(n)] = owner;
          push(n);
        }
      }
    }
    return settled;
  }

  static constexpr std::uint8_t kPartMask = 0x7f;
  static constexpr std::uint8_t kFinal = 0x80;  // settled in an earlier pass

private:
  const GridGeometry& g_;
  Neighbourhood n_;
  std::vector<float>& distance_;
  std::vector<std::uint8_t>& owner_;
  RadixHeap heap_;
};

void countParts(BodyParts& out) {
  out.voxels.fill(0);
  for (const Label l : out.parts.labels())
    if (l <= kPartCount) ++out.voxels[l];
  for (auto& b : out.seedBones) b.clear();
  for (const BoneVoxels& b : out.bones) {
    auto& list = out.seedBones[std::size_t(bonePart(b.bone, b.side))];
    if (std::find(list.begin(), list.end(), b.bone) == list.end()) list.push_back(b.bone);
  }
}

}  // namespace

void forEachComponent(const GridGeometry& g, std::vector<std::uint8_t>& marked,
                      const std::function<void(std::uint8_t, const std::vector<std::int64_t>&)>& fn) {
  std::vector<std::int64_t> piece, stack;
  for (std::int64_t seed = 0; seed < g.voxelCount(); ++seed) {
    const std::uint8_t cls = marked[std::size_t(seed)];
    if (cls == 0) continue;
    piece.clear();
    stack.assign(1, seed);
    marked[std::size_t(seed)] = 0;
    while (!stack.empty()) {
      const std::int64_t v = stack.back();
      stack.pop_back();
      piece.push_back(v);
      const Index3 c = g.ijk(v);
      for (int dk = -1; dk <= 1; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const std::int64_t i = c[0] + di, j = c[1] + dj, k = c[2] + dk;
            if (!g.contains(i, j, k)) continue;
            const std::int64_t n = g.index(i, j, k);
            if (marked[std::size_t(n)] == cls) {
              marked[std::size_t(n)] = 0;
              stack.push_back(n);
            }
          }
    }
    fn(cls, piece);
  }
}


const char* partName(Part part) {
  const int i = int(part);
  return i >= 0 && i <= kPartCount ? kPartNames[std::size_t(i)] : "?";
}

std::optional<Part> partFromName(const std::string& name) {
  std::string n;
  for (const unsigned char c : name) n += c == '-' ? '_' : char(std::tolower(c));
  for (int i = 1; i <= kPartCount; ++i)
    if (n == kPartNames[std::size_t(i)]) return Part(i);
  return std::nullopt;
}

std::string partNames() {
  std::string s;
  for (int i = 1; i <= kPartCount; ++i) s += std::string(i > 1 ? ", " : "") + kPartNames[std::size_t(i)];
  return s;
}

Part bonePart(Bone bone, Side side) {
  const bool left = side == Side::Left;
  switch (bone) {
    case Bone::Cranium:
    case Bone::Mandible: return Part::Head;
    case Bone::CervicalSpine: return Part::Neck;
    case Bone::Sacrum:
    case Bone::Pelvis: return Part::Pelvis;
    case Bone::Humerus: return left ? Part::LeftUpperArm : Part::RightUpperArm;
    case Bone::ForearmBones: return left ? Part::LeftForearm : Part::RightForearm;
    case Bone::HandBones: return left ? Part::LeftHand : Part::RightHand;
    case Bone::Femur: return left ? Part::LeftThigh : Part::RightThigh;
    case Bone::LowerLegBones: return left ? Part::LeftLowerLeg : Part::RightLowerLeg;
    case Bone::FootBones: return left ? Part::LeftFoot : Part::RightFoot;
    case Bone::None: return Part::None;
    default: return Part::Trunk;
  }
}

LabelGroup labelGroupOf(Part part) {
  switch (part) {
    case Part::Head:
    case Part::Neck: return LabelGroup::Head;
    case Part::RightUpperArm:
    case Part::RightForearm:
    case Part::RightHand: return LabelGroup::RightArm;
    case Part::LeftUpperArm:
    case Part::LeftForearm:
    case Part::LeftHand: return LabelGroup::LeftArm;
    case Part::RightThigh:
    case Part::RightLowerLeg:
    case Part::RightFoot: return LabelGroup::RightLeg;
    case Part::LeftThigh:
    case Part::LeftLowerLeg:
    case Part::LeftFoot: return LabelGroup::LeftLeg;
    default: return LabelGroup::Trunk;
  }
}

const BoneVoxels* BodyParts::find(Bone bone, Side side) const {
  for (const BoneVoxels& b : bones)
    if (b.bone == bone && b.side == side) return &b;
  return nullptr;
}

BodyParts findBones(const LabelGrid& grid, const OrganTable& organs, const std::string& gridSource, const std::string& organsSource,
                    const BodyPartOptions& options) {
  requireBones(organs, organsSource);
  const GridGeometry& g = grid.geometry();
  const Label maxLabel = grid.maxLabel();
  const std::vector<Bone> boneOf = boneOfLabels(organs, maxLabel);
  std::vector<Side> namedSide(boneOf.size(), Side::Axial);
  for (std::size_t l = 1; l < boneOf.size(); ++l)
    if (const Organ* o = organs.find(int(l)); o && boneOf[l] != Bone::None) namedSide[l] = sideInName(o->name);

  // One pass: centroids of every bone, the voxels of each (bone, side), and
  // the paired bones' voxels without a side in their name, to split below.
  std::array<Centroid, kBoneCount + 1> centroid;
  Centroid foreground;
  std::array<std::array<std::vector<std::int64_t>, 3>, kBoneCount + 1> voxels;
  std::vector<std::uint8_t> unsided(std::size_t(g.voxelCount()), 0);
  bool anyUnsided = false;
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
    const Label l = grid.labels()[std::size_t(v)];
    if (l == 0) continue;
    const Bone b = boneOf[l];
    const Eigen::Vector3d p = centreOf(g, v);
    foreground.add(p);
    if (b == Bone::None) continue;
    centroid[std::size_t(b)].add(p);
    if (isPaired(b) && namedSide[l] == Side::Axial) {
      unsided[std::size_t(v)] = std::uint8_t(b);
      anyUnsided = true;
    } else {
      voxels[std::size_t(b)][std::size_t(isPaired(b) ? namedSide[l] : Side::Axial)].push_back(v);
    }
  }
  bool anyBone = false;
  for (const Centroid& c : centroid) anyBone = anyBone || c.count > 0;
  if (!anyBone) throw InputError(gridSource, "has no voxel of the bones its organ table (" + organsSource + ") names");

  BodyParts out;
  AnatomicalFrame& f = out.frame;
  const auto sumOf = [&](std::initializer_list<Bone> bones) {
    Centroid c;
    for (const Bone b : bones) c.add(centroid[std::size_t(b)]);
    return c;
  };
  const Centroid head = sumOf({Bone::Cranium, Bone::Mandible, Bone::CervicalSpine});
  const Centroid low = sumOf({Bone::Pelvis, Bone::Sacrum, Bone::LumbarSpine});
  const Centroid sternum = sumOf({Bone::Sternum});
  const Centroid spine = sumOf({Bone::ThoracicSpine});
  bool superiorMeasured = false, anteriorMeasured = false;
  if (head.count > 0 && low.count > 0 && (head.mean() - low.mean()).norm() > 0) {
    f.superior = (head.mean() - low.mean()).normalized();
    superiorMeasured = true;
  }
  if (sternum.count > 0 && spine.count > 0) {
    const Eigen::Vector3d a = sternum.mean() - spine.mean();
    const Eigen::Vector3d ortho = a - a.dot(f.superior) * f.superior;
    if (ortho.norm() > 1e-6 * a.norm() && ortho.norm() > 0) {
      f.anterior = ortho.normalized();
      anteriorMeasured = true;
    }
  }
  if (!anteriorMeasured) {
    const Eigen::Vector3d ortho = f.anterior - f.anterior.dot(f.superior) * f.superior;
    f.anterior = ortho.norm() > 1e-6 ? ortho.normalized() : f.superior.unitOrthogonal();
  }
  if (options.snapToGridAxes) {
    // The grid axis (and sign) nearest each measured direction.
    const auto nearestAxis = [](const Eigen::Vector3d& d, int skip) {
      int best = 0;
      for (int a = 1; a < 3; ++a)
        if (a != skip && (best == skip || std::abs(d(a)) > std::abs(d(best)))) best = a;
      return best;
    };
    const int up = nearestAxis(f.superior, -1);
    const int front = nearestAxis(f.anterior, up);
    f.superior = Eigen::Vector3d::Unit(up) * (f.superior(up) < 0 ? -1.0 : 1.0);
    f.anterior = Eigen::Vector3d::Unit(front) * (f.anterior(front) < 0 ? -1.0 : 1.0);
  }
  f.right = f.anterior.cross(f.superior).normalized();
  f.fromBones = superiorMeasured && anteriorMeasured;
  const Centroid midline = sumOf({Bone::CervicalSpine, Bone::ThoracicSpine, Bone::LumbarSpine, Bone::Sacrum, Bone::Sternum, Bone::Cranium,
                                  Bone::Mandible});
  f.midpoint = midline.count > 0 ? midline.mean() : foreground.mean();

  if (anyUnsided) {
    const auto onRight = [&](std::int64_t v) { return (centreOf(g, v) - f.midpoint).dot(f.right) > 0.0; };
    forEachComponent(g, unsided, [&](std::uint8_t cls, const std::vector<std::int64_t>& piece) {
      std::int64_t right = 0;
      for (const std::int64_t v : piece) right += onRight(v);
      const std::int64_t size = std::int64_t(piece.size());
      const bool perVoxel = double(std::min(right, size - right)) >= options.straddleFraction * double(size);
      const Side pieceSide = 2 * right >= size ? Side::Right : Side::Left;
      for (const std::int64_t v : piece) {
        const Side s = perVoxel ? (onRight(v) ? Side::Right : Side::Left) : pieceSide;
        voxels[cls][std::size_t(s)].push_back(v);
      }
    });
  }
  for (int b = 1; b <= kBoneCount; ++b)
    for (int s = 0; s < 3; ++s) {
      std::vector<std::int64_t>& list = voxels[std::size_t(b)][std::size_t(s)];
      if (list.empty()) continue;
      std::sort(list.begin(), list.end());
      out.bones.push_back({Bone(b), Side(s), std::move(list)});
    }
  return out;
}

BodyParts bodyParts(const LabelGrid& grid, const OrganTable& organs, const std::string& gridSource, const std::string& organsSource,
                    const BodyPartOptions& options) {
  BodyParts out = findBones(grid, organs, gridSource, organsSource, options);
  const GridGeometry& g = grid.geometry();
  if (g.voxelCount() >= (std::int64_t(1) << 32))
    throw InputError(gridSource, "has more than 2^32 voxels, too many for the body-part assignment");

  std::vector<std::uint8_t> skin(std::size_t(grid.maxLabel()) + 1, 0);
  if (options.skinBlocksPaths) skin = skinOfLabels(organs, grid.maxLabel());

  std::vector<float> distance(std::size_t(g.voxelCount()), std::numeric_limits<float>::infinity());
  std::vector<std::uint8_t> owner(std::size_t(g.voxelCount()), 0);
  GeodesicFront front(g, distance, owner);
  for (const BoneVoxels& b : out.bones)
    for (const std::int64_t v : b.voxels) {
      distance[std::size_t(v)] = 0.0f;
      owner[std::size_t(v)] = std::uint8_t(bonePart(b.bone, b.side));
      front.push(v);
    }
  const std::vector<Label>& labels = grid.labels();
  const auto foreground = [&](std::int64_t n) { return labels[std::size_t(n)] != 0; };

  // Pass 1: through foreground, not through skin.
  reportProgress("body parts", 0.0);
  front.run([&](std::int64_t v) { return !skin[labels[std::size_t(v)]]; }, foreground);
  reportProgress("body parts", 0.9);
  // Pass 2: on from the skin, into what pass 1 left.
  const auto mark = [&]() {
    std::int64_t open = 0;
    for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
      if (v % 65536 == 0) throwIfCancelled();
      if (std::isfinite(distance[std::size_t(v)])) owner[std::size_t(v)] |= GeodesicFront::kFinal;
      else open += foreground(v);
    }
    return open;
  };
  const auto notFinal = [&](std::int64_t n) { return (owner[std::size_t(n)] & GeodesicFront::kFinal) == 0; };
  std::int64_t open = mark();
  if (open > 0) {
    for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
      if (v % 65536 == 0) throwIfCancelled();
      if (skin[labels[std::size_t(v)]] && std::isfinite(distance[std::size_t(v)])) front.push(v);
    }
    front.run([](std::int64_t) { return true; }, [&](std::int64_t n) { return foreground(n) && notFinal(n); });
    const std::int64_t left = mark();
    out.reachedThroughSkin = open - left;
    open = left;
  }
  // Pass 3: foreground pieces without a bone, through the background.
  if (open > 0) {
    for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
      if (v % 65536 == 0) throwIfCancelled();
      if (std::isfinite(distance[std::size_t(v)])) front.push(v);
    }
    front.run([](std::int64_t) { return true; }, notFinal);
    out.reachedThroughBackground = open;
  }
  reportProgress("body parts", 1.0);

  out.parts = LabelGrid(g, 0);
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
    if (v % 65536 == 0) throwIfCancelled();
    if (foreground(v)) out.parts.labels()[std::size_t(v)] = Label(owner[std::size_t(v)] & GeodesicFront::kPartMask);
  }
  throwIfCancelled();
  countParts(out);
  return out;
}

BodyParts userBodyParts(const LabelGrid& grid, const OrganTable& organs, LabelGrid parts, const std::string& gridSource,
                        const std::string& organsSource, const std::string& partsSource, const BodyPartOptions& options) {
  const GridGeometry &g = grid.geometry(), &p = parts.geometry();
  if (p.dims != g.dims)
    throw InputError(partsSource, "has " + std::to_string(p.dims[0]) + " x " + std::to_string(p.dims[1]) + " x " + std::to_string(p.dims[2]) +
                                      " voxels, the grid " + gridSource + " " + std::to_string(g.dims[0]) + " x " +
                                      std::to_string(g.dims[1]) + " x " + std::to_string(g.dims[2]));
  if (((p.spacing - g.spacing).array().abs() > 1e-4 * g.spacing.array()).any())
    throw InputError(partsSource, "has another voxel size than the grid " + gridSource);
  const Label top = parts.maxLabel();
  if (top > kPartCount)
    throw InputError(partsSource, "has value " + std::to_string(top) + "; body parts are 1.." + std::to_string(kPartCount) + " (" +
                                      partNames() + ")");
  BodyParts out = findBones(grid, organs, gridSource, organsSource, options);
  parts.geometry() = g;
  out.parts = std::move(parts);
  countParts(out);
  return out;
}

LabelGrid euclideanBodyParts(const LabelGrid& grid, const BodyParts& bones) {
  const GridGeometry& g = grid.geometry();
  std::vector<std::uint8_t> seeds(std::size_t(g.voxelCount()), 0);
  std::vector<std::uint8_t> part(std::size_t(g.voxelCount()), 0);
  for (const BoneVoxels& b : bones.bones)
    for (const std::int64_t v : b.voxels) {
      seeds[std::size_t(v)] = 1;
      part[std::size_t(v)] = std::uint8_t(bonePart(b.bone, b.side));
    }
  const DistanceTransform dt = euclideanDistanceTransform(g, seeds, true);
  LabelGrid out(g, 0);
  for (std::int64_t v = 0; v < g.voxelCount(); ++v)
    if (grid.labels()[std::size_t(v)] != 0 && dt.nearest[std::size_t(v)] >= 0)
      out.labels()[std::size_t(v)] = part[std::size_t(dt.nearest[std::size_t(v)])];
  return out;
}

LabelGrid labelGroupsOfParts(const LabelGrid& parts) {
  LabelGrid out(parts.geometry(), 0);
  std::transform(parts.labels().begin(), parts.labels().end(), out.labels().begin(), [](Label l) {
    return l == 0 || l > kPartCount ? Label(0) : Label(labelGroupOf(Part(l)));
  });
  return out;
}

std::array<int, kPartCount + 1> partComponents(const LabelGrid& parts) {
  std::vector<std::uint8_t> marked(parts.labels().size());
  std::transform(parts.labels().begin(), parts.labels().end(), marked.begin(),
                 [](Label l) { return std::uint8_t(l <= kPartCount ? l : 0); });
  std::array<int, kPartCount + 1> count{};
  forEachComponent(parts.geometry(), marked, [&](std::uint8_t cls, const std::vector<std::int64_t>&) { ++count[cls]; });
  return count;
}

}  // namespace vox::skeleton
