#include "msdeform/decomposition/detail_check.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"

namespace msd {

DetailCheck check_details(const Positions& S, const Positions& B, const Faces& F) {
  const char* who = "check_details";
  if (S.rows() != B.rows())
    throw InvalidInput(std::string(who) + ": S has " + std::to_string(S.rows()) + " vertices, B " +
                       std::to_string(B.rows()));
  check_mesh_arrays(B, F, who);
  check_finite(S, who, "S");
  const long nv = static_cast<long>(B.rows());
  const Positions N = vertex_normals(B, F);
  Eigen::VectorXd height(nv), max_kappa = Eigen::VectorXd::Zero(nv), fold = Eigen::VectorXd::Zero(nv);
  for (long i = 0; i < nv; ++i) height[i] = (S.row(i) - B.row(i)).dot(N.row(i));
  // Every directed edge i → j of every face (interior edges are visited twice per direction: harmless).
  std::vector<char> boundary(nv, 0);
  for (int v : boundary_vertices(F, static_cast<int>(nv))) boundary[v] = 1;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      for (int d = 1; d <= 2; ++d) {
        const int i = F(f, k), j = F(f, (k + d) % 3);
        const Vec3 e = B.row(j) - B.row(i);
        const double len2 = e.squaredNorm();
        if (!(len2 > 0) || boundary[i] || N.row(i).squaredNorm() == 0 || N.row(j).squaredNorm() == 0) continue;
        const double kappa = (N.row(i) - N.row(j)).dot(e) / len2;
        max_kappa[i] = std::max(max_kappa[i], std::abs(kappa));
        fold[i] = std::max(fold[i], height[i] * kappa);
      }
  DetailCheck c;
  double sum2 = 0;
  for (long i = 0; i < nv; ++i) {
    const double d = (S.row(i) - B.row(i)).norm();
    c.max_height = std::max(c.max_height, d);
    sum2 += d * d;
    if (max_kappa[i] > 0) c.min_curvature_radius = std::min(c.min_curvature_radius, 1 / max_kappa[i]);
    if (fold[i] >= 1) ++c.folding_vertices;
    if (fold[i] > c.max_fold_ratio) {
      c.max_fold_ratio = fold[i];
      c.worst_vertex = static_cast<int>(i);
    }
  }
  c.rms_height = nv > 0 ? std::sqrt(sum2 / static_cast<double>(nv)) : 0.0;
  if (nv > 0) {
    std::vector<double> ratio(fold.data(), fold.data() + nv);
    const auto q = ratio.begin() + std::min<long>(nv - 1, static_cast<long>(0.999 * static_cast<double>(nv)));
    std::nth_element(ratio.begin(), q, ratio.end());
    c.fold_ratio_p999 = *q;
  }
  if (c.worst_vertex >= 0) {
    c.worst_height = std::abs(height[c.worst_vertex]);
    c.worst_radius = 1 / max_kappa[c.worst_vertex];
  }
  return c;
}

}  // namespace msd
