#include "geometry/render/camera.h"

#include "geometry/error.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <vector>

namespace vox {

CameraRays cameraRays(const Camera& c) {
  if (c.width <= 0 || c.height <= 0) throw InputError("camera", "image size must be positive");
  if (!(c.fovYDegrees > 0.0 && c.fovYDegrees < 180.0)) throw InputError("camera", "field of view must be in (0, 180) degrees");
  if (!c.eye.allFinite() || !c.target.allFinite() || !c.up.allFinite()) throw InputError("camera", "non-finite eye, target or up");
  const Eigen::Vector3d view = c.target - c.eye;
  if (view.norm() <= 0.0) throw InputError("camera", "eye and target coincide");
  CameraRays r;
  r.eye = c.eye;
  r.forward = view.normalized();
  const Eigen::Vector3d side = r.forward.cross(c.up);
  if (side.norm() <= 1e-9 * c.up.norm()) throw InputError("camera", "up is parallel to the view direction");
  r.right = side.normalized();
  r.up = r.right.cross(r.forward);
  r.tanHalfFovY = std::tan(0.5 * c.fovYDegrees * std::numbers::pi / 180.0);
  r.width = c.width;
  r.height = c.height;
  r.aspect = double(c.width) / double(c.height);
  return r;
}

namespace {

double parseNumber(const std::string& key, std::string text, bool* millimetres = nullptr) {
  if (millimetres) {
    *millimetres = text.size() > 2 && text.compare(text.size() - 2, 2, "mm") == 0;
    if (*millimetres) text.resize(text.size() - 2);
  }
  double v = 0.0;
  const char* end = text.data() + text.size();
  const auto res = std::from_chars(text.data(), end, v);
  if (text.empty() || res.ec != std::errc() || res.ptr != end || !std::isfinite(v))
    throw UsageError("--camera", "'" + text + "' is not a number (key " + key + ")");
  return v;
}

Eigen::Vector3d parseVector(const std::string& key, const std::vector<std::string>& values) {
  if (values.size() != 3) throw UsageError("--camera", key + " needs three numbers x,y,z");
  return {parseNumber(key, values[0]), parseNumber(key, values[1]), parseNumber(key, values[2])};
}

}  // namespace

Camera parseCamera(const std::string& description, const Eigen::Vector3d& sceneMin, const Eigen::Vector3d& sceneMax, int width,
                   int height) {
  // key -> values; a token without '=' continues the previous key's list.
  std::map<std::string, std::vector<std::string>> keys;
  std::string current;
  std::size_t start = 0;
  while (start <= description.size() && !description.empty()) {
    std::size_t comma = description.find(',', start);
    if (comma == std::string::npos) comma = description.size();
    std::string token = description.substr(start, comma - start);
    start = comma + 1;
    while (!token.empty() && token.front() == ' ') token.erase(token.begin());
    while (!token.empty() && token.back() == ' ') token.pop_back();
    const std::size_t eq = token.find('=');
    if (eq != std::string::npos) {
      current = token.substr(0, eq);
      if (keys.count(current)) throw UsageError("--camera", "key '" + current + "' given twice");
      keys[current].push_back(token.substr(eq + 1));
    } else {
      if (current.empty()) throw UsageError("--camera", "expected key=value, got '" + token + "'");
      keys[current].push_back(token);
    }
  }
  static const std::vector<std::string> known = {"azimuth", "elevation", "distance", "fov", "eye", "target", "up"};
  for (const auto& [k, v] : keys) {
    if (std::find(known.begin(), known.end(), k) == known.end())
      throw UsageError("--camera", "unknown key '" + k + "' (azimuth, elevation, distance, fov, eye, target, up)");
    if (k != "eye" && k != "target" && k != "up" && v.size() != 1) throw UsageError("--camera", k + " takes one number");
  }

  Camera cam;
  cam.width = width;
  cam.height = height;
  if (keys.count("fov")) cam.fovYDegrees = parseNumber("fov", keys["fov"][0]);
  if (!(cam.fovYDegrees > 0.0 && cam.fovYDegrees < 180.0)) throw UsageError("--camera", "fov must be in (0, 180) degrees");
  cam.target = keys.count("target") ? parseVector("target", keys["target"]) : Eigen::Vector3d(0.5 * (sceneMin + sceneMax));
  if (keys.count("up")) cam.up = parseVector("up", keys["up"]);

  if (keys.count("eye")) {
    for (const char* k : {"azimuth", "elevation", "distance"})
      if (keys.count(k)) throw UsageError("--camera", std::string("eye cannot be combined with ") + k);
    cam.eye = parseVector("eye", keys["eye"]);
  } else {
    const double az = keys.count("azimuth") ? parseNumber("azimuth", keys["azimuth"][0]) : 0.0;
    const double el = keys.count("elevation") ? parseNumber("elevation", keys["elevation"][0]) : 0.0;
    if (std::abs(el) >= 90.0) throw UsageError("--camera", "elevation must be in (-90, 90) degrees");
    const double diagonal = (sceneMax - sceneMin).norm();
    const double a = az * std::numbers::pi / 180.0, e = el * std::numbers::pi / 180.0;
    // Direction from the target to the eye: azimuth 0 puts the eye on -y.
    const Eigen::Vector3d toEye(std::sin(a) * std::cos(e), -std::cos(a) * std::cos(e), std::sin(e));
    // Default: the nearest eye from which the box's eight corners project
    // inside the frame, kFrameMargin of the half-frame left free (a tall
    // body fills the frame's height rather than a sphere around it), or the
    // bounding sphere's fit where that is nearer.
    const double tanY = std::tan(0.5 * cam.fovYDegrees * std::numbers::pi / 180.0) * (1.0 - kFrameMargin);
    const double tanX = tanY * double(width) / double(height);
    const Eigen::Vector3d right = (-toEye).cross(cam.up).normalized();
    const Eigen::Vector3d up = right.cross(-toEye);
    double distance = 0.0;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d corner((c & 1) ? sceneMax.x() : sceneMin.x(), (c & 2) ? sceneMax.y() : sceneMin.y(),
                                   (c & 4) ? sceneMax.z() : sceneMin.z());
      const Eigen::Vector3d d = corner - cam.target;
      const double depth = d.dot(toEye);  // towards the eye
      distance = std::max({distance, depth + std::abs(d.dot(right)) / tanX, depth + std::abs(d.dot(up)) / tanY});
    }
    // Never farther than the bounding sphere's fit.
    const double halfY = 0.5 * cam.fovYDegrees * std::numbers::pi / 180.0;
    const double halfX = std::atan(std::tan(halfY) * double(width) / double(height));
    distance = std::min(distance, 0.5 * diagonal / std::sin(std::min(halfX, halfY)));
    if (keys.count("distance")) {
      bool mm = false;
      const double d = parseNumber("distance", keys["distance"][0], &mm);
      distance = mm ? d : d * diagonal;
    }
    if (!(distance > 0.0)) throw UsageError("--camera", "distance must be positive");
    cam.eye = cam.target + distance * toEye;
  }
  const CameraRays rays = cameraRays(cam);  // validates the result
  cam.depthNear = std::numeric_limits<double>::max();
  cam.depthFar = -cam.depthNear;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? sceneMax.x() : sceneMin.x(), (c & 2) ? sceneMax.y() : sceneMin.y(),
                                 (c & 4) ? sceneMax.z() : sceneMin.z());
    const double depth = (corner - rays.eye).dot(rays.forward);
    cam.depthNear = std::min(cam.depthNear, depth);
    cam.depthFar = std::max(cam.depthFar, depth);
  }
  return cam;
}

void parseImageSize(const std::string& text, int& width, int& height) {
  const std::size_t x = text.find_first_of("xX");
  auto parse = [&](const std::string& s) {
    int v = 0;
    const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || res.ec != std::errc() || res.ptr != s.data() + s.size() || v < 1 || v > 16384)
      throw UsageError("--size", "expected WIDTHxHEIGHT with both in 1..16384, got '" + text + "'");
    return v;
  };
  if (x == std::string::npos) throw UsageError("--size", "expected WIDTHxHEIGHT, got '" + text + "'");
  width = parse(text.substr(0, x));
  height = parse(text.substr(x + 1));
}

}  // namespace vox
