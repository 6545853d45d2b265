#include "app/viewer/orbit_camera.h"

#include <algorithm>
#include <cmath>

namespace vox::app {

int viewLeft(int /*windowWidth*/) { return int(kPanelWidth); }

Camera OrbitCamera::camera(int width, int height) const {
  const double az = azimuth * kPi / 180.0, el = elevation * kPi / 180.0;
  Camera c;
  c.target = target;
  c.eye = target + distance * Eigen::Vector3d(std::sin(az) * std::cos(el), -std::cos(az) * std::cos(el), std::sin(el));
  c.up = Eigen::Vector3d::UnitZ();
  c.fovYDegrees = fov;
  c.width = width;
  c.height = height;
  return c;
}

CameraRays OrbitCamera::viewRays(int fw, int fh) const { return cameraRays(camera(fw - viewLeft(fw), fh)); }

void OrbitCamera::fit(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  // The parsed default orbit fits the foreground box (render's framing).
  const Camera c = parseCamera("", lo, hi, 640, 480);
  target = c.target;
  distance = (c.eye - c.target).norm();
  fov = c.fovYDegrees;
}

void OrbitCamera::zoom(double notches) { distance *= std::pow(0.9, notches); }

void OrbitCamera::orbit(double dx, double dy) {
  azimuth -= 0.4 * dx;
  elevation = std::clamp(elevation + 0.4 * dy, -89.0, 89.0);
}

void OrbitCamera::pan(const CameraRays& rays, double dx, double dy) {
  const double mmPerPx = 2.0 * distance * rays.tanHalfFovY / rays.height;
  target += mmPerPx * (-dx * rays.right + dy * rays.up);
}

bool project(const CameraRays& r, const Eigen::Vector3d& p, float& x, float& y) {
  const Eigen::Vector3d k = p - r.eye;
  const double t = k.dot(r.forward);
  if (t <= 1e-6) return false;
  const double sx = k.dot(r.right) / t, sy = k.dot(r.up) / t;
  x = float(viewLeft(r.width + int(kPanelWidth)) + (sx / (r.tanHalfFovY * r.aspect) + 1.0) * 0.5 * r.width);
  y = float((1.0 - sy / r.tanHalfFovY) * 0.5 * r.height);
  return true;
}

}  // namespace vox::app
