#include "geometry/skeleton/skeleton.h"

#include "geometry/world_frame.h"

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace vox::skeleton {

namespace {

using nlohmann::json;

json vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

}  // namespace

const Joint* Skeleton::joint(JointId id) const { return findJoint(joints, id); }

const Joint* Skeleton::nearestJoint(const Eigen::Vector3d& p) const {
  const Joint* best = nullptr;
  for (const Joint& j : joints)
    if (!best || (j.centre - p).squaredNorm() < (best->centre - p).squaredNorm()) best = &j;
  return best;
}

Skeleton buildSkeleton(const LabelGrid& grid, const OrganTable& organs, const SkeletonSources& sources, std::optional<LabelGrid> userParts,
                       const BodyPartOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  Skeleton s;
  s.parts = userParts ? userBodyParts(grid, organs, std::move(*userParts), sources.grid, sources.organs, sources.parts, options)
                      : bodyParts(grid, organs, sources.grid, sources.organs, options);
  s.joints = estimateJoints(grid.geometry(), s.parts);
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return s;
}

std::string skeletonReportJson(const Skeleton& s, const GridGeometry& g, const std::string& input, const std::string& output) {
  const AnatomicalFrame& f = s.parts.frame;
  const auto world = [&](const Eigen::Vector3d& p) { return vec(gridToWorld(g, p)); };
  json parts = json::array();
  for (int p = 1; p <= kPartCount; ++p) {
    json bones = json::array();
    for (const Bone b : s.parts.seedBones[std::size_t(p)]) bones.push_back(boneName(b));
    const std::int64_t n = s.parts.voxels[std::size_t(p)];
    parts.push_back({{"id", p}, {"name", partName(Part(p))}, {"voxels", n}, {"volume_ml", double(n) * g.voxelVolume() / 1000.0}, {"bones", bones}});
  }
  json joints = json::array();
  for (const Joint& j : s.joints) {
    const JointKind& k = j.kind();
    json dofs = json::object();
    for (int d = 0; d < kDofCount; ++d)
      if (k.dofNames[std::size_t(d)])
        dofs[k.dofNames[std::size_t(d)]] = {{"axis", world(j.axis(Dof(d)))},
                                            {"range_deg", json::array({k.range[std::size_t(d)][0], k.range[std::size_t(d)][1]})}};
    json entry = {{"name", k.name},
                  {"parent", partName(k.parent)},
                  {"child", partName(k.child)},
                  {"center_mm", world(j.centre)},
                  {"long_axis", world(j.longAxis)},
                  {"left_right_axis", world(j.leftRight)},
                  {"center_method", j.method},
                  {"axis_method", j.axisMethod},
                  {"degrees_of_freedom", dofs}};
    if (j.radius > 0) entry["sphere_radius_mm"] = j.radius;
    joints.push_back(std::move(entry));
  }
  json bones = json::array();
  for (const BoneVoxels& b : s.parts.bones)
    bones.push_back({{"bone", boneName(b.bone)}, {"side", sideName(b.side)}, {"voxels", b.voxels.size()}, {"part", partName(bonePart(b.bone, b.side))}});
  json j = {{"input", input},
            {"output", output},
            {"seconds", s.seconds},
            {"frame", "world"},
            {"anatomical_frame",
             {{"right", world(f.right)},
              {"anterior", world(f.anterior)},
              {"superior", world(f.superior)},
              {"midline_point_mm", world(f.midpoint)},
              {"from_bones", f.fromBones}}},
            {"voxels_reached_through_skin", s.parts.reachedThroughSkin},
            {"voxels_reached_through_background", s.parts.reachedThroughBackground},
            {"parts", parts},
            {"joints", joints},
            {"bones", bones}};
  return j.dump(2) + "\n";
}

std::string skeletonSummary(const Skeleton& s, const GridGeometry& g) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line, "%-4s %-16s %10s %11s  %s\n", "id", "part", "voxels", "volume mL", "bones");
  out += line;
  for (int p = 1; p <= kPartCount; ++p) {
    std::string bones;
    for (const Bone b : s.parts.seedBones[std::size_t(p)]) bones += std::string(bones.empty() ? "" : ", ") + boneName(b);
    const std::int64_t n = s.parts.voxels[std::size_t(p)];
    std::snprintf(line, sizeof line, "%-4d %-16s %10lld %11.1f  %s\n", p, partName(Part(p)), (long long)n, double(n) * g.voxelVolume() / 1000.0,
                  bones.c_str());
    out += line;
  }
  out += "\n";
  std::snprintf(line, sizeof line, "%-15s %-30s %-8s  %s\n", "joint", "centre (world, mm)", "radius", "how");
  out += line;
  for (const Joint& j : s.joints) {
    const Eigen::Vector3d c = gridToWorld(g, j.centre);
    char centre[64], radius[16] = "";
    std::snprintf(centre, sizeof centre, "(%.1f, %.1f, %.1f)", c.x(), c.y(), c.z());
    if (j.radius > 0) std::snprintf(radius, sizeof radius, "%.1f", j.radius);
    std::snprintf(line, sizeof line, "%-15s %-30s %-8s  %s; axis: %s\n", j.kind().name, centre, radius, j.method.c_str(), j.axisMethod.c_str());
    out += line;
  }
  return out;
}

}  // namespace vox::skeleton
