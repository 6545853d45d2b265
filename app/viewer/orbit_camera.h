#pragma once
// The viewer's orbit camera and the screen layout of its view: the ray-cast
// view fills the window right of the panel column, and grid-frame points map
// to window pixels through the view's camera rays.

#include "geometry/render/camera.h"

#include <Eigen/Core>

namespace vox::app {

constexpr double kPi = 3.14159265358979323846;
constexpr float kPanelWidth = 360.0f;

// Left edge of the ray-cast view in window pixels (the panel's width).
int viewLeft(int windowWidth);

// Orbit camera around a target, z up (camera.h conventions: azimuth 0 looks
// along +y, azimuth 90 along -x).
struct OrbitCamera {
  Eigen::Vector3d target{0, 0, 0};
  double distance = 1000.0;
  double azimuth = 0.0, elevation = 0.0;  // degrees
  double fov = 35.0;

  Camera camera(int width, int height) const;
  // The rays of the view area of a window of fw x fh pixels.
  CameraRays viewRays(int fw, int fh) const;
  // Frames the box lo..hi as `render`'s default camera does (keeps the angles).
  void fit(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
  // Mouse gestures, in window pixels (wheel notches for zoom).
  void zoom(double notches);
  void orbit(double dx, double dy);
  void pan(const CameraRays& rays, double dx, double dy);
};

// Grid-frame point -> window pixel (x right, y down) for rays of the view
// area; false behind the eye.
bool project(const CameraRays& rays, const Eigen::Vector3d& p, float& x, float& y);

}  // namespace vox::app
