#include "decomposition/laplace.h"

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/laplacian.h"

namespace msd {

LaplaceOperator laplace_operator(const Positions& P, const Faces& F, LaplacianWeights weights) {
  LaplaceOperator op;
  const int nv = static_cast<int>(P.rows());
  if (weights == LaplacianWeights::Cotan) {
    CotanLaplacian lap = cotan_laplacian(P, F);
    op.W = std::move(lap.W);
    op.mass = std::move(lap.mass);
    return op;
  }
  op.W = uniform_laplacian(F, nv);
  const double h = mean_edge_length(P, F);
  // On a regular triangulation with edge h the umbrella D⁻¹W applied to x² + y² gives h², while Δ gives 4.
  op.mass = -op.W.diagonal() * (h * h / 4.0);
  return op;
}

double mean_edge_length(const Positions& P, const Faces& F) {
  if (F.rows() == 0) return 0;
  double sum = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) sum += (P.row(F(f, k)) - P.row(F(f, (k + 1) % 3))).norm();
  return sum / (3.0 * static_cast<double>(F.rows()));
}

void check_mesh_arrays(const Positions& P, const Faces& F, const char* who) {
  const Eigen::Index nv = P.rows();
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= nv)
        throw InvalidInput(std::string(who) + ": face " + std::to_string(f) + " has vertex index " +
                           std::to_string(F(f, k)) + ", outside [0, " + std::to_string(nv) + ")");
  if (!P.allFinite())
    for (Eigen::Index v = 0; v < nv; ++v)
      if (!P.row(v).allFinite())
        throw InvalidInput(std::string(who) + ": vertex " + std::to_string(v) +
                           " has a non-finite coordinate");
}

std::vector<int> boundary_vertices(const Faces& F, int num_vertices) {
  // Undirected edges as sorted 64-bit keys; a key that occurs once is a boundary edge.
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const auto a = static_cast<std::uint64_t>(F(f, k)), b = static_cast<std::uint64_t>(F(f, (k + 1) % 3));
      edges.push_back(std::min(a, b) << 32 | std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  std::vector<char> on_boundary(num_vertices, 0);
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) on_boundary[edges[i] >> 32] = on_boundary[edges[i] & 0xffffffffu] = 1;
    i = j;
  }
  std::vector<int> out;
  for (int v = 0; v < num_vertices; ++v)
    if (on_boundary[v]) out.push_back(v);
  return out;
}

const char* to_string(LaplacianWeights weights) {
  return weights == LaplacianWeights::Cotan ? "cotan" : "uniform";
}

}  // namespace msd
