#include "geometry/deform/pose/posed_extent.h"

#include "geometry/raster/lattice_tets.h"
#include "geometry/error.h"

#include <charconv>
#include <cmath>

namespace vox {

namespace {

std::string number(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::general, 4);
  return std::string(buf, r.ptr);
}

std::string vectorText(const Eigen::Vector3d& v) { return "(" + number(v.x()) + ", " + number(v.y()) + ", " + number(v.z()) + ")"; }

std::string dimsText(const Eigen::Vector3d& d) { return number(d.x()) + " x " + number(d.y()) + " x " + number(d.z()); }

}  // namespace

std::string selectionMovingFarthest(const Pose& pose, const PoseHandles& handles, const std::vector<Eigen::Vector3d>& deformedCage,
                                    const GridGeometry& source) {
  const Eigen::Vector3d boxLo = source.origin - 0.5 * source.spacing;
  const Eigen::Vector3d boxHi = source.origin + source.spacing.cwiseProduct(Eigen::Vector3d(double(source.dims[0]), double(source.dims[1]),
                                                                                            double(source.dims[2])) -
                                                                            Eigen::Vector3d::Constant(0.5));
  double farthest = 0.0;
  std::int32_t culprit = -1;
  for (std::size_t h = 0; h < handles.vertices.size(); ++h) {
    const Eigen::Vector3d& p = deformedCage[std::size_t(handles.vertices[h])];
    const double outside = (boxLo - p).cwiseMax(p - boxHi).cwiseMax(0.0).norm();
    if (outside > farthest || (!std::isfinite(outside) && culprit < 0)) {
      farthest = outside;
      culprit = handles.selection[h];
    }
  }
  if (culprit < 0) return {};
  const PoseSelection& s = pose.selections[std::size_t(culprit)];
  std::string text = "selection '" + (s.name.empty() ? std::to_string(culprit + 1) : s.name) + "'";
  if (s.fixed) return text;
  std::string how;
  if (s.transform.angleDeg != 0.0) how = "rotation about " + vectorText(s.transform.center) + " mm";
  if (s.transform.translation != Eigen::Vector3d::Zero())
    how += (how.empty() ? "" : ", ") + std::string("translation ") + vectorText(s.transform.translation) + " mm";
  return how.empty() ? text : text + " (" + how + ")";
}

void checkPosedGrowth(const GridGeometry& source, const std::vector<Eigen::Vector3d>& deformed, const std::string& poseSource,
                      const std::string& culprit, bool allowGrowth) {
  const std::string who = culprit.empty() ? std::string("the pose") : culprit;
  PosedExtent e;
  try {
    e = posedExtent(source, deformed);
  } catch (const InputError& error) {
    throw InputError(poseSource, who + " moves the " + error.what());
  }
  const double sourceVoxels = double(source.voxelCount());
  const double growth = e.voxels / sourceVoxels;
  const bool tooLarge = !(e.voxels <= double(kMaxGridVoxels));
  if (!tooLarge && (allowGrowth || growth <= kMaxPosedGrowth)) return;
  std::string fault = who + " makes a posed grid of " + dimsText(e.dims) + " voxels, " + number(growth) + " times the source's " +
                      std::to_string(source.dims[0]) + " x " + std::to_string(source.dims[1]) + " x " + std::to_string(source.dims[2]);
  if (tooLarge) fault += ", more than the largest supported grid (" + std::to_string(kMaxGridVoxels) + " voxels)";
  else fault += " (at most " + number(kMaxPosedGrowth) + " times without --allow-growth)";
  throw InputError(poseSource, fault);
}

}  // namespace vox
