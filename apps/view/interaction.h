#pragma once
// The viewer's geometry without OpenGL, so it is tested headlessly: the orbit camera, the translate /
// rotate gizmo on a handle, brush and lasso selection in screen space with a depth test, and the
// scripted mode's commands.
//
// Screen coordinates are pixels of the 3D view: x to the right, y downwards, origin at the view's top
// left corner; depth is OpenGL's window depth in [0, 1] (0 at the near plane).

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "msdeform/core/types.h"

namespace msd::view {

using Vec2 = Eigen::Vector2d;

// A camera orbiting a target point: yaw about the world up axis, pitch above the horizon, distance.
class OrbitCamera {
 public:
  // Frames positions P (#V×3, finite): the camera looks at the bounding-box centre from the direction
  // the still pictures use (analysis/render.h, view_axes()), or along `view_direction` when it is not
  // zero, with `up` upwards, at a distance that shows the whole shape in a view of width×height pixels.
  void frame(const Positions& P, const Vec3& up, const Vec3& view_direction, int width, int height);
  void resize(int width, int height);

  void orbit(double dx_pixels, double dy_pixels);  // drag: 0.3° per pixel, pitch kept within ±89°
  void pan(double dx_pixels, double dy_pixels);    // the target follows the cursor in the target's plane
  void zoom(double steps);                         // scroll: 10 % closer per step (0.001 to 1000 radii away)

  Vec3 eye() const;
  Vec3 forward() const;  // unit, from the eye towards the target
  Vec3 right() const;
  Vec3 screen_up() const;
  // Column-major 4×4 OpenGL matrices (right-handed view, perspective projection).
  Mat4 view_matrix() const;
  Mat4 projection_matrix() const;
  // The drawing frame set by frame(): positions go to OpenGL as (p − frame_origin()) / frame_unit() in
  // single precision, and these matrices take such positions to clip space (the view to eye space in
  // frame units, the projection divided by the unit: homogeneous, so the same pixels and depths). Floats
  // then keep their digits at any size and place (raw coordinates lost them 1e6 sizes from the origin, and
  // at sizes of 1e-15 or 1e20 the drawn vertices missed their pixels: tests/view).
  const Vec3& frame_origin() const { return origin_; }
  double frame_unit() const { return unit_; }
  Mat4 frame_view_matrix() const;
  Mat4 frame_projection_matrix() const;
  // Pixel coordinates and window depth of world point p (depth outside [0, 1] when it is clipped).
  Vec3 project(const Vec3& p) const;
  // The same with projection_matrix() * view_matrix() computed once by the caller.
  Vec3 project(const Mat4& view_projection, const Vec3& p) const;
  // World units per pixel at the distance of p from the eye (along the view direction).
  double pixel_size_at(const Vec3& p) const;
  int width() const { return width_; }
  int height() const { return height_; }
  const Vec3& target() const { return target_; }
  double distance() const { return distance_; }

 private:
  Vec3 up_ = Vec3::UnitZ(), front_ = Vec3::UnitY(), side_ = Vec3::UnitX();  // world axes, side = front × up
  Vec3 target_ = Vec3::Zero();
  double yaw_ = 0, pitch_ = 0.5, distance_ = 3, radius_ = 1;
  Vec3 origin_ = Vec3::Zero();
  double unit_ = 1;
  double fov_degrees_ = 35;
  int width_ = 800, height_ = 600;
};

// Positions X (#V×3) as the viewer hands them to OpenGL, row by row into out (resized to 3·#V): in the
// camera's drawing frame, (p − frame_origin()) / frame_unit() in single precision, for the matrices
// frame_view_matrix() and frame_projection_matrix().
void drawing_positions(const OrbitCamera& camera, const Positions& X, std::vector<float>& out);

// The gizmo on the active handle, drawn as three axis arrows (x red, y green, z blue) and a centre disc.
enum class GizmoMode { Translate, Rotate };
enum class GizmoPart { None, X, Y, Z, Center };

struct Gizmo {
  Vec3 center = Vec3::Zero();  // world position (the handle's centroid where its transform puts it)
  double arrow_pixels = 90;    // on-screen length of each axis arrow
  double pick_pixels = 8;      // how close the cursor must come to an arrow, the centre disc or the ring

  // World end of the arrow of axis 0, 1 or 2 (its on-screen length is arrow_pixels).
  Vec3 arrow_tip(const OrbitCamera& camera, int axis) const;
  // Radius in pixels of the ring that turns about the view direction (Rotate; outside the arrows).
  double ring_pixels() const { return 1.3 * arrow_pixels; }
  // The part under the cursor: Center is the disc on the centre (Translate) or the ring around it
  // (Rotate); otherwise the nearest arrow within pick_pixels.
  GizmoPart pick(const OrbitCamera& camera, GizmoMode mode, const Vec2& cursor) const;
  // The world transform a drag of `part` from `from` to `to` (pixels) applies:
  //   Translate: an arrow moves along its axis by the cursor's motion along the arrow on screen; the
  //   centre moves in the view plane.
  //   Rotate: about the axis through the centre by the angle the cursor sweeps around the centre on
  //   screen (the ring: about the view direction), so the handle turns with the cursor.
  Mat4 drag(const OrbitCamera& camera, GizmoMode mode, GizmoPart part, const Vec2& from, const Vec2& to) const;
};

// The angle in degrees, in [0, 180], of the rotation in T's linear part (core/rotation.h).
double turn_degrees(const Mat4& T);

// Whether a handle turned by `from` stays below half a turn from rest all along the shortest turn to
// `to` (rotations of their polar decompositions; checked every degree, with a degree's margin). A transform
// keeps a rotation only up to whole turns (200° is the −160° transform), so a handle turned half a turn or
// more would not come back from the .def that save-def writes (a method that blends rotations, or iterates
// from the shown shape, turns it the other way round): `deform --rotate` refuses such turns too.
bool turn_stays_below_half(const Mat4& from, const Mat4& to);

// Why a turn was stopped (the viewer's message; `handle` its index).
std::string half_turn_message(int handle, const Mat4& start);

// The window depth buffer of the 3D view, row 0 at the top (as screen coordinates), for visibility tests.
struct DepthImage {
  int width = 0, height = 0;
  std::vector<float> depth;  // width×height values in [0, 1]; 1 where nothing was drawn
  // Whether a point at pixel (x, y) with window depth d is in front of (or on) the drawn surface.
  bool visible(double x, double y, double d, double tolerance) const;
};

// Screen positions (x, y, depth) of every vertex, one row each (#V×3), from the camera.
Positions project_vertices(const OrbitCamera& camera, const Positions& P);
// Vertices within `radius` pixels of `center` that are visible in `depth`.
std::vector<int> brush_select(const Positions& screen, const Vec2& center, double radius, const DepthImage& depth);
// Vertices inside the closed polygon `lasso` (pixels, even-odd rule) that are visible in `depth`.
std::vector<int> lasso_select(const Positions& screen, const std::vector<Vec2>& lasso, const DepthImage& depth);

// One line of a viewer script (--script FILE): a verb and its arguments, with the line for messages.
struct ScriptCommand {
  std::string verb;
  std::vector<std::string> args;
  int line = 0;
};

// Reads a script: one command per line, '#' starts a comment. The verbs (arguments in brackets optional):
//   method NAME                       the catalogue method (shell, arap, multiscale-normal, ...)
//   handle K                          the active handle (0-based)
//   translate DX DY DZ [STEPS]        move the active handle by a world vector in STEPS frames (10)
//   rotate AX AY AZ DEGREES [STEPS]   turn it about an axis through its centroid
//   gizmo translate|rotate x|y|z|center DX DY [STEPS]
//                                     a mouse drag on the gizmo part by DX, DY pixels, through the same
//                                     code as the mouse (pick, drag) in STEPS frames
//   orbit DX DY | zoom STEPS          move the camera
//   paint fixed|free|handle K X Y RADIUS
//                                     a brush stroke at pixel (X, Y) of the 3D view, radius in pixels
//   lasso fixed|free|handle K X1 Y1 X2 Y2 X3 Y3 ...
//   color region|rigidity|detail|none    shading flat|smooth
//   converge                          iterate a nonlinear method until it converges (at most 10 s)
//   screenshot PATH [window]          the 3D view (without the panel and gizmo) as a PNG; with
//                                     `window`, the whole window as drawn (panel, gizmo)
//   save-mesh PATH | save-sel PATH | save-def PATH
//   reset                             every handle back to rest
// \throw InvalidInput naming the file and line for an unknown verb or a wrong argument count or number.
std::vector<ScriptCommand> read_script(const std::string& path);
// The numeric argument i of a command. \throw InvalidInput naming the line.
double script_number(const ScriptCommand& command, size_t i, const std::string& path);

}  // namespace msd::view
