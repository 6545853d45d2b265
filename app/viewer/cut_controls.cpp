#include "app/viewer/cut_controls.h"

#include "geometry/deform/pose/pose_editor.h"

#include <algorithm>
#include <cstdio>

namespace vox::app {

void CutControls::setBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  lo_ = lo;
  hi_ = hi;
  for (int a = 0; a < 3; ++a) at[a] = float(0.5 * (lo[a] + hi[a]));
  freeOffset = float(0.5 * (lo[0] + hi[0]));
}

Eigen::Vector3d CutControls::handle(int a) const {
  Eigen::Vector3d c = 0.5 * (lo_ + hi_);
  c[a] = at[a];
  return c;
}

void CutControls::slide(int a, double mm) { at[a] = float(std::clamp(double(at[a]) + mm, lo_[a], hi_[a])); }

std::vector<std::string> CutControls::strings() const {
  std::vector<std::string> cuts;
  const char axes[3] = {'x', 'y', 'z'};
  char buf[128];
  for (int a = 0; a < 3; ++a)
    if (on[a]) {
      std::snprintf(buf, sizeof buf, "%c%c%.3fmm", axes[a], above[a] ? '>' : '<', double(at[a]));
      cuts.push_back(buf);
    }
  if (freeOn) {
    std::snprintf(buf, sizeof buf, "plane=%.6f,%.6f,%.6f,%.3f", double(freeNormal[0]), double(freeNormal[1]), double(freeNormal[2]),
                  double(freeOffset));
    cuts.push_back(buf);
  }
  return cuts;
}

void CutControls::read(const std::vector<std::string>& cuts) {
  for (int a = 0; a < 3; ++a) on[a] = false;
  freeOn = false;
  for (const std::string& c : cuts) {
    CuttingPlanes one;
    one.add(c);
    for (int a = 0; a < 3; ++a)
      if (one.axis[a]) {
        on[a] = true;
        above[a] = one.axis[a]->normal[a] > 0;
        at[a] = float(one.axis[a]->offset * (above[a] ? 1.0 : -1.0));
      }
    if (one.free) {
      freeOn = true;
      for (int a = 0; a < 3; ++a) freeNormal[a] = float(one.free->normal[a]);
      freeOffset = float(one.free->offset);
    }
  }
  stale_ = true;
}

void CutControls::commit(PoseEditor& editor) {
  editor.setCuts(strings());
  stale_ = true;
}

const CuttingPlanes& CutControls::planes(const std::vector<std::string>& cuts) {
  if (stale_) {
    CuttingPlanes parsed;
    for (const std::string& c : cuts) parsed.add(c);
    planes_ = parsed;
    stale_ = false;
  }
  return planes_;
}

}  // namespace vox::app
