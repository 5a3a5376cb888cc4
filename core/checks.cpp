#include "msdeform/core/checks.h"

#include <string>

#include "msdeform/core/errors.h"

namespace msd {

void check_finite(const Positions& X, const char* who, const char* what) {
  if (X.allFinite()) return;
  for (Eigen::Index v = 0; v < X.rows(); ++v)
    if (!X.row(v).allFinite())
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
