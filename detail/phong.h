#pragma once
//! \file Points and Phong normals interpolated over base triangles: shared by the detail encodings.

#include "msdeform/core/types.h"

namespace msd::phong {

//! Below this length an interpolated normal has no usable direction (vertex normals cancelling).
constexpr double kMinNormalLength = 1e-12;

//! Rows of a #V by 3 column-major array read straight from its three columns (no Eigen block temporaries
//! in per-vertex loops).
struct Columns {
  const double *x, *y, *z;
  explicit Columns(const Positions& X) : x(X.data()), y(X.data() + X.rows()), z(X.data() + 2 * X.rows()) {}
  Vec3 row(long i) const { return Vec3(x[i], y[i], z[i]); }
};

//! Rows of a #V by 3 row-major array.
struct Rows {
  const double* p;
  explicit Rows(const RowPositions& X) : p(X.data()) {}
  Vec3 row(long i) const { return Vec3(p[3 * i], p[3 * i + 1], p[3 * i + 2]); }
};

//! Σ_k w_k X(corners_k).
template <class Points>
inline Vec3 interpolate(const Points& X, const int* corners, const Vec3& w) {
  return w[0] * X.row(corners[0]) + w[1] * X.row(corners[1]) + w[2] * X.row(corners[2]);
}

//! The displacement direction at barycentrics w of the triangle `corners` (seed 9.3.2): the normalised
//! interpolated vertex normal, or the unit face normal where that vanishes, or zero on a zero-area face.
template <class Points, class Normals>
inline Vec3 direction(const Points& X, const Normals& N, const int* corners, const Vec3& w) {
  const Vec3 m = interpolate(N, corners, w);
  const double len = m.norm();
  if (len > kMinNormalLength) return m / len;
  const Vec3 a = X.row(corners[0]);
  const Vec3 n = (X.row(corners[1]) - a).cross(X.row(corners[2]) - a);
  const double n_len = n.norm();
  return n_len > 0 ? Vec3(n / n_len) : Vec3::Zero();
}

}  // namespace msd::phong
