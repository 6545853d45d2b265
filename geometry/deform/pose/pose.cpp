#include "geometry/deform/pose/pose.h"
#include "geometry/disjoint_sets.h"

#include "geometry/skeleton/label_groups.h"
#include "geometry/error.h"
#include "geometry/skeleton/body_parts.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <set>

namespace vox {

Eigen::Vector3d PoseTransform::apply(const Eigen::Vector3d& x, double fraction) const {
  const double angle = fraction * angleDeg * std::numbers::pi / 180.0;
  // Without a rotation x is not sent through (x - center) + center, which
  // rounds: the identity (and fraction 0) gives x bit for bit.
  const Eigen::Vector3d rotated = angle == 0.0 ? x : Eigen::Vector3d(Eigen::AngleAxisd(angle, axis) * (x - center) + center);
  return rotated + fraction * translation;
}

bool PoseSelection::contains(const Eigen::Vector3d& p) const {
  if (shape == SelectionShape::Everywhere) return true;
  if (shape == SelectionShape::Points) return std::find(points.begin(), points.end(), p) != points.end();
  if (shape == SelectionShape::Box) return (p.array() >= boxMin.array()).all() && (p.array() <= boxMax.array()).all();
  return (p - center).squaredNorm() <= radius * radius;
}

std::vector<std::int32_t> cageParts(const TriMesh& cage) {
  DisjointSets parts(cage.vertexCount());
  for (const Tri& t : cage.triangles)
    for (int k = 1; k < 3; ++k) parts.unite(t[0], t[k]);
  return parts.representatives();
}

bool usesLabelGroups(const Pose& pose) {
  return std::any_of(pose.selections.begin(), pose.selections.end(), [](const PoseSelection& s) { return s.group.has_value(); });
}

void requireOrganTable(bool present, OrganTableNeed need, const std::string& source, bool usage) {
  if (present) return;
  const char* fault = "";
  switch (need) {
    case OrganTableNeed::Separation: fault = "limb separation needs the grid's organ table (--organs) to find the label groups"; break;
    case OrganTableNeed::LabelGroup: fault = "a selection by label group needs the grid's organ table (--organs)"; break;
    case OrganTableNeed::Bones: fault = "a pose with joints or body parts needs the grid's organ table (--organs) to find the bones"; break;
  }
  if (usage) throw UsageError(source, fault);
  throw InputError(source, fault);
}

bool usesBodyParts(const Pose& pose) {
  return std::any_of(pose.selections.begin(), pose.selections.end(), [](const PoseSelection& s) { return !s.bodyParts.empty(); });
}

PoseHandles selectHandles(const Pose& pose, const TriMesh& cage, const std::string& source, std::span<const Label> vertexGroups,
                          std::span<const Label> vertexParts) {
  std::vector<std::int32_t> owner(cage.vertexCount(), -1);
  const std::vector<std::int32_t> parts = cageParts(cage);
  for (std::size_t k = 0; k < pose.selections.size(); ++k) {
    const PoseSelection& s = pose.selections[k];
    std::int32_t part = -1;
    if (s.part) {
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t v = 0; v < cage.vertexCount(); ++v)
        if (const double d = (cage.positions[v] - *s.part).squaredNorm(); d < best) {
          best = d;
          part = parts[v];
        }
    }
    if (s.group) requireOrganTable(vertexGroups.size() == cage.vertexCount(), OrganTableNeed::LabelGroup, source + ": selection '" + s.name + "'");
    if (!s.bodyParts.empty() && vertexParts.size() != cage.vertexCount())
      throw InputError(source, "selection '" + s.name + "' selects by body part, which needs the grid's body parts (a joint pose, or --parts)");
    bool any = false;
    const auto eligible = [&](std::size_t v) {
      return (part < 0 || parts[v] == part) && (!s.group || vertexGroups[v] == *s.group) &&
             (s.bodyParts.empty() || std::find(s.bodyParts.begin(), s.bodyParts.end(), vertexParts[v]) != s.bodyParts.end());
    };
    if (s.shape == SelectionShape::Points) {
      for (const Eigen::Vector3d& q : s.points) {
        std::int32_t nearest = -1;
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t v = 0; v < cage.vertexCount(); ++v)
          if (const double d = (cage.positions[v] - q).squaredNorm(); d < best && eligible(v)) {
            best = d;
            nearest = std::int32_t(v);
          }
        if (nearest >= 0) {
          owner[std::size_t(nearest)] = std::int32_t(k);
          any = true;
        }
      }
    } else {
      for (std::size_t v = 0; v < cage.vertexCount(); ++v)
        if (s.contains(cage.positions[v]) && eligible(v)) {
          owner[v] = std::int32_t(k);
          any = true;
        }
    }
    if (!any) throw InputError(source, "selection '" + s.name + "' selects no cage vertex");
  }
  PoseHandles handles;
  for (std::size_t v = 0; v < owner.size(); ++v)
    if (owner[v] >= 0) {
      handles.vertices.push_back(std::int32_t(v));
      handles.selection.push_back(owner[v]);
    }
  return handles;
}

Eigen::MatrixX3d handleTargets(const Pose& pose, const PoseHandles& handles, const TriMesh& cage, double fraction) {
  if (!(fraction >= 0.0 && fraction <= 1.0)) throw InputError("pose", "fraction " + std::to_string(fraction) + " is outside [0, 1]");
  Eigen::MatrixX3d targets(Eigen::Index(handles.vertices.size()), 3);
  for (std::size_t k = 0; k < handles.vertices.size(); ++k) {
    const Eigen::Vector3d& rest = cage.positions[std::size_t(handles.vertices[k])];
    const PoseSelection& s = pose.selections[std::size_t(handles.selection[k])];
    targets.row(Eigen::Index(k)) = (s.fixed ? rest : s.transform.apply(rest, fraction)).transpose();
  }
  return targets;
}

}  // namespace vox
