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
  faces_ = Fs;
  base_faces_ = Fb;
  num_vertices_ = S.rows();
  num_base_vertices_ = B.rows();
  const bool shared = Fs.rows() == Fb.rows() && S.rows() == B.rows() && Fs == Fb;
  std::unique_ptr<ClosestPointQuery> query;
  if (!shared) query = std::make_unique<ClosestPointQuery>(B, Fb);
  reference_.resize(Fs.rows());
  rest_sign_.assign(Fs.rows(), 0);
  for (Eigen::Index f = 0; f < Fs.rows(); ++f) {
    const Vec3 centroid = (S.row(Fs(f, 0)) + S.row(Fs(f, 1)) + S.row(Fs(f, 2))) / 3;
    reference_[f] = shared ? static_cast<int>(f) : query->query(centroid).face;
    rest_sign_[f] = orientation(S, &faces_(f, 0), B, &base_faces_(reference_[f], 0));
  }
}

int FoldCheck::count(const Positions& S_deformed, const Positions& B_deformed) const {
  if (num_base_vertices_ < 0) throw UsageError("FoldCheck::count before prepare()");
  if (B_deformed.rows() != num_base_vertices_ || S_deformed.rows() != num_vertices_)
    throw UsageError("FoldCheck::count: S' or B' has the wrong number of rows");
  std::atomic<int> folded{0};
  parallel_for_chunks(static_cast<long>(faces_.rows()), [&](long begin, long end) {
    int n = 0;
    for (long f = begin; f < end; ++f)
      if (rest_sign_[f] != 0)
        n += orientation(S_deformed, &faces_(f, 0), B_deformed, &base_faces_(reference_[f], 0)) == -rest_sign_[f];
    folded += n;
  });
  return folded;
}

}  // namespace msd
