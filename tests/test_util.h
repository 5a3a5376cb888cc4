#pragma once
// Shared helpers for the tests: generated meshes, data paths and temporary folders.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>

#include <catch2/catch.hpp>

#include "msdeform/core/mesh.h"
#include "msdeform/core/region.h"
#include "msdeform/core/scenes.h"

namespace msd::test {

// The bumpy bar bent by 120° at about 2500 vertices: its fixed and handle rings span all three dimensions.
inline const Scene& bent_bar() {
  static const Scene s = [] {
    SceneOptions o;
    o.resolution = 2500;
    return make_scene("bar-bend120", o);
  }();
  return s;
}

// A general affine map: shear, anisotropic scale and a translation.
inline Mat4 general_affine() {
  Mat4 T = Mat4::Identity();
  T.topLeftCorner<3, 3>() << 1.2, 0.3, -0.1, 0.05, 0.9, 0.2, -0.15, 0.1, 1.1;
  T.topRightCorner<3, 1>() = Vec3(0.4, -0.3, 0.2);
  return T;
}

// T applied to every row of P.
inline Positions transformed(const Mat4& T, const Positions& P) {
  Positions out(P.rows(), 3);
  for (Eigen::Index v = 0; v < P.rows(); ++v) out.row(v) = transform_point(T, P.row(v)).transpose();
  return out;
}

inline std::string shared_data(const std::string& name) { return std::string(MSD_SHARED_DATA) + "/" + name; }
inline std::string cgal_mesh(const std::string& name) { return std::string(MSD_CGAL_DATA) + "/data/meshes/" + name; }
inline std::string cgal_deformation_data(const std::string& name) {
  return std::string(MSD_CGAL_DATA) + "/examples/Surface_mesh_deformation/data/" + name;
}
inline std::string test_data(const std::string& name) { return std::string(MSD_TEST_DATA) + "/" + name; }

//! A fresh empty folder under the system temp dir, removed when the object dies.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::random_device rd;
    path = std::filesystem::temp_directory_path() / ("msd-test-" + std::to_string(rd()) + std::to_string(rd()));
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::string file(const std::string& name) const { return (path / name).string(); }
  //! Writes text (bytes as they are) to the file name in this folder and returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(file(name), std::ios::binary) << text;
    return file(name);
  }
};

//! Largest distance between corresponding rows of A and B (same shape required).
inline double max_row_distance(const Positions& A, const Positions& B) {
  REQUIRE(A.rows() == B.rows());
  return (A - B).rowwise().norm().maxCoeff();
}

//! Max over the constrained vertices of |p' − T_k p| (fixed vertices: T = I), in mesh units.
inline double constraint_error(const Positions& rest, const Positions& out, const Region& region,
                               const std::vector<Mat4>& T) {
  double err = 0;
  for (int v : region.constrained_vertices()) {
    const int k = region.handle_of(v);
    const Vec3 target = k < 0 ? Vec3(rest.row(v)) : transform_point(T[k], rest.row(v));
    err = std::max(err, (Vec3(out.row(v)) - target).norm());
  }
  return err;
}

//! P (#V by 3) moved by x -> R x + t.
inline Positions rigid_motion(const Positions& P, const Mat3& R, const Vec3& t) {
  return (P * R.transpose()).rowwise() + t.transpose();
}

//! Unit icosahedron refined `levels` times by midpoint splits projected to the unit sphere.
inline void icosphere(int levels, Positions& P, Faces& F) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f.swap(g);
  }
  P.resize(v.size(), 3);
  for (size_t i = 0; i < v.size(); ++i) P.row(i) = v[i];
  F.resize(f.size(), 3);
  for (size_t i = 0; i < f.size(); ++i) F.row(i) = f[i];
}

//! The unit disk (z = 0) triangulated as one fan: vertex 0 at the centre, k around it (1..k), k faces.
inline void fan_disk(int k, Positions& P, Faces& F) {
  P.resize(k + 1, 3);
  F.resize(k, 3);
  P.row(0).setZero();
  for (int i = 0; i < k; ++i) {
    const double a = 2 * M_PI * i / k;
    P.row(i + 1) << std::cos(a), std::sin(a), 0;
    F.row(i) << 0, i + 1, (i + 1) % k + 1;
  }
}

//! Regular n x n grid on [0,1]^2 (z = 0) with interior vertices jittered in the plane by up to
//! jitter * spacing; returns interior flags via `interior`.
inline void jittered_grid(int n, double jitter, Positions& P, Faces& F, std::vector<bool>& interior, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  P.resize((n + 1) * (n + 1), 3);
  interior.assign(P.rows(), false);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const int k = j * (n + 1) + i;
      const bool inside = i > 0 && j > 0 && i < n && j < n;
      interior[k] = inside;
      P.row(k) << (i + (inside ? jitter * u(rng) : 0)) / n, (j + (inside ? jitter * u(rng) : 0)) / n, 0.0;
    }
  F.resize(2 * n * n, 3);
  for (int j = 0, f = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      F.row(f++) << a, b, d;
      F.row(f++) << a, d, c;
    }
}

// Rolls the plane z = 0 up onto a circular arc along x: x < x0 stays, [x0, x0 + R θ] goes onto the arc of
// radius R around (x0, ·, R) (concave side up, +z), the rest continues along the arc's end tangent. A point
// at height z above the plane goes to arc(x) + z n(x): the exact bend of a thick plate. With x0 = 0.2,
// R θ = 0.6 this is the bend120 scene: its handle transform is this map on x > 0.8.
struct ArcBend {
  double x0, R, theta;
  double angle(double x) const { return std::clamp((x - x0) / R, 0.0, theta); }
  Vec3 normal(double x) const {
    const double phi = angle(x);
    return Vec3(-std::sin(phi), 0, std::cos(phi));
  }
  Vec3 operator()(const Vec3& p) const {
    const double phi = angle(p.x()), s = p.x() - x0;
    Vec3 on_arc(x0 + R * std::sin(phi), p.y(), R * (1 - std::cos(phi)));
    if (s < 0) on_arc.x() = p.x();
    if (s > R * theta) on_arc += (s - R * theta) * Vec3(std::cos(theta), 0, std::sin(theta));
    return on_arc + p.z() * normal(p.x());
  }
  Positions operator()(const Positions& P) const {
    Positions out(P.rows(), 3);
    for (Eigen::Index i = 0; i < P.rows(); ++i) out.row(i) = (*this)(Vec3(P.row(i))).transpose();
    return out;
  }
};

}  // namespace msd::test
