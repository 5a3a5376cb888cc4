#include "msdeform/detail/fold_check.h"

#include <atomic>
#include <memory>
#include <string>

#include "msdeform/core/errors.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/detail/closest_point.h"
#include "msdeform/detail/phong.h"

namespace msd {
namespace {

// Twice the area-weighted normal of triangle t of X.
void normal(const phong::Columns& X, const int* t, double n[3]) {
  const double ax = X.x[t[1]] - X.x[t[0]], ay = X.y[t[1]] - X.y[t[0]], az = X.z[t[1]] - X.z[t[0]];
  const double bx = X.x[t[2]] - X.x[t[0]], by = X.y[t[2]] - X.y[t[0]], bz = X.z[t[2]] - X.z[t[0]];
  n[0] = ay * bz - az * by, n[1] = az * bx - ax * bz, n[2] = ax * by - ay * bx;
}

// Sign of n_a · n_b for triangle ta of A and tb of B: −1, 0 (a degenerate one) or 1. Raw columns: this
// runs every frame over all triangles, and Eigen's row views of the column-major arrays cost a third of it.
signed char orientation(const phong::Columns& A, const int* ta, const phong::Columns& B, const int* tb) {
  double na[3], nb[3];
  normal(A, ta, na);
  normal(B, tb, nb);
  const double d = na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2];
  return static_cast<signed char>((d > 0) - (d < 0));
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
    rest_sign_[f] = orientation(s, &Fs(f, 0), b, &Fb(r, 0));
  }
}

int FoldCheck::count(const Positions& S_deformed, const Positions& B_deformed) const {
  if (num_base_vertices_ < 0) throw UsageError("FoldCheck::count before prepare()");
  if (B_deformed.rows() != num_base_vertices_ || S_deformed.rows() != num_vertices_)
    throw UsageError("FoldCheck::count: S' or B' has the wrong number of rows");
  const phong::Columns s(S_deformed), b(B_deformed);
  const int* fs = faces_.data();
  const int* fb = shared_ ? fs : base_faces_.data();
  const int* ref = shared_ ? nullptr : reference_.data();
  const signed char* rest = rest_sign_.data();
  std::atomic<int> folded{0};
  parallel_for_chunks(static_cast<long>(faces_.rows()), [&](long begin, long end) {
    int n = 0;
    for (long f = begin; f < end; ++f)
      if (rest[f] != 0) n += orientation(s, fs + 3 * f, b, fb + 3 * (ref ? ref[f] : f)) == -rest[f];
    folded += n;
  });
  return folded;
}

}  // namespace msd
