#include "msdeform/detail/fold_check.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/detail/closest_point.h"
#include "msdeform/detail/phong.h"

namespace msd {
namespace {

// n_a · n_b for triangle ta of A and tb of B, each n twice the area-weighted normal. Raw columns and
// indices in locals: this runs every frame over all triangles (Eigen's row views of the column-major
// arrays cost a third of it). Of order size⁴: it overflows beyond sizes of about 1e77 and underflows below
// 1e-77, where orientation() takes over.
inline double dot_of_normals(const phong::Columns& A, const int* ta, const phong::Columns& B, const int* tb) {
  const int a0 = ta[0], a1 = ta[1], a2 = ta[2], b0 = tb[0], b1 = tb[1], b2 = tb[2];
  const double ax = A.x[a1] - A.x[a0], ay = A.y[a1] - A.y[a0], az = A.z[a1] - A.z[a0];
  const double cx = A.x[a2] - A.x[a0], cy = A.y[a2] - A.y[a0], cz = A.z[a2] - A.z[a0];
  const double ex = B.x[b1] - B.x[b0], ey = B.y[b1] - B.y[b0], ez = B.z[b1] - B.z[b0];
  const double gx = B.x[b2] - B.x[b0], gy = B.y[b2] - B.y[b0], gz = B.z[b2] - B.z[b0];
  return (ay * cz - az * cy) * (ey * gz - ez * gy) + (az * cx - ax * cz) * (ez * gx - ex * gz) +
         (ax * cy - ay * cx) * (ex * gy - ey * gx);
}

// The normal of triangle t of X scaled to a largest component of 1, from edges scaled the same way (no
// overflow or underflow at any finite size); zero for a triangle that cotan_laplacian calls degenerate
// (area below 1e-14 of its squared longest edge): its orientation is rounding noise.
Vec3 unit_scale_normal(const phong::Columns& X, const int* t) {
  const Vec3 p0 = X.row(t[0]);
  Vec3 e1 = X.row(t[1]) - p0, e2 = X.row(t[2]) - p0;
  const double scale = std::max(e1.cwiseAbs().maxCoeff(), e2.cwiseAbs().maxCoeff());
  if (!(scale > 0) || !std::isfinite(scale)) return Vec3::Zero();
  e1 /= scale, e2 /= scale;
  const Vec3 n = e1.cross(e2);
  const double longest2 = std::max({e1.squaredNorm(), e2.squaredNorm(), (e2 - e1).squaredNorm()});
  if (!(n.norm() > 2 * TriangleCotangents::kDegenerateAreaRatio * longest2)) return Vec3::Zero();
  return n / n.cwiseAbs().maxCoeff();
}

// A product of normals whose sign can be trusted: neither zero, subnormal nor overflowed.
inline bool normal_range(double d) {
  const double m = std::abs(d);
  return m >= std::numeric_limits<double>::min() && m <= std::numeric_limits<double>::max();
}

// Sign of n_a · n_b (−1, 0 or 1), right at any finite size; 0 where either triangle is degenerate.
int orientation(const phong::Columns& A, const int* ta, const phong::Columns& B, const int* tb) {
  const double d = unit_scale_normal(A, ta).dot(unit_scale_normal(B, tb));
  return (d > 0) - (d < 0);
}

}  // namespace

void FoldCheck::prepare(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) {
  const char* who = "FoldCheck::prepare";
  check_faces(Fs, S.rows(), who, "S");
  check_faces(Fb, B.rows(), who, "B");
  const bool shared = Fs.rows() == Fb.rows() && S.rows() == B.rows() && Fs == Fb;
  faces_ = Fs;
  base_faces_ = shared ? Faces() : Fb;  // shared: triangle t of S is triangle t of B
  shared_ = shared;
  num_vertices_ = S.rows();
  num_base_vertices_ = B.rows();
  std::unique_ptr<ClosestPointQuery> query;
  if (!shared) query = std::make_unique<ClosestPointQuery>(B, Fb);
  reference_.resize(shared ? 0 : Fs.rows());
  rest_sign_.assign(Fs.rows(), 0);
  const phong::Columns s(S), b(B);
  for (Eigen::Index f = 0; f < Fs.rows(); ++f) {
    int r = static_cast<int>(f);
    if (!shared) {
      const Vec3 centroid = (S.row(Fs(f, 0)) + S.row(Fs(f, 1)) + S.row(Fs(f, 2))) / 3;
      r = reference_[f] = query->query(centroid).face;
    }
    rest_sign_[f] = static_cast<signed char>(orientation(s, &Fs(f, 0), b, &Fb(r, 0)));
  }
}

int FoldCheck::count(const Positions& S_deformed, const Positions& B_deformed) const {
  if (num_base_vertices_ < 0) throw UsageError("FoldCheck::count before prepare()");
  if (B_deformed.rows() != num_base_vertices_ || S_deformed.rows() != num_vertices_)
    throw UsageError("FoldCheck::count: S' or B' has the wrong number of rows");
  const phong::Columns s(S_deformed), b(B_deformed);
  const int* const fs = faces_.data();
  const int* const fb = shared_ ? fs : base_faces_.data();
  const int* const ref = shared_ ? nullptr : reference_.data();
  const signed char* const rest = rest_sign_.data();
  std::atomic<int> folded{0}, unsure{0};
  parallel_for_chunks(static_cast<long>(faces_.rows()), [=, &folded, &unsure](long begin, long end) {
    int n = 0, u = 0;
    for (long f = begin; f < end; ++f) {
      // Folded when the orientation changed sign: (n_S' · n_B') · rest < 0. Branch-free: a data-dependent
      // branch per triangle (skip the uncounted ones, compare signs) costs half of the pass. A product that
      // is zero, subnormal or not finite (a collapsed triangle, or sizes beyond 1e±77) is unsure.
      const double d = dot_of_normals(s, fs + 3 * f, b, fb + 3 * (ref ? ref[f] : f));
      n += d * rest[f] < 0;
      u += (rest[f] != 0) & !normal_range(d);
    }
    folded += n;
    unsure += u;
  });
  if (unsure == 0) return folded;
  // Rare: the pass again, deciding the unsure triangles from normals scaled to unit size.
  int recount = 0;
  for (long f = 0; f < static_cast<long>(faces_.rows()); ++f) {
    if (rest[f] == 0) continue;
    const int* tb = fb + 3 * (ref ? ref[f] : f);
    const double d = dot_of_normals(s, fs + 3 * f, b, tb);
    recount += normal_range(d) ? d * rest[f] < 0 : orientation(s, fs + 3 * f, b, tb) == -rest[f];
  }
  return recount;
}

}  // namespace msd
