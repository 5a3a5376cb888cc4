#include "apps/view/interaction.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <Eigen/Geometry>

#include "msdeform/core/errors.h"
#include "msdeform/core/rotation.h"

namespace msd::view {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180;

Vec3 any_perpendicular(const Vec3& n) {
  const Vec3 a = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return n.cross(a).normalized();
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Camera

void OrbitCamera::frame(const Positions& P, const Vec3& up, const Vec3& view_direction, int width, int height) {
  const Vec3 lo = P.colwise().minCoeff().transpose(), hi = P.colwise().maxCoeff().transpose();
  target_ = origin_ = 0.5 * (lo + hi);
  unit_ = 0.5 * (hi - lo).maxCoeff();
  if (!(unit_ > 0) || !std::isfinite(unit_)) unit_ = 1;
  // In frame units, without a floor: the radius was clamped at 1e-12 (a smaller shape was framed far too
  // wide), and the squares of coordinates below 1e-154 underflowed.
  radius_ =
      unit_ * std::sqrt(((P.rowwise() - origin_.transpose()) / unit_).rowwise().squaredNorm().maxCoeff());
  if (!(radius_ > 0)) radius_ = unit_;
  up_ = up.normalized();
  Vec3 d = view_direction.norm() > 0 ? view_direction.normalized() : Vec3(-0.6, -1.0, 0.8).normalized();
  Vec3 horizontal = d - d.dot(up_) * up_;
  if (horizontal.norm() < 1e-6) horizontal = any_perpendicular(up_);
  front_ = horizontal.normalized();  // the direction towards the camera at yaw 0
  side_ = up_.cross(front_);
  yaw_ = 0;
  pitch_ = std::asin(std::clamp(d.dot(up_), -1.0, 1.0));
  resize(width, height);
  const double half_fov = 0.5 * fov_degrees_ * kDegree;
  const double aspect = static_cast<double>(width_) / height_;
  const double half_fov_x = std::atan(std::tan(half_fov) * aspect);
  distance_ = 1.1 * radius_ / std::sin(std::min(half_fov, half_fov_x));
}

void OrbitCamera::resize(int width, int height) {
  width_ = std::max(width, 1);
  height_ = std::max(height, 1);
}

void OrbitCamera::orbit(double dx_pixels, double dy_pixels) {
  yaw_ -= 0.3 * kDegree * dx_pixels;
  pitch_ = std::clamp(pitch_ + 0.3 * kDegree * dy_pixels, -89 * kDegree, 89 * kDegree);
}

void OrbitCamera::pan(double dx_pixels, double dy_pixels) {
  const double s = pixel_size_at(target_);
  target_ += (-dx_pixels * right() + dy_pixels * screen_up()) * s;
}

void OrbitCamera::zoom(double steps) {
  distance_ = std::clamp(distance_ * std::pow(0.9, steps), 1e-3 * radius_, 1e3 * radius_);
}

Vec3 OrbitCamera::eye() const {
  const Vec3 towards_camera =
      std::cos(pitch_) * (std::cos(yaw_) * front_ + std::sin(yaw_) * side_) + std::sin(pitch_) * up_;
  return target_ + distance_ * towards_camera;
}

Vec3 OrbitCamera::forward() const { return (target_ - eye()).normalized(); }

Vec3 OrbitCamera::right() const {
  const Vec3 r = forward().cross(up_);
  return r.norm() > 1e-9 ? r.normalized() : side_;
}

Vec3 OrbitCamera::screen_up() const { return right().cross(forward()); }

Mat4 OrbitCamera::view_matrix() const {
  Mat4 V = Mat4::Identity();
  const Vec3 r = right(), u = screen_up(), f = forward(), e = eye();
  V.block<1, 3>(0, 0) = r.transpose();
  V.block<1, 3>(1, 0) = u.transpose();
  V.block<1, 3>(2, 0) = -f.transpose();
  V(0, 3) = -r.dot(e);
  V(1, 3) = -u.dot(e);
  V(2, 3) = f.dot(e);
  return V;
}

Mat4 OrbitCamera::projection_matrix() const {
  const double f = 1 / std::tan(0.5 * fov_degrees_ * kDegree);
  const double aspect = static_cast<double>(width_) / height_;
  const double near = std::max(1e-3 * distance_, distance_ - 3 * radius_), far = distance_ + 3 * radius_;
  Mat4 M = Mat4::Zero();
  M(0, 0) = f / aspect;
  M(1, 1) = f;
  M(2, 2) = (far + near) / (near - far);
  M(2, 3) = 2 * far * near / (near - far);
  M(3, 2) = -1;
  return M;
}

Mat4 OrbitCamera::frame_view_matrix() const {
  Mat4 to_world = Mat4::Identity();  // T(origin) S(unit)
  to_world.topLeftCorner<3, 3>() *= unit_;
  to_world.topRightCorner<3, 1>() = origin_;
  Mat4 to_frame_units = Mat4::Identity();  // S(1 / unit)
  to_frame_units.topLeftCorner<3, 3>() /= unit_;
  return to_frame_units * view_matrix() * to_world;
}

Mat4 OrbitCamera::frame_projection_matrix() const {
  Mat4 M = projection_matrix();
  M.leftCols<3>() *= unit_;  // projection S(unit): eye space in frame units
  return M / unit_;
}

void drawing_positions(const OrbitCamera& camera, const Positions& X, std::vector<float>& out) {
  out.resize(static_cast<size_t>(X.size()));
  const Vec3& origin = camera.frame_origin();
  const double unit = camera.frame_unit();
  for (Eigen::Index v = 0; v < X.rows(); ++v)
    for (int k = 0; k < 3; ++k) out[3 * v + k] = static_cast<float>((X(v, k) - origin[k]) / unit);
}

Vec3 OrbitCamera::project(const Vec3& p) const { return project(projection_matrix() * view_matrix(), p); }

Vec3 OrbitCamera::project(const Mat4& view_projection, const Vec3& p) const {
  const Eigen::Vector4d clip = view_projection * Eigen::Vector4d(p.x(), p.y(), p.z(), 1);
  if (clip.w() <= 0) return Vec3(0, 0, -1);  // behind the eye
  const Vec3 ndc = clip.head<3>() / clip.w();
  return Vec3(0.5 * (ndc.x() + 1) * width_, 0.5 * (1 - ndc.y()) * height_, 0.5 * (ndc.z() + 1));
}

double OrbitCamera::pixel_size_at(const Vec3& p) const {
  const double z = std::max((p - eye()).dot(forward()), 1e-6 * distance_);
  return 2 * z * std::tan(0.5 * fov_degrees_ * kDegree) / height_;
}

// ---------------------------------------------------------------------------------------------------
// Gizmo

Vec3 Gizmo::arrow_tip(const OrbitCamera& camera, int axis) const {
  return center + Vec3::Unit(axis) * arrow_pixels * camera.pixel_size_at(center);
}

GizmoPart Gizmo::pick(const OrbitCamera& camera, GizmoMode mode, const Vec2& cursor) const {
  const Vec2 c = camera.project(center).head<2>();
  const double r = (cursor - c).norm();
  if (mode == GizmoMode::Translate ? r <= std::max(pick_pixels, 10.0) : std::abs(r - ring_pixels()) <= pick_pixels)
    return GizmoPart::Center;
  GizmoPart best = GizmoPart::None;
  double best_distance = pick_pixels;
  for (int axis = 0; axis < 3; ++axis) {
    const Vec2 tip = camera.project(arrow_tip(camera, axis)).head<2>();
    const Vec2 s = tip - c;
    const double t = s.squaredNorm() > 0 ? std::clamp((cursor - c).dot(s) / s.squaredNorm(), 0.0, 1.0) : 0.0;
    const double distance = (cursor - (c + t * s)).norm();
    if (distance <= best_distance) {
      best_distance = distance;
      best = static_cast<GizmoPart>(static_cast<int>(GizmoPart::X) + axis);
    }
  }
  return best;
}

Mat4 Gizmo::drag(const OrbitCamera& camera, GizmoMode mode, GizmoPart part, const Vec2& from, const Vec2& to) const {
  Mat4 T = Mat4::Identity();
  if (part == GizmoPart::None) return T;
  const double pixel = camera.pixel_size_at(center);
  const Vec2 c = camera.project(center).head<2>();
  const int axis = static_cast<int>(part) - static_cast<int>(GizmoPart::X);  // 0..2 for an arrow
  if (mode == GizmoMode::Translate) {
    if (part == GizmoPart::Center) {
      const Vec2 d = to - from;
      T.topRightCorner<3, 1>() = (d.x() * camera.right() - d.y() * camera.screen_up()) * pixel;
      return T;
    }
    const Vec2 s = camera.project(arrow_tip(camera, axis)).head<2>() - c;
    if (s.norm() < 1) return T;  // the arrow points at the viewer: no direction on screen to follow
    const double along = (to - from).dot(s) / s.squaredNorm();  // in arrow lengths
    T.topRightCorner<3, 1>() = Vec3::Unit(axis) * along * arrow_pixels * pixel;
    return T;
  }
  // Rotate: the angle swept around the centre, counter-clockwise on screen (y down) positive, which is a
  // positive turn about the axis pointing at the viewer.
  const Vec2 u = from - c, w = to - c;
  if (u.norm() < 1 || w.norm() < 1) return T;
  const double angle = std::atan2(u.x() * -w.y() - -u.y() * w.x(), u.dot(w));
  const Vec3 towards_viewer = -camera.forward();
  Vec3 a = towards_viewer;
  double sign = 1;
  if (part != GizmoPart::Center) {
    a = Vec3::Unit(axis);
    sign = a.dot(towards_viewer) >= 0 ? 1 : -1;
  }
  const Eigen::Matrix3d R = Eigen::AngleAxisd(sign * angle, a).toRotationMatrix();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = center - R * center;
  return T;
}

double turn_degrees(const Mat4& T) { return msd::turn_degrees(Mat3(T.topLeftCorner<3, 3>())); }

bool turn_stays_below_half(const Mat4& from, const Mat4& to) {
  // The shortest turn from one to the other is by θ about an axis; along it the handle's turn from rest
  // moves by at most θ/m per m-th, so checking m + 1 samples with that margin bounds it all the way
  // (conservative within 1° of 180°).
  const Mat3 start = polar_decomposition(from.topLeftCorner<3, 3>()).rotation;
  const Eigen::AngleAxisd turn(polar_decomposition(to.topLeftCorner<3, 3>()).rotation * start.transpose());
  const double theta = std::abs(turn.angle()) / kDegree;
  const int m = std::max(1, static_cast<int>(std::ceil(theta)));
  for (int i = 0; i <= m; ++i) {
    Mat4 at = Mat4::Identity();
    at.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(turn.angle() * i / m, turn.axis()).toRotationMatrix() * start;
    if (!(turn_degrees(at) + theta / m < 180)) return false;
  }
  return true;
}

std::string half_turn_message(int handle, const Mat4& start) {
  char text[400];
  std::snprintf(
      text, sizeof text,
      "handle %d stops at %.0f degrees from rest: half a turn is as far as a handle "
      "turns (its transform is a matrix, which keeps a rotation only up to whole turns, so a .def saved past "
      "it would give the shape turned the other way round); turn it back, or reset",
      handle, turn_degrees(start));
  return text;
}

// ---------------------------------------------------------------------------------------------------
// Selection

bool DepthImage::visible(double x, double y, double d, double tolerance) const {
  const int px = static_cast<int>(std::floor(x)), py = static_cast<int>(std::floor(y));
  if (px < 0 || py < 0 || px >= width || py >= height || d < 0 || d > 1) return false;
  // The farthest surface drawn around the pixel, so vertices on a silhouette count as visible.
  float farthest = 0;
  for (int j = std::max(py - 1, 0); j <= std::min(py + 1, height - 1); ++j)
    for (int i = std::max(px - 1, 0); i <= std::min(px + 1, width - 1); ++i)
      farthest = std::max(farthest, depth[static_cast<size_t>(j) * width + i]);
  return d <= farthest + tolerance;
}

Positions project_vertices(const OrbitCamera& camera, const Positions& P) {
  const Mat4 M = camera.projection_matrix() * camera.view_matrix();  // once, not per vertex
  Positions S(P.rows(), 3);
  for (Eigen::Index v = 0; v < P.rows(); ++v) S.row(v) = camera.project(M, P.row(v).transpose()).transpose();
  return S;
}

namespace {
constexpr double kDepthTolerance = 2e-3;
}

std::vector<int> brush_select(const Positions& screen, const Vec2& center, double radius, const DepthImage& depth) {
  std::vector<int> out;
  for (Eigen::Index v = 0; v < screen.rows(); ++v)
    if ((Vec2(screen(v, 0), screen(v, 1)) - center).norm() <= radius &&
        depth.visible(screen(v, 0), screen(v, 1), screen(v, 2), kDepthTolerance))
      out.push_back(static_cast<int>(v));
  return out;
}

std::vector<int> lasso_select(const Positions& screen, const std::vector<Vec2>& lasso, const DepthImage& depth) {
  std::vector<int> out;
  if (lasso.size() < 3) return out;
  for (Eigen::Index v = 0; v < screen.rows(); ++v) {
    const double x = screen(v, 0), y = screen(v, 1);
    bool inside = false;
    for (size_t i = 0, j = lasso.size() - 1; i < lasso.size(); j = i++) {
      const Vec2 &a = lasso[i], &b = lasso[j];
      if ((a.y() > y) != (b.y() > y) && x < (b.x() - a.x()) * (y - a.y()) / (b.y() - a.y()) + a.x()) inside = !inside;
    }
    if (inside && depth.visible(x, y, screen(v, 2), kDepthTolerance)) out.push_back(static_cast<int>(v));
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------
// Scripts

double script_number(const ScriptCommand& command, size_t i, const std::string& path) {
  const std::string& text = command.args.at(i);
  std::istringstream in(text);
  double x = 0;
  std::string rest;
  if (!(in >> x) || (in >> rest) || !std::isfinite(x))
    throw InvalidInput(path + ":" + std::to_string(command.line) + ": '" + command.verb + "' expects a number, found '" +
                       text + "'");
  return x;
}

std::vector<ScriptCommand> read_script(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InvalidInput(path + ": cannot open the script (not a file)");
  if (std::filesystem::file_size(path, ec) > (1u << 20))
    throw InvalidInput(path + ": a script of more than 1 MB is not a list of commands");
  std::ifstream in(path);
  if (!in) throw InvalidInput(path + ": cannot open the script");
  // verb -> (fewest, most) arguments, and which must be numbers (from the first numeric one on)
  struct Rule {
    size_t fewest, most;
    size_t first_number;  // arguments from this index on are numbers
  };
  constexpr size_t kAny = static_cast<size_t>(-1);
  const std::map<std::string, Rule> rules = {
      {"method", {1, 1, 1}},      {"handle", {1, 1, 0}},     {"translate", {3, 4, 0}},  {"rotate", {4, 5, 0}},
      {"gizmo", {4, 5, 2}},       {"orbit", {2, 2, 0}},      {"zoom", {1, 1, 0}},       {"paint", {4, 5, 1}},
      {"lasso", {1, kAny, 1}},    {"color", {1, 1, 1}},      {"shading", {1, 1, 1}},    {"converge", {0, 0, 0}},
      {"screenshot", {1, 2, 2}},  {"save-mesh", {1, 1, 1}},  {"save-sel", {1, 1, 1}},   {"save-def", {1, 1, 1}},
      {"reset", {0, 0, 0}}};
  std::vector<ScriptCommand> commands;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (line == 1 && text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);  // a UTF-8 byte-order mark
    text = text.substr(0, text.find('#'));
    for (const char ch : text)
      if (static_cast<unsigned char>(ch) < 32 && ch != '\t' && ch != '\r')
        throw InvalidInput(path + ":" + std::to_string(line) + ": not text (a control character)");
    std::istringstream words(text);
    ScriptCommand c;
    c.line = line;
    if (!(words >> c.verb)) continue;
    for (std::string w; words >> w;) c.args.push_back(w);
    const std::string where = path + ":" + std::to_string(line) + ": ";
    const auto rule = rules.find(c.verb);
    if (rule == rules.end()) {
      std::string known;
      for (const auto& [verb, r] : rules) known += (known.empty() ? "" : ", ") + verb;
      throw InvalidInput(where + "unknown command '" + c.verb + "' (known: " + known + ")");
    }
    if (c.args.size() < rule->second.fewest || c.args.size() > rule->second.most)
      throw InvalidInput(where + "'" + c.verb + "' takes " + std::to_string(rule->second.fewest) +
                         (rule->second.most != rule->second.fewest
                              ? " to " + (rule->second.most == kAny ? std::string("any number of")
                                                                    : std::to_string(rule->second.most))
                              : std::string()) +
                         " arguments, found " + std::to_string(c.args.size()));
    size_t first_number = rule->second.first_number;
    if ((c.verb == "paint" || c.verb == "lasso") && !c.args.empty()) {
      if (c.args[0] == "handle") {
        first_number = 1;  // the handle index is a number too
      } else if (c.args[0] != "fixed" && c.args[0] != "free") {
        throw InvalidInput(where + "'" + c.verb + "' paints fixed, free or handle K, not '" + c.args[0] + "'");
      }
      const size_t coordinates = c.args.size() - (c.args[0] == "handle" ? 2 : 1);
      if (c.verb == "paint" && coordinates != 3)
        throw InvalidInput(where + "'paint' takes X Y RADIUS after the role");
      if (c.verb == "lasso" && (coordinates < 6 || coordinates % 2 != 0))
        throw InvalidInput(where + "'lasso' takes three or more X Y corners after the role");
    }
    if (c.verb == "gizmo") {
      if (c.args[0] != "translate" && c.args[0] != "rotate")
        throw InvalidInput(where + "'gizmo' is translate or rotate, not '" + c.args[0] + "'");
      if (c.args[1] != "x" && c.args[1] != "y" && c.args[1] != "z" && c.args[1] != "center")
        throw InvalidInput(where + "the gizmo part is x, y, z or center, not '" + c.args[1] + "'");
    }
    if (c.verb == "color" && c.args[0] != "region" && c.args[0] != "rigidity" && c.args[0] != "detail" &&
        c.args[0] != "none")
      throw InvalidInput(where + "'color' is region, rigidity, detail or none, not '" + c.args[0] + "'");
    if (c.verb == "screenshot" && c.args.size() == 2 && c.args[1] != "window")
      throw InvalidInput(where + "'screenshot PATH window' takes the whole window; found '" + c.args[1] + "'");
    if (c.verb == "shading" && c.args[0] != "flat" && c.args[0] != "smooth")
      throw InvalidInput(where + "'shading' is flat or smooth, not '" + c.args[0] + "'");
    for (size_t i = first_number; i < c.args.size(); ++i) script_number(c, i, path);
    for (const char* counted : {"handle", "zoom"})
      if (c.verb == counted && script_number(c, 0, path) != std::floor(script_number(c, 0, path)))
        throw InvalidInput(where + "'" + c.verb + "' takes a whole number");
    const bool handle_role = (c.verb == "paint" || c.verb == "lasso") && c.args[0] == "handle";
    if (c.verb == "handle" || handle_role) {
      const double k = script_number(c, handle_role ? 1 : 0, path);
      if (k != std::floor(k) || k < 0 || k > 1e6)
        throw InvalidInput(where + "a handle is a whole number from 0, not " + c.args[handle_role ? 1 : 0]);
    }
    // STEPS: the optional last argument of translate (4th), rotate (5th) and gizmo (5th).
    const size_t steps_at = c.verb == "translate" ? 3 : (c.verb == "rotate" || c.verb == "gizmo") ? 4 : 0;
    if (steps_at && c.args.size() > steps_at) {
      const double steps = script_number(c, steps_at, path);
      if (steps != std::floor(steps) || steps < 1 || steps > 10000)
        throw InvalidInput(where + "STEPS is a whole number from 1 to 10000, not " + c.args[steps_at]);
    }
    if (c.verb == "rotate" &&
        !(Vec3(script_number(c, 0, path), script_number(c, 1, path), script_number(c, 2, path)).norm() > 1e-12))
      throw InvalidInput(where + "the rotation axis is zero (or too short to have a direction)");
    if (c.verb == "paint" && !(script_number(c, c.args.size() - 1, path) > 0))
      throw InvalidInput(where + "the brush radius is a positive number of pixels");
    if (c.verb == "zoom" && std::abs(script_number(c, 0, path)) > 100)
      throw InvalidInput(where + "zoom takes -100 to 100 steps");
    commands.push_back(std::move(c));
  }
  return commands;
}

}  // namespace msd::view
