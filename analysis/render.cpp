#include "msdeform/analysis/render.h"

#include <Eigen/Eigenvalues>
#include <embree3/rtcore.h>
#include <stb/stb_image_write.h>  // declarations only: libstb holds the implementation

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <tuple>

#include "msdeform/core/atomic_file.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/surface_check.h"
#include "msdeform/detail/embree_error.h"

namespace msd {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kGamma = 2.2;
// Point radius per median nearest-neighbour distance (default_point_radius): measured on CGAL's b9 scan,
// where half the spacing left the gaps between scan lines showing and 0.85 closes them (a square grid is
// covered from 0.71 on) while every point still shows as a bead.
constexpr double kPointRadiusPerSpacing = 0.85;
const Vec3 kTextColour(0.12, 0.13, 0.16);

std::uint8_t to_byte(double c) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(c, 0.0, 1.0) * 255.0));
}

// Lighting is computed on linear intensities and encoded back with a plain 2.2 gamma, so shading falls
// off as on a screen-referred photograph and supersampled edges average correctly.
Vec3 to_linear(const Vec3& c) {
  return Vec3(std::pow(std::clamp(c.x(), 0.0, 1.0), kGamma), std::pow(std::clamp(c.y(), 0.0, 1.0), kGamma),
              std::pow(std::clamp(c.z(), 0.0, 1.0), kGamma));
}
Vec3 to_display(const Vec3& c) {
  return Vec3(std::pow(std::clamp(c.x(), 0.0, 1.0), 1 / kGamma),
              std::pow(std::clamp(c.y(), 0.0, 1.0), 1 / kGamma),
              std::pow(std::clamp(c.z(), 0.0, 1.0), 1 / kGamma));
}

Vec3 background(const RenderOptions& o, int row, int height) {
  const double t = height > 1 ? static_cast<double>(row) / (height - 1) : 0.0;
  return (1 - t) * o.background_top + t * o.background_bottom;
}

// The closest hit of a ray: the primitive (a face, or a point of a cloud), the barycentrics of corners 1
// and 2 of a face, and Embree's geometric normal (unnormalised; outwards for a sphere).
struct Hit {
  int primitive = -1;
  float u = 0, v = 0;
  Vec3 normal = Vec3::Zero();
};

// Owns an Embree device and a committed scene of one geometry: the triangles F, or, for an empty F, one
// sphere of point_radius per row of P.
class EmbreeScene {
 public:
  // P: #V by 3 in the render frame (already centred), F: #F by 3 with valid indices.
  EmbreeScene(const Positions& P, const Faces& F, double point_radius) {
    device_ = rtcNewDevice(nullptr);
    if (!device_)
      throw Error("render: Embree could not create a device (" +
                  embree_error_text(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
    scene_ = rtcNewScene(device_);
    const bool points = F.rows() == 0;
    RTCGeometry geometry =
        rtcNewGeometry(device_, points ? RTC_GEOMETRY_TYPE_SPHERE_POINT : RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!geometry)
      fail(points ? "could not create the point geometry" : "could not create the triangle geometry");
    // Spheres take (x, y, z, radius) per point; triangles a vertex buffer and an index buffer.
    const int stride = points ? 4 : 3;
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, points ? RTC_FORMAT_FLOAT4 : RTC_FORMAT_FLOAT3,
        stride * sizeof(float), P.rows()));
    unsigned* indices = nullptr;
    if (!points)
      indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
          geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), F.rows()));
    if (!vertices || (!points && !indices)) {
      rtcReleaseGeometry(geometry);
      fail("could not allocate buffers");
    }
    for (Eigen::Index v = 0; v < P.rows(); ++v) {
      for (int k = 0; k < 3; ++k) vertices[stride * v + k] = static_cast<float>(P(v, k));
      if (points) vertices[stride * v + 3] = static_cast<float>(point_radius);
    }
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int k = 0; k < 3; ++k) indices[3 * f + k] = static_cast<unsigned>(F(f, k));
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene_, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) fail("could not build the scene");
  }
  ~EmbreeScene() {
    if (scene_) rtcReleaseScene(scene_);
    if (device_) rtcReleaseDevice(device_);
  }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  // Closest hit along org + t dir, t > 0 (primitive -1 for none).
  Hit intersect(const Vec3& org, const Vec3& dir) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    set_ray(rh.ray, org, dir);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &context, &rh);
    Hit hit;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
    hit.primitive = static_cast<int>(rh.hit.primID);
    hit.u = rh.hit.u;
    hit.v = rh.hit.v;
    hit.normal = Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    return hit;
  }

  bool occluded(const Vec3& org, const Vec3& dir) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray;
    set_ray(ray, org, dir);
    rtcOccluded1(scene_, &context, &ray);
    return ray.tfar < 0;  // Embree sets tfar to -inf on a hit
  }

 private:
  static void set_ray(RTCRay& ray, const Vec3& org, const Vec3& dir) {
    ray.org_x = static_cast<float>(org.x());
    ray.org_y = static_cast<float>(org.y());
    ray.org_z = static_cast<float>(org.z());
    ray.dir_x = static_cast<float>(dir.x());
    ray.dir_y = static_cast<float>(dir.y());
    ray.dir_z = static_cast<float>(dir.z());
    ray.tnear = 0.0f;
    ray.tfar = std::numeric_limits<float>::infinity();
    ray.time = 0.0f;
    ray.mask = ~0u;
    ray.id = 0;
    ray.flags = 0;
  }
  [[noreturn]] void fail(const char* what) const {
    throw Error(std::string("render: Embree ") + what + " (" +
                embree_error_text(static_cast<int>(rtcGetDeviceError(device_))) + ")");
  }
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

// A pinhole camera in the centred frame of the mesh.
struct Camera {
  Vec3 eye, forward, right, up;
  double tan_h = 0, tan_v = 0;  // half-extents of the image plane at unit distance

  Vec3 ray(double ndc_x, double ndc_y) const {
    return (forward + ndc_x * tan_h * right + ndc_y * tan_v * up).normalized();
  }
};

// Camera for the traced positions Pc (P − centre in units of `unit`, everything drawn within radius), each
// drawn as a sphere of radius pad (0 for the vertices of faces).
Camera frame_camera(const Positions& Pc, double radius, double pad, const Vec3& centre, double unit,
                    const RenderOptions& o, int view_width) {
  Camera cam;
  const Vec3 to_eye = o.view_direction.normalized();
  Vec3 up = o.up.norm() > 0 ? o.up.normalized() : Vec3(0, 0, 1);
  if (up.cross(to_eye).norm() < 1e-6) {
    Eigen::Index axis;
    to_eye.cwiseAbs().minCoeff(&axis);
    up = Vec3::Unit(axis);
  }
  cam.forward = -to_eye;
  cam.right = cam.forward.cross(up).normalized();
  cam.up = cam.right.cross(cam.forward);
  cam.tan_v = std::tan(0.5 * o.fov_degrees * kPi / 180.0);
  cam.tan_h = cam.tan_v * view_width / o.height;

  if (o.framing == Framing::BoundingSphere) {
    // A sphere at distance d subtends a half-angle asin(r / d): fit it to the narrower field.
    const bool given = o.sphere_radius > 0;
    const Vec3 target = given ? Vec3((o.sphere_center - centre) / unit) : Vec3::Zero();
    const double r = given ? o.sphere_radius / unit : radius;
    const double half_angle = std::atan(std::min(cam.tan_v, cam.tan_h));
    cam.eye = target + to_eye * (1.04 * r / std::sin(half_angle));
    return cam;
  }

  // Tight: with the eye at s_x right + s_y up − D forward, vertex (x, y, z) in camera axes lies inside
  // the frame iff |x − s_x| ≤ fit tan_h (D + z) and |y − s_y| ≤ fit tan_v (D + z). For a given aim the
  // smallest such D is explicit; the aim is refined a few times to centre the extreme vertices.
  constexpr double fit = 0.95;
  const Eigen::VectorXd x = Pc * cam.right, y = Pc * cam.up, z = Pc * cam.forward;
  const double near = -z.minCoeff() + pad + 1e-3 * radius;  // every vertex (and sphere) in front of the eye
  double sx = 0, sy = 0, D = 0;
  // A sphere's outline is taken as its centre's offset plus pad at the depth of its nearest point, a
  // little generous for spheres off the axis, which the 5% margin absorbs.
  auto distance = [&] {
    double d = near;
    for (Eigen::Index i = 0; i < x.size(); ++i)
      d = std::max(d, std::max((std::abs(x[i] - sx) + pad) / (fit * cam.tan_h),
                               (std::abs(y[i] - sy) + pad) / (fit * cam.tan_v)) -
                          (z[i] - pad));
    return d;
  };
  // Shift s that balances the extreme projections: (a − s)/da + (b − s)/db = 0 for the vertices with the
  // largest and smallest projected coordinate (offsets a, b from the current aim, depths da, db).
  auto centring_shift = [&](const Eigen::VectorXd& c, double aim) {
    Eigen::Index lo = 0, hi = 0;
    double plo = 1e300, phi = -1e300;
    for (Eigen::Index i = 0; i < c.size(); ++i) {
      const double p = (c[i] - aim) / (D + z[i]);
      if (p < plo) {
        plo = p;
        lo = i;
      }
      if (p > phi) {
        phi = p;
        hi = i;
      }
    }
    const double da = D + z[hi], db = D + z[lo];
    return ((c[hi] - aim) / da + (c[lo] - aim) / db) / (1 / da + 1 / db);
  };
  for (int iteration = 0; iteration < 4; ++iteration) {
    D = distance();
    const double dx = centring_shift(x, sx), dy = centring_shift(y, sy);
    sx += dx;
    sy += dy;
  }
  D = distance();
  cam.eye = sx * cam.right + sy * cam.up - D * cam.forward;
  return cam;
}

void check_options(const RenderOptions& o, const Positions& P, const Faces& F) {
  auto fail = [](const std::string& what) { throw InvalidInput("render: " + what); };
  if (o.width < 1 || o.width > 16384 || o.height < 1 || o.height > 16384)
    fail("image size " + std::to_string(o.width) + "x" + std::to_string(o.height) + " is outside 1..16384");
  if (o.samples_per_axis < 1 || o.samples_per_axis > 16)
    fail("samples_per_axis = " + std::to_string(o.samples_per_axis) + " is outside 1..16");
  if (!(o.fov_degrees > 0 && o.fov_degrees < 170))
    fail("fov_degrees = " + std::to_string(o.fov_degrees) + " is outside (0, 170)");
  if (!o.view_direction.allFinite() || !(o.view_direction.norm() > 0))
    fail("view_direction must be finite and non-zero");
  if (!o.up.allFinite()) fail("up must be finite");
  if (!o.sphere_center.allFinite() || !std::isfinite(o.sphere_radius) || o.sphere_radius < 0)
    fail("sphere_center must be finite and sphere_radius finite and non-negative");
  if (!std::isfinite(o.point_radius) || o.point_radius < 0)
    fail("point_radius = " + format_number(o.point_radius) +
         " must be finite and non-negative (0: automatic)");
  if (o.highlighted_faces)
    for (int f : *o.highlighted_faces)
      if (f < 0 || f >= F.rows())
        fail("highlighted face " + std::to_string(f) + " is not a row of F (" + std::to_string(F.rows()) + " faces)");
  if (o.vertex_colors) {
    const Positions& c = *o.vertex_colors;
    if (c.rows() != P.rows())
      fail("vertex_colors has " + std::to_string(c.rows()) + " rows for " + std::to_string(P.rows()) + " vertices");
    if (!c.allFinite()) fail("vertex_colors is not finite");
  }
  if (o.vertex_scalar) {
    const Eigen::VectorXd& s = *o.vertex_scalar;
    if (s.size() != P.rows())
      fail("vertex_scalar has " + std::to_string(s.size()) + " values for " + std::to_string(P.rows()) +
           " vertices");
    for (Eigen::Index i = 0; i < s.size(); ++i)
      if (!std::isfinite(s[i])) fail("vertex_scalar is not finite at vertex " + std::to_string(i));
    if (!std::isfinite(o.scalar_min) || !std::isfinite(o.scalar_max))
      fail("scalar_min / scalar_max must be finite");
  }
}

// Colour bar at the right of the image: sized from its texts, drawn after tracing.
struct Legend {
  bool shown = false;
  int scale = 1, panel_width = 0;
  double lo = 0, hi = 1;
  bool below = false, above = false;  // values beyond lo or hi exist (drawn in the end colours)
  std::string label;

  int margin() const { return 8 * scale; }
  int bar_width() const { return 9 * scale; }
  // The value at t of the bar; an end beyond which values were clipped reads "<lo" or ">hi".
  std::string number(double t) const {
    const std::string n = format_number(lo + t * (hi - lo));
    return t == 0 && below ? "<" + n : t == 1 && above ? ">" + n : n;
  }

  void layout(const RenderOptions& o) {
    scale = o.height >= 400 ? 2 : 1;
    int numbers = 0;
    for (double t : {0.0, 0.5, 1.0}) numbers = std::max(numbers, text_width(number(t), scale));
    panel_width = margin() + bar_width() + 5 * scale + numbers + margin();
    panel_width = std::max(panel_width, text_width(label, scale) + 2 * margin());
    panel_width = std::min(panel_width, o.width / 3);
  }

  void draw(Image& image) const {
    const int x0 = image.width - panel_width + margin();
    const int bar_height = image.height * 3 / 5;
    const int top = (image.height - bar_height) / 2 + text_height(scale);
    const int text_gap = 5 * scale;
    // Title above the bar, right-aligned so a long label grows into the picture rather than off the edge.
    const int label_x = std::min(x0, image.width - margin() - text_width(label, scale));
    draw_text(image, label_x, top - 3 * text_height(scale), label, kTextColour, scale);
    for (int y = 0; y < bar_height; ++y) {
      const Vec3 c = viridis(1.0 - static_cast<double>(y) / std::max(bar_height - 1, 1));
      for (int x = 0; x < bar_width(); ++x) image.set(x0 + x, top + y, c);
    }
    for (int x = -1; x <= bar_width(); ++x) {
      image.set(x0 + x, top - 1, kTextColour);
      image.set(x0 + x, top + bar_height, kTextColour);
    }
    for (int y = -1; y <= bar_height; ++y) {
      image.set(x0 - 1, top + y, kTextColour);
      image.set(x0 + bar_width(), top + y, kTextColour);
    }
    // Numbers beside the bar at its ends and middle; no tick marks, which would read as minus signs.
    for (double t : {0.0, 0.5, 1.0}) {
      const int y = top + static_cast<int>(std::lround((1.0 - t) * (bar_height - 1)));
      draw_text(image, x0 + bar_width() + text_gap, y - text_height(scale) / 2, number(t), kTextColour,
                scale);
    }
  }
};

double percentile(std::vector<double>& sorted, double q) {
  const size_t rank = static_cast<size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::clamp<size_t>(rank, 1, sorted.size()) - 1];
}

}  // namespace

Image::Image(int w, int h, const Vec3& fill) : width(w), height(h), rgb(3 * static_cast<size_t>(w) * h) {
  const std::uint8_t c[3] = {to_byte(fill.x()), to_byte(fill.y()), to_byte(fill.z())};
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = c[i % 3];
}

void Image::set(int x, int y, const Vec3& colour) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  std::uint8_t* p = pixel(x, y);
  p[0] = to_byte(colour.x());
  p[1] = to_byte(colour.y());
  p[2] = to_byte(colour.z());
}

Vec3 viridis(double t) {
  // matplotlib's viridis sampled at t = 0, 1/8, ..., 1.
  static const double samples[9][3] = {
      {0.267004, 0.004874, 0.329415}, {0.282623, 0.140926, 0.457517}, {0.229739, 0.322361, 0.545706},
      {0.172719, 0.448791, 0.557885}, {0.127568, 0.566949, 0.550556}, {0.134692, 0.658636, 0.517649},
      {0.266941, 0.748751, 0.440573}, {0.477504, 0.821444, 0.318195}, {0.993248, 0.906157, 0.143936}};
  if (!(t > 0)) t = 0;  // also maps NaN to the low end
  t = std::min(t, 1.0) * 8.0;
  const int k = std::min(static_cast<int>(t), 7);
  const double f = t - k;
  Vec3 c;
  for (int i = 0; i < 3; ++i) c[i] = (1 - f) * samples[k][i] + f * samples[k + 1][i];
  return c;
}

Positions region_colors(const Region& region) {
  static const Vec3 palette[] = {{0.84, 0.19, 0.15}, {0.20, 0.63, 0.17}, {0.55, 0.32, 0.71},
                                 {0.95, 0.55, 0.10}, {0.10, 0.60, 0.62}, {0.85, 0.40, 0.65}};
  const Vec3 fixed(0.38, 0.47, 0.62), free = RenderOptions{}.base_color;
  Positions colors(region.num_vertices(), 3);
  for (int v = 0; v < region.num_vertices(); ++v) {
    const int k = region.handle_of(v);
    colors.row(v) = (k >= 0 ? palette[k % 6] : region.is_fixed(v) ? fixed : free).transpose();
  }
  return colors;
}

std::pair<double, double> robust_scalar_range(const Eigen::VectorXd& values) {
  if (values.size() == 0) throw InvalidInput("robust_scalar_range: no values");
  std::vector<double> v(values.data(), values.data() + values.size());
  for (size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      throw InvalidInput("robust_scalar_range: value " + std::to_string(i) + " is not finite");
  std::sort(v.begin(), v.end());
  double lo = v.front() >= 0 ? 0.0 : percentile(v, 0.01);
  double hi = percentile(v, 0.99);
  if (!(hi > lo)) hi = v.back();
  if (!(hi > lo)) hi = lo + std::max(std::abs(lo), 1.0);
  return {lo, hi};
}

Image render(const Positions& P, const Faces& F, const RenderOptions& o) {
  check_mesh_arrays(P, F, "render");
  if (P.rows() == 0) throw InvalidInput("render: nothing to draw (no vertices)");
  check_options(o, P, F);
  const bool points = F.rows() == 0;
  const double point_radius = !points ? 0.0 : o.point_radius > 0 ? o.point_radius : default_point_radius(P);

  // Everything is traced relative to the bounding-box centre, which keeps Embree's floats accurate for
  // meshes far from the origin, and in units of the largest centred coordinate: Embree's single-precision
  // products of coordinates underflowed below a size of about 1e-15 and overflowed beyond 1e19 (an empty
  // picture), and its shading was striped from 1e15.
  const Vec3 lo = P.colwise().minCoeff().transpose(), hi = P.colwise().maxCoeff().transpose();
  const Vec3 centre = 0.5 * (lo + hi);
  Positions Pc = P.rowwise() - centre.transpose();
  double unit = std::max(Pc.cwiseAbs().maxCoeff(), point_radius);
  if (!(unit > 0) || !std::isfinite(unit)) unit = 1;
  Pc /= unit;
  const double pad = point_radius / unit;  // a point's sphere, traced
  double radius = Pc.rowwise().norm().maxCoeff() + pad;
  if (!(radius > 0)) radius = 1;
  // Vertex normals of the faces wound consistently where the surface allows (check_surface turns a copy
  // over): a soup's faces may come in either winding, and a normal summed over opposite windings would
  // cancel and mottle the shading. Shading is two-sided, so which of the two windings wins is immaterial.
  Positions N;
  if (!points) {
    Faces oriented = F;
    check_surface(P, oriented);
    N = vertex_normals(Pc, oriented);
  }
  const EmbreeScene scene(Pc, F, pad);

  Legend legend;
  if (o.vertex_scalar) {
    legend.lo = o.scalar_min;
    legend.hi = o.scalar_max;
    if (legend.lo == legend.hi) std::tie(legend.lo, legend.hi) = robust_scalar_range(*o.vertex_scalar);
    if (o.vertex_scalar->size() > 0) {
      legend.below = o.vertex_scalar->minCoeff() < legend.lo;
      legend.above = o.vertex_scalar->maxCoeff() > legend.hi;
    }
    legend.shown = o.legend && o.width >= 100 && o.height >= 60;
    legend.label = o.scalar_label;
    if (legend.shown) legend.layout(o);
  }
  const int view_width = o.width - (legend.shown ? legend.panel_width : 0);

  const Camera cam = frame_camera(Pc, radius, pad, centre, unit, o, view_width);

  // Head light from the eye, key light from the upper left (in camera terms, so every view is lit alike).
  const Vec3 key = (-0.6 * cam.right + 0.7 * cam.up - 0.4 * cam.forward).normalized();
  constexpr double ambient = 0.12, head_strength = 0.42, key_strength = 0.62, specular_strength = 0.12;
  const double shadow_offset = 1e-4 * radius;
  const Vec3 base = to_linear(o.base_color);
  const Eigen::VectorXd* scalar = o.vertex_scalar;
  const Positions* colors = o.vertex_colors;
  std::vector<char> highlighted;  // per face, when some are highlighted
  if (o.highlighted_faces && !o.highlighted_faces->empty()) {
    highlighted.assign(F.rows(), 0);
    for (int f : *o.highlighted_faces) highlighted[f] = 1;
  }
  const Vec3 highlight = to_linear(o.highlight_color);
  auto albedo_of = [&](double s) { return to_linear(viridis((s - legend.lo) / (legend.hi - legend.lo))); };

  // Lambert from the head and key lights at point (shading normal n, geometric normal ng, both unit and
  // turned towards the viewer), the key light's shadow ray leaving just above the surface.
  auto light = [&](const Vec3& point, const Vec3& n, const Vec3& ng, const Vec3& view,
                   const Vec3& albedo) -> Vec3 {
    double lit = ambient + head_strength * std::abs(n.dot(view));
    const double n_dot_key = n.dot(key);
    if (n_dot_key > 0 && ng.dot(key) > 0) {
      const bool visible = !o.shadows || !scene.occluded(point + shadow_offset * ng, key);
      if (visible) {
        lit += key_strength * n_dot_key;
        const double spec = std::pow(std::max(0.0, n.dot((key + view).normalized())), 40.0);
        return lit * albedo + Vec3::Constant(specular_strength * spec);
      }
    }
    return lit * albedo;
  };

  auto shade_face = [&](const Hit& hit, const Vec3& dir) -> Vec3 {
    const int f = hit.primitive;
    const double u = hit.u, v = hit.v;
    const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
    const double w0 = 1 - u - v;
    const Vec3 pa = Pc.row(a).transpose(), pb = Pc.row(b).transpose(), pc = Pc.row(c).transpose();
    Vec3 ng = (pb - pa).cross(pc - pa);
    ng = ng.norm() > 0 ? ng.normalized() : Vec3(-dir);
    const Vec3 view = -dir;
    if (ng.dot(view) < 0) ng = -ng;  // two-sided: the face turned towards the viewer
    Vec3 n = (w0 * N.row(a) + u * N.row(b) + v * N.row(c)).transpose();
    n = n.norm() > 1e-12 ? n.normalized() : ng;
    if (n.dot(ng) < 0) n = -n;
    const Vec3 albedo = !highlighted.empty() && highlighted[f] ? highlight
                        : scalar ? albedo_of(w0 * (*scalar)[a] + u * (*scalar)[b] + v * (*scalar)[c])
                        : colors ? to_linear((w0 * colors->row(a) + u * colors->row(b) + v * colors->row(c)).transpose())
                                 : base;
    return light(w0 * pa + u * pb + v * pc, n, ng, view, albedo);
  };

  // A point's sphere: its normal is the geometric one (a sphere has no interpolated normal to smooth).
  auto shade_point = [&](const Hit& hit, const Vec3& dir) -> Vec3 {
    const int i = hit.primitive;
    const Vec3 view = -dir;
    Vec3 n = hit.normal.norm() > 0 ? hit.normal.normalized() : view;
    if (n.dot(view) < 0) n = -n;
    const Vec3 centre_i = Pc.row(i).transpose();
    const Vec3 albedo = scalar ? albedo_of((*scalar)[i]) : colors ? to_linear(colors->row(i).transpose()) : base;
    return light(centre_i + pad * n, n, n, view, albedo);
  };

  Image image(o.width, o.height);
  for (int y = 0; y < o.height; ++y) {
    const Vec3 bg = background(o, y, o.height);
    for (int x = 0; x < o.width; ++x) image.set(x, y, bg);
  }
  const int s = o.samples_per_axis;
  parallel_for_chunks(
      o.height,
      [&](long row_begin, long row_end) {
        for (long yl = row_begin; yl < row_end; ++yl) {
          const int y = static_cast<int>(yl);
          const Vec3 bg = to_linear(background(o, y, o.height));
          for (int x = 0; x < view_width; ++x) {
            Vec3 sum = Vec3::Zero();
            int hits = 0;
            for (int sy = 0; sy < s; ++sy)
              for (int sx = 0; sx < s; ++sx) {
                const double px = x + (sx + 0.5) / s, py = y + (sy + 0.5) / s;
                const double ndc_x = 2.0 * px / view_width - 1.0, ndc_y = 1.0 - 2.0 * py / o.height;
                const Vec3 dir = cam.ray(ndc_x, ndc_y);
                const Hit hit = scene.intersect(cam.eye, dir);
                if (hit.primitive < 0) {
                  sum += bg;
                } else {
                  sum += points ? shade_point(hit, dir) : shade_face(hit, dir);
                  ++hits;
                }
              }
            if (hits > 0) image.set(x, y, to_display(sum / (s * s)));
          }
        }
      },
      4);
  if (legend.shown) legend.draw(image);
  return image;
}

double default_point_radius(const Positions& P) {
  check_finite(P, "default_point_radius", "the points");
  if (P.rows() == 0) throw InvalidInput("default_point_radius: no points");
  // Nearest distinct neighbour of up to kSamples points spread evenly through the ids, each against all
  // points: O(kSamples #V), exact for small clouds, and a sample's median is all a radius needs.
  constexpr Eigen::Index kSamples = 256;
  const Eigen::Index n = P.rows(), samples = std::min(n, kSamples);
  std::vector<double> best(static_cast<size_t>(samples), std::numeric_limits<double>::infinity());
  parallel_for_chunks(
      samples,
      [&](long begin, long end) {
        for (long k = begin; k < end; ++k) {
          const Vec3 p = P.row(k * n / samples).transpose();
          double& b = best[static_cast<size_t>(k)];
          for (Eigen::Index j = 0; j < n; ++j) {
            const double d2 = (P.row(j).transpose() - p).squaredNorm();
            if (d2 > 0 && d2 < b) b = d2;  // coincident copies of a point are not its neighbours
          }
        }
      },
      16);
  std::vector<double> nearest;
  for (double d2 : best)
    if (std::isfinite(d2)) nearest.push_back(std::sqrt(d2));
  if (nearest.empty()) return 1;  // a single point, or all points coincide: no spacing to measure
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  return kPointRadiusPerSpacing * nearest[nearest.size() / 2];
}

void render_png(const Positions& P, const Faces& F, const std::string& path, const RenderOptions& options) {
  write_png(render(P, F, options), path);
}

void write_png(const Image& image, const std::string& path) {
  if (image.width < 1 || image.height < 1)
    throw InvalidInput("write_png: the image for " + path + " is empty");
  if (image.rgb.size() != 3 * static_cast<size_t>(image.width) * image.height)
    throw InvalidInput("write_png: the image for " + path + " holds " + std::to_string(image.rgb.size()) +
                       " bytes, not 3 x " + std::to_string(image.width) + " x " +
                       std::to_string(image.height));
  std::string png;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), static_cast<size_t>(size));
  };
  if (!stbi_write_png_to_func(append, &png, image.width, image.height, 3, image.rgb.data(), 3 * image.width))
    throw Error("write_png: PNG encoding failed for " + path);
  write_file_atomically(path, png);
}

Image tile_images(const std::vector<Image>& tiles, int columns, const std::vector<std::string>& labels) {
  if (tiles.empty()) throw InvalidInput("tile_images: no tiles");
  if (columns < 1)
    throw InvalidInput("tile_images: columns = " + std::to_string(columns) + " must be at least 1");
  if (!labels.empty() && labels.size() != tiles.size())
    throw InvalidInput("tile_images: " + std::to_string(labels.size()) + " labels for " +
                       std::to_string(tiles.size()) + " tiles (give one per tile or none)");
  int cell_w = 0, cell_h = 0;
  for (size_t i = 0; i < tiles.size(); ++i) {
    const Image& t = tiles[i];
    if (t.width < 1 || t.height < 1 || t.rgb.size() != 3 * static_cast<size_t>(t.width) * t.height)
      throw InvalidInput("tile_images: tile " + std::to_string(i) +
                         " is empty or has a buffer of the wrong size");
    cell_w = std::max(cell_w, t.width);
    cell_h = std::max(cell_h, t.height);
  }
  const int scale = cell_w >= 400 ? 2 : 1;
  const int gap = 4 * scale;
  const int label_h = labels.empty() ? 0 : text_height(scale) + 2 * gap;
  columns = std::min<int>(columns, static_cast<int>(tiles.size()));
  const int rows = (static_cast<int>(tiles.size()) + columns - 1) / columns;
  Image sheet(gap + columns * (cell_w + gap), gap + rows * (cell_h + label_h + gap), Vec3(1, 1, 1));
  for (size_t i = 0; i < tiles.size(); ++i) {
    const Image& t = tiles[i];
    const int col = static_cast<int>(i) % columns, row = static_cast<int>(i) / columns;
    const int cell_x = gap + col * (cell_w + gap), cell_y = gap + row * (cell_h + label_h + gap);
    const int x0 = cell_x + (cell_w - t.width) / 2, y0 = cell_y + (cell_h - t.height) / 2;
    for (int y = 0; y < t.height; ++y)
      std::copy(t.pixel(0, y), t.pixel(0, y) + 3 * t.width, sheet.pixel(x0, y0 + y));
    if (!labels.empty())
      draw_text(sheet, cell_x + (cell_w - text_width(labels[i], scale)) / 2, cell_y + cell_h + gap, labels[i],
                kTextColour, scale);
  }
  return sheet;
}

Vec3 ViewAxes::direction(double azimuth_degrees, double elevation_degrees) const {
  const double kDegree = 3.14159265358979323846 / 180;
  const double az = azimuth_degrees * kDegree, el = elevation_degrees * kDegree;
  return std::cos(el) * (-std::cos(az) * front - std::sin(az) * side) + std::sin(el) * up;
}

namespace {
// Components or extents within this fraction of each other are a tie, broken by the axes' order: the
// choice must not follow rounding (a square moved along x turned its picture by 90°).
constexpr double kTie = 1e-9;

// The index of the largest (or smallest) of v's non-negative entries; of tied ones `preferred` where it is
// one of them, else the first.
int extreme_index(const Vec3& v, bool smallest = false, int preferred = -1) {
  const auto is_extreme = [&](int k) {
    return smallest ? v[k] <= (1 + kTie) * v.minCoeff() : v[k] >= (1 - kTie) * v.maxCoeff();
  };
  if (preferred >= 0 && is_extreme(preferred)) return preferred;
  int k = 0;
  while (!is_extreme(k)) ++k;
  return k;
}

// The coordinate axis (positive) nearest to direction d; of tied ones, the first.
Vec3 nearest_axis(const Vec3& d) { return Vec3::Unit(extreme_index(d.cwiseAbs())); }
}  // namespace

ViewAxes view_axes(const Positions& P, const Vec3& up) {
  if (P.rows() == 0) throw InvalidInput("view_axes: no vertices");
  if (!P.allFinite()) throw InvalidInput("view_axes: a coordinate is not finite");
  if (!(up.squaredNorm() > 0) || !up.allFinite()) throw InvalidInput("view_axes: the up direction is zero or not finite");
  ViewAxes axes;
  axes.up = up.normalized();
  // front: the coordinate axis across up (the two least aligned with it) along which P is thinner.
  const Vec3 extent = P.colwise().maxCoeff() - P.colwise().minCoeff();
  Eigen::Index k;
  axes.up.cwiseAbs().maxCoeff(&k);
  const int a = (k + 1) % 3, b = (k + 2) % 3;
  const int thin = extent[a] < (1 - kTie) * extent[b] ? a : b;  // a tie (a square) gives b
  Vec3 front = Vec3::Unit(thin);
  front = (front - front.dot(axes.up) * axes.up).normalized();  // exactly across up when up is not an axis
  axes.front = front;
  axes.side = front.cross(axes.up);
  return axes;
}

namespace {
// The principal axis P stands along (the longest), or for a flat shape the one it is seen along (the
// thinnest: below 0.15 of the middle extent); `flat` says which.
Vec3 principal_up(const Positions& P, bool& flat) {
  const Eigen::RowVector3d mean = P.colwise().mean();
  const Eigen::MatrixX3d centred = P.rowwise() - mean;
  const Eigen::SelfAdjointEigenSolver<Mat3> pca(centred.transpose() * centred);
  const Mat3 axes = pca.eigenvectors();
  Vec3 extent;
  for (int i = 0; i < 3; ++i) {
    const Eigen::VectorXd t = centred * axes.col(i);
    extent[i] = t.maxCoeff() - t.minCoeff();
  }
  int order[3] = {0, 1, 2};  // by extent (the eigenvalues order the variances, not the extents)
  std::sort(order, order + 3, [&](int i, int j) { return extent[i] < extent[j]; });
  flat = extent[order[0]] < 0.15 * extent[order[1]];
  const int chosen = flat ? order[0] : order[2];
  // Two variances equal to rounding (a sphere, a cube, a cylinder, a regular prism) make the principal
  // directions in their plane arbitrary: the eigen-solver's pick follows the rounding, and so did the extents
  // measured along them, and the picture turned with the shape's size or place. Where the choice depends on
  // such directions (any tie for an upright shape, a tie with the chosen axis for a flat one), the bounding
  // box decides: its longest coordinate axis (flat: its thinnest), of tied ones the axis of the variance no
  // other shares (a cylinder's), else the first.
  const Vec3 variance = pca.eigenvalues();
  const double tolerance = 1e-6 * variance.cwiseAbs().maxCoeff();
  const auto tied = [&](int i, int j) { return i != j && std::abs(variance[i] - variance[j]) <= tolerance; };
  bool ambiguous = false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) ambiguous = ambiguous || (tied(i, j) && (!flat || i == chosen));
  if (!ambiguous) return axes.col(chosen);
  int distinct = -1;
  for (int i = 0; i < 3; ++i)
    if (!tied(i, 0) && !tied(i, 1) && !tied(i, 2)) distinct = extreme_index(axes.col(i).cwiseAbs());
  const Vec3 box = P.colwise().maxCoeff() - P.colwise().minCoeff();
  return Vec3::Unit(extreme_index(box, flat, distinct));
}
}  // namespace

ViewAxes view_axes(const Positions& P) { return edit_view_axes(P, {}); }

ViewAxes edit_view_axes(const Positions& P, const std::vector<int>& fixed_vertices) {
  if (P.rows() == 0) throw InvalidInput("view_axes: no vertices");
  if (!P.allFinite()) throw InvalidInput("view_axes: a coordinate is not finite");
  bool flat = false;
  const Vec3 principal = principal_up(P, flat);
  if (!flat && !fixed_vertices.empty()) {
    Vec3 fixed = Vec3::Zero(), lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (int v : fixed_vertices) {
      fixed += P.row(v).transpose();
      lo = lo.cwiseMin(P.row(v).transpose()), hi = hi.cwiseMax(P.row(v).transpose());
    }
    fixed /= static_cast<double>(fixed_vertices.size());
    const Vec3 away = Vec3(P.colwise().mean().transpose()) - fixed;
    const double diagonal = bounding_box_diagonal(P);
    // A foot or a base spans a few percent of the shape at least; a pin of a few vertices says nothing of up.
    if (away.norm() > 0.1 * diagonal && (hi - lo).norm() >= 0.05 * diagonal) return view_axes(P, nearest_axis(away));
  }
  return view_axes(P, nearest_axis(principal));
}

}  // namespace msd
