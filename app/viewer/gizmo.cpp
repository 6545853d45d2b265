#include "app/viewer/gizmo.h"

#include "geometry/deform/pose/pose_editor.h"
#include "geometry/error.h"
#include "geometry/render/raycast_scene.h"
#include "geometry/skeleton/joints.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>

namespace vox::app {

namespace {

constexpr float kPickRadiusPx = 8.0f;

ImU32 rgba(int r, int g, int b, int a = 255) { return IM_COL32(r, g, b, a); }

// Gizmo radius in mm: a fixed share of the view at the centre's depth.
double gizmoRadiusMm(const CameraRays& rays, const Eigen::Vector3d& centre) {
  const double depth = std::max(1.0, (centre - rays.eye).dot(rays.forward));
  return 0.12 * depth * rays.tanHalfFovY * 2.0;
}

// The ring about axis n: the unit vectors u, v of its plane (u, v, n
// right-handed; for a grid axis, the next two grid axes).
void ringBasis(const Eigen::Vector3d& n, Eigen::Vector3d& u, Eigen::Vector3d& v) {
  for (int a = 0; a < 3; ++a)
    if (n == Eigen::Vector3d::Unit(a)) {
      u = Eigen::Vector3d::Unit((a + 1) % 3);
      v = Eigen::Vector3d::Unit((a + 2) % 3);
      return;
    }
  u = n.unitOrthogonal();
  v = n.normalized().cross(u);
}

// The point at angle t (radians) of the ring of radius r about axis n.
Eigen::Vector3d ringPoint(const Eigen::Vector3d& c, double r, const Eigen::Vector3d& n, double t) {
  Eigen::Vector3d u, v;
  ringBasis(n, u, v);
  return c + r * (std::cos(t) * u + std::sin(t) * v);
}

// The screen angle of the mouse about the gizmo centre, for a rotation about
// axis n: the signed angle (degrees, right-handed about n) in the ring's
// plane of the mouse ray's hit.
bool ringAngle(const CameraRays& rays, const Eigen::Vector3d& c, const Eigen::Vector3d& n, double mx, double my, double& angle) {
  mx -= viewLeft(rays.width + int(kPanelWidth));
  const Eigen::Vector3d dir = rays.forward + ((2.0 * mx / rays.width - 1.0) * rays.tanHalfFovY * rays.aspect) * rays.right +
                              ((1.0 - 2.0 * my / rays.height) * rays.tanHalfFovY) * rays.up;
  const double denom = dir.dot(n);
  if (std::abs(denom) < 1e-9) return false;
  const double t = (c - rays.eye).dot(n) / denom;
  const Eigen::Vector3d q = rays.eye + t * dir - c;
  Eigen::Vector3d u, v;
  ringBasis(n, u, v);
  angle = std::atan2(q.dot(v), q.dot(u)) * 180.0 / kPi;
  return true;
}

// A pointer move (dx, dy) as mm along axis a at c, as the axis appears on
// screen (r mm of it measured); false where it cannot be measured.
bool screenAxisMm(const CameraRays& rays, const Eigen::Vector3d& c, double r, int a, double dx, double dy, double& mm) {
  float x0, y0, x1, y1;
  if (!project(rays, c, x0, y0) || !project(rays, c + r * Eigen::Vector3d::Unit(a), x1, y1)) return false;
  const double ax = x1 - x0, ay = y1 - y0, len2 = ax * ax + ay * ay;
  if (!(len2 > 1e-6)) return false;
  mm = (dx * ax + dy * ay) / len2 * r;
  return true;
}

}  // namespace

std::vector<std::int32_t> cageVerticesInRect(const CameraRays& rays, const std::vector<Eigen::Vector3d>& cage, double x0, double y0,
                                             double x1, double y1) {
  std::vector<std::int32_t> inside;
  for (std::size_t v = 0; v < cage.size(); ++v) {
    float x, y;
    if (project(rays, cage[v], x, y) && x >= x0 && x <= x1 && y >= y0 && y <= y1) inside.push_back(std::int32_t(v));
  }
  return inside;
}

Gizmo::Target Gizmo::target() const {
  Target t;
  const EditState& s = editor_.state();
  if (s.joint >= 0) {
    const JointFrame f = editor_.jointFrame(s.joint);
    t.valid = true;
    t.centre = f.centre;
    t.axes = f.axes;
  } else if (s.active >= 0) {
    const PoseTransform& p = editor_.pose().selections[std::size_t(s.active)].transform;
    t.valid = t.arrows = true;
    t.centre = p.center + p.translation;
    t.axes = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  }
  return t;
}

void Gizmo::draw(const CameraRays& rays, const InputState& input, const Overlays& overlays, const RaycastMesh& mesh) const {
  ImDrawList* dl = ImGui::GetBackgroundDrawList();
  const auto projectAll = [&](const std::vector<Eigen::Vector3d>& pts) {
    std::vector<ImVec2> out(pts.size(), ImVec2(-1e9f, -1e9f));
    for (std::size_t i = 0; i < pts.size(); ++i) {
      float x, y;
      if (project(rays, pts[i], x, y)) out[i] = ImVec2(x, y);
    }
    return out;
  };
  const auto drawTriangles = [&](const std::vector<ImVec2>& p, const std::vector<Tri>& tris, ImU32 colour, float width) {
    // Closed surfaces: every edge appears once in each direction.
    for (const Tri& t : tris)
      for (int k = 0; k < 3; ++k) {
        const std::int32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
        const ImVec2 &pa = p[std::size_t(a)], &pb = p[std::size_t(b)];
        if (a < b && pa.x > -1e8f && pb.x > -1e8f) dl->AddLine(pa, pb, colour, width);
      }
  };
  if (overlays.tm) {
    std::vector<Tri> faces;
    for (const BoundaryFace& f : mesh.boundary) faces.push_back(f.vertices);
    drawTriangles(projectAll(editor_.transferMeshPositions()), faces, rgba(120, 220, 255, 90), 1.0f);
  }
  if (overlays.envelope && !editor_.pipeline().envelope().triangles.empty()) {
    const std::vector<Eigen::Vector3d>& env = editor_.posed() ? editor_.pipeline().deformedEnvelope() : editor_.pipeline().envelope().positions;
    drawTriangles(projectAll(env), editor_.pipeline().envelope().triangles, rgba(255, 230, 120, 70), 1.0f);
  }
  if (overlays.cage) {
    const std::vector<ImVec2> p = projectAll(editor_.builtCagePositions());
    drawTriangles(p, editor_.pipeline().builtCage().triangles, rgba(200, 200, 210, 140), 1.0f);
    const std::vector<std::int32_t> owners = editor_.handleOwners();
    const std::vector<std::int32_t>& picked = editor_.picked();
    const Pose& compiled = editor_.compiledPose();
    const int active = editor_.state().active < 0 ? -1 : editor_.state().active + int(editor_.ownSelectionsAt());
    for (std::size_t v = 0; v < p.size(); ++v) {
      if (p[v].x < -1e8f) continue;
      ImU32 c = rgba(230, 230, 235, 200);  // free
      const std::int32_t o = owners[v];
      if (o >= 0 && std::size_t(o) < compiled.selections.size())
        c = compiled.selections[std::size_t(o)].fixed ? rgba(90, 140, 255) : (o == active ? rgba(255, 150, 40) : rgba(255, 220, 60));
      const bool isPicked = std::binary_search(picked.begin(), picked.end(), std::int32_t(v));
      dl->AddCircleFilled(p[v], isPicked ? 5.0f : 3.0f, isPicked ? rgba(255, 60, 200) : c);
    }
  }
  // Axis cuts: the plane's section of the scene box and a handle to slide it.
  const Eigen::Vector3d &lo = cuts_.lo(), &hi = cuts_.hi();
  for (int a = 0; a < 3; ++a) {
    if (!cuts_.on[a]) continue;
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    ImVec2 corner[4];
    bool shown = true;
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector3d q;
      q[a] = cuts_.at[a];
      q[u] = (k == 0 || k == 3) ? lo[u] : hi[u];
      q[v] = k < 2 ? lo[v] : hi[v];
      shown = shown && project(rays, q, corner[k].x, corner[k].y);
    }
    float hx, hy;
    if (shown && project(rays, cuts_.handle(a), hx, hy)) {
      const ImU32 c = drag_ == DragKind::CutPlane && dragAxis_ == a ? rgba(255, 255, 255) : rgba(120, 255, 200, 200);
      dl->AddPolyline(corner, 4, c, ImDrawFlags_Closed, 1.5f);
      dl->AddCircleFilled(ImVec2(hx, hy), 7.0f, c);
    }
  }
  if (drag_ == DragKind::Rect) {
    dl->AddRect(ImVec2(float(dragX0_), float(dragY0_)), ImVec2(float(input.x), float(input.y)), rgba(255, 60, 200), 0, 0, 1.5f);
  }
  drawGizmo(rays);
}

void Gizmo::drawGizmo(const CameraRays& rays) const {
  const Target g = target();
  if (!g.valid) return;
  ImDrawList* dl = ImGui::GetForegroundDrawList();
  const Eigen::Vector3d& c = g.centre;
  const double r = gizmoRadiusMm(rays, c);
  const ImU32 colours[3] = {rgba(235, 70, 70), rgba(80, 210, 90), rgba(70, 130, 245)};
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d& n = g.axes[std::size_t(a)];
    if (n == Eigen::Vector3d::Zero()) continue;
    std::vector<ImVec2> ring;
    for (int k = 0; k <= 64; ++k) {
      float x, y;
      if (project(rays, ringPoint(c, r, n, 2.0 * kPi * k / 64.0), x, y)) ring.emplace_back(x, y);
    }
    const float width = (drag_ == DragKind::GizmoRotate && dragAxis_ == a) ? 4.0f : 2.0f;
    if (ring.size() > 1) dl->AddPolyline(ring.data(), int(ring.size()), colours[a], 0, width);
    float x0, y0, x1, y1;
    if (g.arrows && project(rays, c, x0, y0) && project(rays, c + 1.4 * r * n, x1, y1)) {
      dl->AddLine(ImVec2(x0, y0), ImVec2(x1, y1), colours[a], (drag_ == DragKind::GizmoTranslate && dragAxis_ == a) ? 5.0f : 3.0f);
      dl->AddCircleFilled(ImVec2(x1, y1), 6.0f, colours[a]);
    }
  }
  float x, y;
  if (!g.arrows && project(rays, c, x, y)) dl->AddCircleFilled(ImVec2(x, y), 4.0f, rgba(255, 255, 255));
}

bool Gizmo::handleMouse(const CameraRays& rays, InputState& input, bool ignoreUi) {
  const ImGuiIO& io = ImGui::GetIO();
  const bool overUi = !ignoreUi && (io.WantCaptureMouse || input.x < viewLeft(0)) && drag_ == DragKind::None;
  const double mx = input.x, my = input.y;
  bool cameraMoved = false;
  if (input.scroll != 0.0) {
    if (!overUi) {
      orbit_.zoom(input.scroll);
      cameraMoved = true;
    }
    input.scroll = 0.0;
  }
  const bool left = input.down[0], right = input.down[1], middle = input.down[2];
  if (drag_ == DragKind::None && !overUi && (left || right || middle)) {
    press(rays, mx, my, io.KeyCtrl, right || middle);
  } else if (drag_ != DragKind::None && (left || right || middle)) {
    cameraMoved = move(rays, mx, my) || cameraMoved;
    lastX_ = mx;
    lastY_ = my;
  } else if (drag_ != DragKind::None) {
    release(rays, mx, my, io.KeyShift);
  }
  return cameraMoved;
}

void Gizmo::press(const CameraRays& rays, double mx, double my, bool ctrl, bool otherButton) {
  dragX0_ = lastX_ = mx;
  dragY0_ = lastY_ = my;
  drag_ = DragKind::Orbit;
  if (otherButton) drag_ = DragKind::Pan;
  else if (ctrl) drag_ = DragKind::Rect;
  for (int a = 0; a < 3 && drag_ == DragKind::Orbit; ++a) {
    float hx, hy;
    if (cuts_.on[a] && project(rays, cuts_.handle(a), hx, hy) && std::hypot(hx - mx, hy - my) < 9.0) {
      drag_ = DragKind::CutPlane;
      dragAxis_ = a;
    }
  }
  const Target g = target();
  if (!g.valid || drag_ != DragKind::Orbit) return;
  // Gizmo handles first: arrow tips, then rings.
  const Eigen::Vector3d& c = g.centre;
  const double r = gizmoRadiusMm(rays, c);
  for (int a = 0; a < 3 && g.arrows && drag_ == DragKind::Orbit; ++a) {
    float x, y;
    if (project(rays, c + 1.4 * r * g.axes[std::size_t(a)], x, y) && std::hypot(x - mx, y - my) < 10.0) {
      drag_ = DragKind::GizmoTranslate;
      dragAxis_ = a;
    }
  }
  // The ring nearest the pointer, within a few pixels.
  double nearest = 7.0;
  for (int a = 0; a < 3 && drag_ != DragKind::GizmoTranslate; ++a) {
    if (g.axes[std::size_t(a)] == Eigen::Vector3d::Zero()) continue;
    for (int k = 0; k < 128; ++k) {
      float x, y;
      if (project(rays, ringPoint(c, r, g.axes[std::size_t(a)], 2.0 * kPi * k / 128.0), x, y))
        if (const double d = std::hypot(x - mx, y - my); d < nearest) {
          nearest = d;
          drag_ = DragKind::GizmoRotate;
          dragAxis_ = a;
        }
    }
  }
  if (drag_ == DragKind::GizmoRotate) ringAngle(rays, c, g.axes[std::size_t(dragAxis_)], mx, my, dragAngle_);
  if (drag_ == DragKind::GizmoRotate && editor_.state().joint >= 0) {
    jointStart_ = editor_.jointAngle(editor_.state().joint, dragAxis_);
    jointTurn_ = 0.0;
  }
  if (drag_ == DragKind::GizmoRotate || drag_ == DragKind::GizmoTranslate) editor_.beginDrag();
}

bool Gizmo::move(const CameraRays& rays, double mx, double my) {
  const double dx = mx - lastX_, dy = my - lastY_;
  switch (drag_) {
    case DragKind::Orbit:
      orbit_.orbit(dx, dy);
      return dx != 0 || dy != 0;
    case DragKind::Pan:
      orbit_.pan(rays, dx, dy);
      return true;
    case DragKind::GizmoRotate: {
      const Target g = target();
      double angle = 0.0;
      if (ringAngle(rays, g.centre, g.axes[std::size_t(dragAxis_)], mx, my, angle)) {
        double delta = angle - dragAngle_;
        while (delta > 180.0) delta -= 360.0;
        while (delta < -180.0) delta += 360.0;
        const int joint = editor_.state().joint;
        if (joint >= 0) {
          // The ring's turn since the press, the angle held to the joint's range.
          jointTurn_ += delta;
          const auto& range = skeleton::jointKind(skeleton::JointId(joint)).range[std::size_t(dragAxis_)];
          editor_.setJointAngle(joint, dragAxis_, std::clamp(jointStart_ + jointTurn_, range[0], range[1]), true);
        } else if (delta != 0.0) {
          editor_.rotateActive(Eigen::Vector3d::Unit(dragAxis_), delta, true);
        }
        dragAngle_ = angle;
      }
      break;
    }
    case DragKind::GizmoTranslate: {
      const Eigen::Vector3d c = target().centre;
      double mm = 0.0;
      if (screenAxisMm(rays, c, gizmoRadiusMm(rays, c), dragAxis_, dx, dy, mm) && mm != 0.0)
        editor_.translateActive(mm * Eigen::Vector3d::Unit(dragAxis_), true);
      break;
    }
    case DragKind::CutPlane: {
      // Along the plane's axis as it appears on screen.
      const Eigen::Vector3d c = cuts_.handle(dragAxis_);
      double mm = 0.0;
      if (screenAxisMm(rays, c, gizmoRadiusMm(rays, c), dragAxis_, dx, dy, mm)) cuts_.slide(dragAxis_, mm);
      break;
    }
    default: break;
  }
  return false;
}

void Gizmo::release(const CameraRays& rays, double mx, double my, bool shift) {
  if (drag_ == DragKind::CutPlane) cuts_.commit(editor_);
  const bool click = std::hypot(mx - dragX0_, my - dragY0_) < 3.0;
  const std::vector<Eigen::Vector3d> cage = editor_.builtCagePositions();
  if (drag_ == DragKind::Rect) {
    editor_.pick(cageVerticesInRect(rays, cage, std::min(dragX0_, mx), std::min(dragY0_, my), std::max(dragX0_, mx), std::max(dragY0_, my)),
                 shift);
  } else if (drag_ == DragKind::Orbit && click) {
    std::int32_t best = -1;
    double bestD = kPickRadiusPx;
    for (std::size_t v = 0; v < cage.size(); ++v) {
      float x, y;
      if (project(rays, cage[v], x, y))
        if (const double d = std::hypot(x - mx, y - my); d < bestD) {
          bestD = d;
          best = std::int32_t(v);
        }
    }
    if (best >= 0) editor_.pick({best}, shift);
    else if (!shift) editor_.clearPicked();
  }
  drag_ = DragKind::None;
  dragAxis_ = -1;
}

PointerPath Gizmo::rotatePath(const CameraRays& rays, int axis, double degrees, int steps) const {
  // Through the gizmo's drag code: press on the ring, move along it, release.
  const Target g = target();
  if (!g.valid || g.axes[std::size_t(axis)] == Eigen::Vector3d::Zero())
    throw InputError("script", "gizmo_rotate: the gizmo has no such ring (no active selection or selected joint, or a degree of freedom the joint lacks)");
  const Eigen::Vector3d& c = g.centre;
  const Eigen::Vector3d& n = g.axes[std::size_t(axis)];
  const double r = gizmoRadiusMm(rays, c);
  // Start at the point of the ring farthest on screen from the other rings.
  double start = 0.0, widest = -1.0;
  for (int k = 0; k < 32; ++k) {
    const double t = 2.0 * kPi * (k + 0.5) / 32.0;
    float x, y;
    if (!project(rays, ringPoint(c, r, n, t), x, y)) continue;
    double clearance = 1e30;
    for (int b = 0; b < 3; ++b) {
      if (b == axis || g.axes[std::size_t(b)] == Eigen::Vector3d::Zero()) continue;
      for (int j = 0; j < 128; ++j) {
        float bx, by;
        if (project(rays, ringPoint(c, r, g.axes[std::size_t(b)], 2.0 * kPi * j / 128.0), bx, by))
          clearance = std::min(clearance, double(std::hypot(bx - x, by - y)));
      }
    }
    if (clearance > widest) {
      widest = clearance;
      start = t;
    }
  }
  PointerPath path{{}, DragKind::GizmoRotate};
  for (int k = 0; k <= steps; ++k) {
    float x = 0, y = 0;
    project(rays, ringPoint(c, r, n, start + degrees * kPi / 180.0 * k / steps), x, y);
    path.points.emplace_back(x, y);
  }
  return path;
}

PointerPath Gizmo::translatePath(const CameraRays& rays, int axis, double mm, int steps) const {
  const Target g = target();
  if (!g.arrows) throw InputError("script", "gizmo_translate: no active selection (a joint only turns)");
  const Eigen::Vector3d c = g.centre;
  const double r = gizmoRadiusMm(rays, c);
  float x0, y0, x1, y1;
  project(rays, c, x0, y0);
  project(rays, c + 1.4 * r * Eigen::Vector3d::Unit(axis), x1, y1);
  const double pxPerMm = std::hypot(x1 - x0, y1 - y0) / (1.4 * r);
  PointerPath path{{}, DragKind::GizmoTranslate};
  for (int k = 0; k <= steps; ++k) {
    const double f = mm * pxPerMm * k / steps / std::hypot(x1 - x0, y1 - y0);
    path.points.emplace_back(x1 + f * (x1 - x0), y1 + f * (y1 - y0));
  }
  return path;
}

PointerPath Gizmo::cutPath(const CameraRays& rays, int axis, double mm, int steps) const {
  // Press on the plane's handle, drag it along its axis, release.
  if (!cuts_.on[axis]) throw InputError("script", "cut_drag: that axis has no cutting plane");
  const Eigen::Vector3d c = cuts_.handle(axis);
  PointerPath path{{}, DragKind::CutPlane};
  for (int k = 0; k <= steps; ++k) {
    float x = 0, y = 0;
    project(rays, c + (mm * k / steps) * Eigen::Vector3d::Unit(axis), x, y);
    path.points.emplace_back(x, y);
  }
  return path;
}

}  // namespace vox::app
