#pragma once
// Measures shared by the tests of the differential-coordinate editors (gradient, Laplacian).

#include <algorithm>
#include <cmath>
#include <string>

#include "msdeform/core/edit_case.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/region.h"
#include "msdeform/core/scenes.h"
#include "test_util.h"

namespace msd::test {

// A generated scene of about 3000 vertices.
inline Scene small_scene(const std::string& name) {
  SceneOptions o;
  o.resolution = 3000;
  return make_scene(name, o);
}

inline EditCase survey_case(const std::string& name) {
  const std::string base = shared_data("survey/" + name);
  return file_case(base + ".off", base + ".sel", base + ".def");
}

// Local scale change of each face: |√(area'/area) − 1|; the max and mean over faces touching a free vertex.
struct ScaleChange {
  double max = 0, mean = 0;
};
inline ScaleChange local_scale_change(const Positions& rest, const Positions& out, const Faces& F, const Region& region) {
  ScaleChange s;
  long n = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    if (!region.is_free(F(f, 0)) && !region.is_free(F(f, 1)) && !region.is_free(F(f, 2))) continue;
    auto area = [&](const Positions& P) {
      return (Vec3(P.row(F(f, 1)) - P.row(F(f, 0))).cross(Vec3(P.row(F(f, 2)) - P.row(F(f, 0))))).norm();
    };
    const double a0 = area(rest);
    if (!(a0 > 0)) continue;
    const double c = std::abs(std::sqrt(area(out) / a0) - 1);
    s.max = std::max(s.max, c);
    s.mean += c;
    ++n;
  }
  if (n) s.mean /= n;
  return s;
}

// Largest change of the angle between the normals of two faces sharing an edge (a crease measure).
inline double max_dihedral_change(const Positions& rest, const Positions& out, const Faces& F) {
  const Mesh mesh = make_mesh(rest, F);
  auto normal = [&](const Positions& P, Mesh::FaceHandle f) {
    Vec3 c[3];
    int k = 0;
    for (auto v : mesh.fv_range(f)) c[k++] = P.row(v.idx());
    return Vec3((c[1] - c[0]).cross(c[2] - c[0]).normalized());
  };
  double worst = 0;
  for (auto e : mesh.edges()) {
    if (e.is_boundary()) continue;
    const auto f0 = e.h0().face(), f1 = e.h1().face();
    const double a0 = std::acos(std::clamp(normal(rest, f0).dot(normal(rest, f1)), -1.0, 1.0));
    const double a1 = std::acos(std::clamp(normal(out, f0).dot(normal(out, f1)), -1.0, 1.0));
    worst = std::max(worst, std::abs(a1 - a0));
  }
  return worst;
}

}  // namespace msd::test
