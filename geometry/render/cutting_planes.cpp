#include "geometry/render/cutting_planes.h"

#include "geometry/error.h"

#include <charconv>
#include <cmath>

namespace vox {

std::vector<CuttingPlane> CuttingPlanes::active() const {
  std::vector<CuttingPlane> out;
  for (const auto& p : axis)
    if (p) out.push_back(*p);
  if (free) out.push_back(*free);
  return out;
}

bool CuttingPlanes::removes(const Eigen::Vector3d& centre) const {
  for (const auto& p : axis)
    if (p && p->removes(centre)) return true;
  return free && free->removes(centre);
}

namespace {
double number(const std::string& text, const std::string& whole) {
  std::string s = text;
  while (!s.empty() && s.front() == ' ') s.erase(s.begin());
  while (!s.empty() && s.back() == ' ') s.pop_back();
  if (s.size() > 2 && s.compare(s.size() - 2, 2, "mm") == 0) s.resize(s.size() - 2);
  double v = 0.0;
  const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || res.ec != std::errc() || res.ptr != s.data() + s.size() || !std::isfinite(v))
    throw UsageError("--cut", "'" + whole + "': '" + text + "' is not a number");
  return v;
}
}  // namespace

void CuttingPlanes::add(const std::string& text) {
  if (text.rfind("plane=", 0) == 0) {
    const std::string body = text.substr(6);
    std::vector<double> v;
    std::size_t start = 0;
    while (start <= body.size()) {
      std::size_t comma = body.find(',', start);
      if (comma == std::string::npos) comma = body.size();
      v.push_back(number(body.substr(start, comma - start), text));
      start = comma + 1;
    }
    if (v.size() != 4) throw UsageError("--cut", "'" + text + "': plane= needs four numbers nx,ny,nz,d");
    const Eigen::Vector3d n(v[0], v[1], v[2]);
    if (n.norm() == 0.0) throw UsageError("--cut", "'" + text + "': the plane normal is zero");
    if (free) throw UsageError("--cut", "'" + text + "': only one free plane is allowed");
    free = CuttingPlane{n, v[3]};
    return;
  }
  if (text.size() < 3 || (text[0] != 'x' && text[0] != 'y' && text[0] != 'z') || (text[1] != '>' && text[1] != '<'))
    throw UsageError("--cut", "'" + text + "': expected x>VALUE, y<VALUE, ... (mm) or plane=nx,ny,nz,d");
  const int a = text[0] - 'x';
  if (axis[a]) throw UsageError("--cut", "'" + text + "': only one plane per axis is allowed");
  const double value = number(text.substr(2), text);
  const double sign = text[1] == '>' ? 1.0 : -1.0;
  CuttingPlane p;
  p.normal = Eigen::Vector3d::Zero();
  p.normal[a] = sign;
  p.offset = sign * value;
  axis[a] = p;
}

}  // namespace vox
