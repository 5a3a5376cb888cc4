#include "msdeform/core/scenes.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>

#include <Eigen/Geometry>

#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"

namespace msd {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kBumpSpacing = 0.1;

// Smooth compactly supported bump: C² where it meets the flat part.
double bump(double r, double radius) {
  if (r >= radius) return 0;
  const double t = 1 - (r / radius) * (r / radius);
  return t * t * t;
}

// Height of the bump lattice at surface coordinates (u, v), bumps centred at (k + 1/2) * spacing.
double lattice_height(double u, double v, double spacing_u, double spacing_v, const SceneOptions& o) {
  const double cu = (std::floor(u / spacing_u) + 0.5) * spacing_u;
  const double cv = (std::floor(v / spacing_v) + 0.5) * spacing_v;
  return o.bump_height * bump(std::hypot(u - cu, v - cv), o.bump_radius);
}

// The refinement level whose vertex count (count(level)) is closest to target in ratio.
template <class Count>
int closest_level(double target, Count count) {
  int best = 0;
  for (int l = 1; l <= 10; ++l)
    if (std::abs(std::log(count(l) / target)) < std::abs(std::log(count(best) / target))) best = l;
  return best;
}

// Renumbers the fine vertices row by row of their surface coordinates (v, then u, in [0, 1]²), and sorts the
// faces by their first vertex, so that mesh neighbours are near each other in memory. OpenSubdiv numbers a
// level's vertices by their parent entity (all vertex children, then all edge children), which scatters
// every one-ring over the whole array: per-vertex kernels then run several times slower at 1M vertices.
// Rows rather than a Z-order curve: a frame pass then reads three rows at a time, which the prefetchers
// stream (at 1M vertices the normals took 3.5 instead of 5.5 ms, the fold count 3.4 instead of 5.2 ms).
void renumber_for_locality(Scene& s, const Eigen::MatrixX2d& uv) {
  const Eigen::Index nv = s.smooth.rows();
  std::vector<std::pair<std::uint64_t, int>> keys(nv);
  const double scale = double((1u << 21) - 1);
  for (Eigen::Index i = 0; i < nv; ++i) {
    const auto q = [&](double t) { return static_cast<std::uint32_t>(std::clamp(t, 0.0, 1.0) * scale); };
    keys[i] = {std::uint64_t(q(uv(i, 1))) << 32 | q(uv(i, 0)), static_cast<int>(i)};
  }
  std::sort(keys.begin(), keys.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm(nv);  // old index → new index
  for (Eigen::Index k = 0; k < nv; ++k) perm.indices()[keys[k].second] = static_cast<int>(k);
  s.smooth = perm * s.smooth;
  s.smooth_normals = perm * s.smooth_normals;
  s.heights = perm * s.heights;
  s.refinement.loop = perm * s.refinement.loop;
  s.refinement.linear = perm * s.refinement.linear;
  Faces& F = s.refinement.faces;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) F(f, k) = perm.indices()[F(f, k)];
  std::vector<int> order(F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f) order[f] = static_cast<int>(f);
  // Stable: faces that share their first vertex keep OpenSubdiv's order, the same with any standard library
  // (the local frames' tangents follow the face order).
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return F.row(a).minCoeff() < F.row(b).minCoeff(); });
  Faces sorted(F.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) sorted.row(f) = F.row(order[f]);
  F = sorted;
  s.F = F;
}

Scene plane(const SceneOptions& o) {
  Scene s;
  const double side = std::sqrt(std::max(o.resolution, 16));
  int levels = 0;
  while (levels < 10 && (side - 1) / std::pow(2.0, levels + 1) >= 4) ++levels;
  const int n = std::max(1, static_cast<int>(std::lround((side - 1) / std::pow(2.0, levels))));
  // Coarse n x n grid of squares, each split along the same diagonal (regular valence 6 inside).
  s.coarse_P.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) s.coarse_P.row(j * (n + 1) + i) << double(i) / n, double(j) / n, 0.0;
  s.coarse_F.resize(2 * n * n, 3);
  for (int j = 0, f = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      s.coarse_F.row(f++) << a, b, d;
      s.coarse_F.row(f++) << a, d, c;
    }
  s.refinement = loop_refine(s.coarse_F, static_cast<int>(s.coarse_P.rows()), levels);
  s.F = s.refinement.faces;
  s.smooth = s.refinement.linear * s.coarse_P;  // exactly the regular fine grid
  const Eigen::Index nv = s.smooth.rows();
  s.smooth_normals = Positions::Zero(nv, 3);
  s.smooth_normals.col(2).setOnes();
  s.heights.resize(nv);
  for (Eigen::Index i = 0; i < nv; ++i)
    s.heights[i] = lattice_height(s.smooth(i, 0), s.smooth(i, 1), kBumpSpacing, kBumpSpacing, o);
  renumber_for_locality(s, s.smooth.leftCols<2>());
  return s;
}

Scene bar(const SceneOptions& o) {
  Scene s;
  const double r = o.bar_radius;
  const int nu = 8, nv_around = 8;  // coarse cells along x and around
  const int levels = closest_level(o.resolution, [&](int l) {
    const double k = std::pow(2.0, l);
    return (nu * k + 1) * (nv_around * k);
  });
  s.coarse_P.resize((nu + 1) * nv_around, 3);
  for (int j = 0; j < nv_around; ++j)
    for (int i = 0; i <= nu; ++i) {
      const double phi = 2 * kPi * j / nv_around;
      s.coarse_P.row(j * (nu + 1) + i) << double(i) / nu, r * std::cos(phi), r * std::sin(phi);
    }
  s.coarse_F.resize(2 * nu * nv_around, 3);
  for (int j = 0, f = 0; j < nv_around; ++j)
    for (int i = 0; i < nu; ++i) {
      // a → b runs along +x and a → c around the axis (+φ): (a, d, b) and (a, c, d) face away from the axis.
      const int a = j * (nu + 1) + i, b = a + 1, c = ((j + 1) % nv_around) * (nu + 1) + i, d = c + 1;
      s.coarse_F.row(f++) << a, d, b;
      s.coarse_F.row(f++) << a, c, d;
    }
  s.refinement = loop_refine(s.coarse_F, static_cast<int>(s.coarse_P.rows()), levels);
  s.F = s.refinement.faces;
  s.smooth = s.refinement.linear * s.coarse_P;
  const Eigen::Index nv = s.smooth.rows();
  s.smooth_normals.resize(nv, 3);
  s.heights.resize(nv);
  Eigen::MatrixX2d uv(nv, 2);
  const double circumference = 2 * kPi * r;
  const int bumps_around = static_cast<int>(std::floor(circumference / kBumpSpacing));
  for (Eigen::Index i = 0; i < nv; ++i) {
    // Project the chord midpoints onto the cylinder, then bump radially.
    double phi = std::atan2(s.smooth(i, 2), s.smooth(i, 1));
    if (phi < 0) phi += 2 * kPi;
    s.smooth.row(i) << s.smooth(i, 0), r * std::cos(phi), r * std::sin(phi);
    s.smooth_normals.row(i) << 0.0, std::cos(phi), std::sin(phi);
    s.heights[i] = lattice_height(s.smooth(i, 0), phi * r, kBumpSpacing, circumference / bumps_around, o);
    uv.row(i) << s.smooth(i, 0), phi / (2 * kPi);
  }
  renumber_for_locality(s, uv);
  return s;
}

Mat4 translation(const Vec3& t) {
  Mat4 T = Mat4::Identity();
  T.topRightCorner<3, 1>() = t;
  return T;
}

Mat4 rotation_about(const Vec3& axis, double radians, const Vec3& center) {
  Mat4 R = Mat4::Identity();
  R.topLeftCorner<3, 3>() = Eigen::AngleAxisd(radians, axis.normalized()).toRotationMatrix();
  return translation(center) * R * translation(-center);
}

}  // namespace

Scene make_surface(SceneShape shape, const SceneOptions& options) {
  if (options.resolution < 16 || options.resolution > 20000000)
    throw InvalidInput("make_surface: resolution " + std::to_string(options.resolution) + " out of range [16, 2e7]");
  if (!(0 < options.fixed_end && options.fixed_end < options.handle_start && options.handle_start < 1))
    throw InvalidInput("make_surface: need 0 < fixed_end < handle_start < 1 (got " + std::to_string(options.fixed_end) +
                       ", " + std::to_string(options.handle_start) + ")");
  Scene s = shape == SceneShape::Plane ? plane(options) : bar(options);
  s.name = shape == SceneShape::Plane ? "plane" : "bar";
  s.P = s.smooth + s.smooth_normals.cwiseProduct(s.heights.replicate(1, 3));
  s.bump_height = options.bump_height;
  s.region = Region(static_cast<int>(s.P.rows()), Region::kFree);
  std::vector<int> fixed, handle;
  for (int i = 0; i < s.P.rows(); ++i) {
    if (s.smooth(i, 0) < options.fixed_end) fixed.push_back(i);
    if (s.smooth(i, 0) > options.handle_start) handle.push_back(i);
  }
  s.region.set_fixed(fixed);
  s.region.set_handle(handle, 0);
  return s;
}

Scene make_scene(SceneShape shape, SceneEdit edit, double amount, const SceneOptions& options) {
  if (!std::isfinite(amount)) throw InvalidInput("make_scene: non-finite edit amount");
  Scene s = make_surface(shape, options);
  // The long axis of both surfaces: along x through (y, z) = (0.5, 0) for the plane, (0, 0) for the bar.
  const Vec3 axis_point = shape == SceneShape::Plane ? Vec3(0, 0.5, 0) : Vec3(0, 0, 0);
  Mat4 T = Mat4::Identity();
  const char* kind = "";
  switch (edit) {
    case SceneEdit::Lift:
      T = translation(Vec3(0, 0, amount));
      kind = "lift";
      break;
    case SceneEdit::Twist:
      T = rotation_about(Vec3::UnitX(), amount * kPi / 180, axis_point);
      kind = "twist";
      break;
    case SceneEdit::Bend: {
      kind = "bend";
      const double theta = amount * kPi / 180;
      const double free_length = options.handle_start - options.fixed_end;
      if (std::abs(theta) < 1e-12) break;
      // The free region rolls onto an arc of radius R around (fixed_end, *, R): slide the handle back
      // to the fixed end, then rotate it about the arc's centre by theta.
      const double R = free_length / theta;
      T = rotation_about(-Vec3::UnitY(), theta, Vec3(options.fixed_end, 0, R + axis_point.z())) *
          translation(Vec3(-free_length, 0, 0));
      break;
    }
  }
  s.transforms = {T};
  std::string amount_text = std::to_string(amount);
  amount_text.erase(amount_text.find_last_not_of('0') + 1);
  if (!amount_text.empty() && amount_text.back() == '.') amount_text.pop_back();
  s.name = std::string(shape == SceneShape::Bar ? "bar-" : "") + kind + (edit == SceneEdit::Lift ? "" : amount_text);
  return s;
}

std::vector<std::string> scene_names() {
  return {"lift", "bend120", "twist135", "bar-lift", "bar-bend120", "bar-twist135", "crease120"};
}

Scene make_scene(const std::string& name, const SceneOptions& options) {
  const bool is_bar = name.rfind("bar-", 0) == 0;
  const std::string edit = is_bar ? name.substr(4) : name;
  const SceneShape shape = is_bar ? SceneShape::Bar : SceneShape::Plane;
  Scene s;
  if (edit == "lift")
    s = make_scene(shape, SceneEdit::Lift, 0.3, options);
  else if (edit == "bend120")
    s = make_scene(shape, SceneEdit::Bend, 120, options);
  else if (edit == "twist135")
    s = make_scene(shape, SceneEdit::Twist, 135, options);
  else if (name == "crease120") {
    // Fig. 9.10: the plane bent by 120° within a free strip 0.1 wide, so the base curves with a radius
    // (about 0.05) near the bumps' height and displacements along its normals cross.
    SceneOptions crease = options;
    crease.fixed_end = 0.45;
    crease.handle_start = 0.55;
    s = make_scene(SceneShape::Plane, SceneEdit::Bend, 120, crease);
  } else {
    std::string known;
    for (const auto& n : scene_names()) known += (known.empty() ? "" : ", ") + n;
    throw InvalidInput("unknown scene '" + name + "' (known: " + known + ")");
  }
  s.name = name;
  return s;
}

void write_scene(const Scene& scene, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InvalidInput("write_scene: cannot create folder " + dir + ": " + ec.message());
  const std::string base = (std::filesystem::path(dir) / scene.name).string();
  save_mesh(scene.P, scene.F, base + ".off");
  write_sel(scene.region, base + ".sel");
  write_def(scene.transforms, base + ".def");
}

int parse_resolution(const std::string& text) {
  // Decimal digits (std::from_chars: no hex, no leading space or sign), then an optional k or M.
  double value = -1;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  const std::string suffix = ec == std::errc() ? text.substr(end - text.data()) : "";
  if (ec != std::errc() || !std::isfinite(value)) value = -1;
  else if (suffix == "k" || suffix == "K") value *= 1e3;
  else if (suffix == "m" || suffix == "M") value *= 1e6;
  else if (!suffix.empty()) value = -1;
  if (!(value >= 16 && value <= 2e7))
    throw InvalidInput("resolution '" + text + "': expected a vertex count from 16 to 20M, like 10000, 100k or 1M");
  return static_cast<int>(std::lround(value));
}

}  // namespace msd
