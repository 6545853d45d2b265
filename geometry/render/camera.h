#pragma once
// Pinhole camera for the ray caster, and its command-line description.
//
// Coordinates are the grid frame (mm). An orbit camera turns around a target
// (by default the centre of the scene box) with z up: azimuth 0 looks along
// +y (the camera sits on the -y side), azimuth 90 looks along -x, elevation
// lifts the camera above the xy plane.

#include <Eigen/Core>

#include <string>

namespace vox {

// Share of the half-frame the default camera leaves free around the scene.
inline constexpr double kFrameMargin = 0.05;

struct Camera {
  Eigen::Vector3d eye{0, -1, 0};
  Eigen::Vector3d target{0, 0, 0};
  Eigen::Vector3d up{0, 0, 1};  // need not be orthogonal to the view direction
  double fovYDegrees = 35.0;    // vertical field of view
  int width = 640;
  int height = 480;
  // Depth along the view axis (mm) of the scene box's nearest and farthest
  // corners, set by parseCamera: the range of the shading's depth cue (none
  // when far <= near). Part of the camera so that two renders of one scene
  // with one camera shade alike.
  double depthNear = 0.0, depthFar = 0.0;
};

// Orthonormal basis and per-pixel rays of a camera.
struct CameraRays {
  Eigen::Vector3d eye;
  Eigen::Vector3d forward;  // unit, towards the target
  Eigen::Vector3d right;    // unit; image x grows along it
  Eigen::Vector3d up;       // unit; image y grows against it (row 0 at the top)
  double tanHalfFovY = 0.0;
  double aspect = 1.0;      // width / height
  int width = 0;
  int height = 0;

  // Image-plane offsets of the centre of pixel (x, y): the ray direction is
  // forward + sx * right + sy * up (not normalized).
  double sx(int x) const { return (2.0 * (double(x) + 0.5) / double(width) - 1.0) * tanHalfFovY * aspect; }
  double sy(int y) const { return (1.0 - 2.0 * (double(y) + 0.5) / double(height)) * tanHalfFovY; }
  Eigen::Vector3d direction(int x, int y) const { return forward + sx(x) * right + sy(y) * up; }
};

// Throws InputError("camera", ...) when eye == target, up is parallel to the
// view direction, the field of view is outside (0, 180) or the size is not
// positive.
CameraRays cameraRays(const Camera& camera);

// Parses a camera description, a comma-separated list of key=value:
//   azimuth=30,elevation=10,distance=2.5,fov=35   orbit around the scene box
//   eye=x,y,z,target=x,y,z,up=x,y,z,fov=35        explicit (mm)
// Orbit keys: azimuth and elevation in degrees (default 0, 0); distance in
// scene-box diagonals, or in mm with an "mm" suffix (default: the distance at
// which the box's bounding sphere fills the view); target=x,y,z overrides the
// box centre. fov is vertical, in degrees (default 35). An empty description
// is the default orbit. The scene box (grid frame, mm) and the image size
// complete the camera. Throws InputError("--camera", ...) for unknown keys,
// malformed numbers or mixed orbit/explicit keys.
Camera parseCamera(const std::string& description, const Eigen::Vector3d& sceneMin, const Eigen::Vector3d& sceneMax, int width,
                   int height);

// Parses "640x480"; throws InputError("--size", ...) unless both are in 1..16384.
void parseImageSize(const std::string& text, int& width, int& height);

}  // namespace vox
