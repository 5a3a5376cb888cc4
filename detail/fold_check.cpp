#include "msdeform/detail/fold_check.h"

#include <atomic>
#include <memory>
#include <string>

#include "msdeform/core/errors.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/detail/closest_point.h"

namespace msd {
namespace {

// Sign of n_a · n_b for triangles (a0, a1, a2) and (b0, b1, b2): −1, 0 (a degenerate one) or 1.
template <class A, class B>
signed char orientation(const A& a, const int* fa, const B& b, const int* fb) {
  const Vec3 a0 = a.row(fa[0]), b0 = b.row(fb[0]);
  const Vec3 na = (Vec3(a.row(fa[1])) - a0).cross(Vec3(a.row(fa[2])) - a0);
  const Vec3 nb = (Vec3(b.row(fb[1])) - b0).cross(Vec3(b.row(fb[2])) - b0);
  const double d = na.dot(nb);
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
  for (Eigen::Index f = 0; f < Fs.rows(); ++f) {
    int r = static_cast<int>(f);
    if (!shared) {
      const Vec3 centroid = (S.row(Fs(f, 0)) + S.row(Fs(f, 1)) + S.row(Fs(f, 2))) / 3;
      r = reference_[f] = query->query(centroid).face;
    }
    rest_sign_[f] = orientation(S, &Fs(f, 0), B, &Fb(r, 0));
  }
}

int FoldCheck::count(const Positions& S_deformed, const Positions& B_deformed) const {
  if (num_base_vertices_ < 0) throw UsageError("FoldCheck::count before prepare()");
  if (B_deformed.rows() != num_base_vertices_ || S_deformed.rows() != num_vertices_)
    throw UsageError("FoldCheck::count: S' or B' has the wrong number of rows");
  // Raw column pointers: this runs every frame over all triangles, and Eigen's row views of the
  // column-major arrays cost a third of it.
  struct Cols {
    const double *x, *y, *z;
    explicit Cols(const Positions& P) : x(P.data()), y(P.data() + P.rows()), z(P.data() + 2 * P.rows()) {}
    // Twice the area-weighted normal of triangle t.
    void normal(const int* t, double n[3]) const {
      const double ax = x[t[1]] - x[t[0]], ay = y[t[1]] - y[t[0]], az = z[t[1]] - z[t[0]];
      const double bx = x[t[2]] - x[t[0]], by = y[t[2]] - y[t[0]], bz = z[t[2]] - z[t[0]];
      n[0] = ay * bz - az * by, n[1] = az * bx - ax * bz, n[2] = ax * by - ay * bx;
    }
  };
  const Cols s(S_deformed), b(B_deformed);
  const int* fs = faces_.data();
  const int* fb = shared_ ? fs : base_faces_.data();
  const int* ref = shared_ ? nullptr : reference_.data();
  const signed char* rest = rest_sign_.data();
  std::atomic<int> folded{0};
  parallel_for_chunks(static_cast<long>(faces_.rows()), [&](long begin, long end) {
    int n = 0;
    for (long f = begin; f < end; ++f) {
      if (rest[f] == 0) continue;
      double ns[3], nb[3];
      s.normal(fs + 3 * f, ns);
      b.normal(fb + 3 * (ref ? ref[f] : f), nb);
      const double d = ns[0] * nb[0] + ns[1] * nb[1] + ns[2] * nb[2];
      n += ((d > 0) - (d < 0)) == -rest[f];
    }
    folded += n;
  });
  return folded;
}

}  // namespace msd
