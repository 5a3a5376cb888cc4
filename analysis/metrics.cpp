#include "analysis/metrics.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "core/checks.h"
#include "core/errors.h"
#include "core/laplacian.h"
#include "core/parallel.h"
#include "core/laplacian.h"
#include "detail/normal_displacements.h"

namespace msd {
namespace {

void require_same_rows(const Positions& A, const Positions& B, const char* who, const char* a_name,
                       const char* b_name) {
  if (A.rows() != B.rows())
    throw InvalidInput(std::string(who) + ": " + a_name + " has " + std::to_string(A.rows()) +
                       " vertices but " + b_name + " has " + std::to_string(B.rows()));
}

void require_finite(const Positions& P, const char* who, const char* name) {
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    if (!P.row(i).allFinite())
      throw InvalidInput(std::string(who) + ": " + name + " has a non-finite coordinate at vertex " +
                         std::to_string(i));
}

// Sorted, unique one-ring neighbours of every vertex in compressed rows.
struct Neighbours {
  std::vector<int> offsets, indices;
};

Neighbours one_rings(const Faces& F, int num_vertices) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(F.rows() * 6);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      if (a == b) continue;
      edges.emplace_back(a, b);
      edges.emplace_back(b, a);
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  Neighbours n;
  n.offsets.assign(num_vertices + 1, 0);
  n.indices.reserve(edges.size());
  for (const auto& [a, b] : edges) {
    ++n.offsets[a + 1];
    n.indices.push_back(b);
  }
  for (int v = 0; v < num_vertices; ++v) n.offsets[v + 1] += n.offsets[v];
  return n;
}

// Local ARAP step for one vertex: the residual of the best rotation and the normaliser Σ w |e|².
// for_each(visit) calls visit(j, w_ij) for every weighted neighbour j of i.
template <class ForEachNeighbour>
double one_ring_residual(const Positions& rest, const Positions& deformed, int i, ForEachNeighbour&& for_each,
                         double& normaliser) {
  Mat3 covariance = Mat3::Zero();
  normaliser = 0;
  const Vec3 p = rest.row(i).transpose(), q = deformed.row(i).transpose();
  for_each([&](int j, double w) {
    const Vec3 e = p - rest.row(j).transpose(), e1 = q - deformed.row(j).transpose();
    covariance += w * e * e1.transpose();
    normaliser += w * e.squaredNorm();
  });
  if (!(normaliser > 0)) return 0;
  // R = V Uᵀ maximises tr(R S) for S = U Σ Vᵀ; flipping the column of the smallest singular value keeps
  // R a rotation when V Uᵀ would be a reflection.
  const Eigen::JacobiSVD<Mat3> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  Mat3 R = svd.matrixV() * U.transpose();
  if (R.determinant() < 0) {
    U.col(2) = -U.col(2);
    R = svd.matrixV() * U.transpose();
  }
  double residual = 0;
  for_each([&](int j, double w) {
    const Vec3 e = p - rest.row(j).transpose(), e1 = q - deformed.row(j).transpose();
    residual += w * (e1 - R * e).squaredNorm();
  });
  return residual;
}

}  // namespace

Stats summarize(const Eigen::VectorXd& values) {
  std::vector<int> all(values.size());
  for (Eigen::Index i = 0; i < values.size(); ++i) all[i] = static_cast<int>(i);
  return summarize(values, all);
}

Stats summarize(const Eigen::VectorXd& values, const std::vector<int>& subset) {
  Stats s;
  if (subset.empty()) return s;
  std::vector<double> v;
  v.reserve(subset.size());
  for (int i : subset) {
    if (i < 0 || i >= values.size())
      throw InvalidInput("summarize: index " + std::to_string(i) + " is outside the " +
                         std::to_string(values.size()) + " values");
    v.push_back(values[i]);
  }
  double sum = 0;
  for (double x : v) sum += x;
  s.count = static_cast<int>(v.size());
  s.mean = sum / s.count;
  s.max = *std::max_element(v.begin(), v.end());
  // Nearest rank: the smallest value with at least 95% of the values at or below it.
  const size_t rank = static_cast<size_t>(std::ceil(0.95 * static_cast<double>(v.size())));
  const size_t k = std::clamp<size_t>(rank, 1, v.size()) - 1;
  std::nth_element(v.begin(), v.begin() + k, v.end());
  s.p95 = v[k];
  return s;
}

double handle_error(const Positions& rest, const Positions& deformed, const Region& region,
                    const std::vector<Mat4>& transforms) {
  const char* who = "handle_error";
  require_same_rows(rest, deformed, who, "rest", "deformed");
  if (region.num_vertices() != rest.rows())
    throw InvalidInput(std::string(who) + ": region has " + std::to_string(region.num_vertices()) +
                       " vertices but the mesh has " + std::to_string(rest.rows()));
  if (static_cast<int>(transforms.size()) < region.num_handles())
    throw InvalidInput(std::string(who) + ": region has " + std::to_string(region.num_handles()) +
                       " handles but only " + std::to_string(transforms.size()) + " transforms were given");
  double error = 0;
  for (int v = 0; v < region.num_vertices(); ++v) {
    const Vec3 p = rest.row(v).transpose();
    const int h = region.handle_of(v);
    Vec3 target;
    if (h >= 0)
      target = transform_point(transforms[h], p);
    else if (region.is_fixed(v))
      target = p;
    else
      continue;
    error = std::max(error, (deformed.row(v).transpose() - target).norm());
  }
  return error;
}

RigidityError rigidity_error(const Positions& rest, const Positions& deformed, const Faces& F,
                             const RigidityOptions& options) {
  const char* who = "rigidity_error";
  require_same_rows(rest, deformed, who, "rest", "deformed");
  check_mesh_arrays(rest, F, who);
  require_finite(deformed, who, "deformed");
  const int nv = static_cast<int>(rest.rows());
  const Neighbours ring = one_rings(F, nv);
  SparseMatrix W;
  if (options.weights == RigidityWeights::Cotan) W = cotan_laplacian(rest, F).W;

  RigidityError out;
  out.per_vertex = Eigen::VectorXd::Zero(nv);
  parallel_for_chunks(
      nv,
      [&](long begin, long end) {
        for (long v = begin; v < end; ++v) {
          const int i = static_cast<int>(v);
          auto uniform = [&](auto&& visit) {
            for (int k = ring.offsets[i]; k < ring.offsets[i + 1]; ++k) visit(ring.indices[k], 1.0);
          };
          double normaliser = 0, residual = 0;
          if (options.weights == RigidityWeights::Cotan) {
            // W is symmetric, so column i lists the weights W_ji = W_ij of i's edges.
            auto cotan = [&](auto&& visit) {
              for (SparseMatrix::InnerIterator it(W, i); it; ++it)
                if (it.row() != i && it.value() > 0) visit(static_cast<int>(it.row()), it.value());
            };
            residual = one_ring_residual(rest, deformed, i, cotan, normaliser);
          }
          if (!(normaliser > 0)) residual = one_ring_residual(rest, deformed, i, uniform, normaliser);
          out.per_vertex[i] = normaliser > 0 ? residual / normaliser : 0.0;
        }
      },
      1024);
  std::vector<int> connected;
  for (int v = 0; v < nv; ++v)
    if (ring.offsets[v + 1] > ring.offsets[v]) connected.push_back(v);
  out.stats = summarize(out.per_vertex, connected);
  return out;
}

DetailDistortion detail_distortion(const Positions& rest, const Positions& deformed, const Faces& F,
                                   const Region& region, const FairingOptions& fairing) {
  const char* who = "detail_distortion";
  require_same_rows(rest, deformed, who, "rest", "deformed");
  if (region.num_vertices() != rest.rows())
    throw InvalidInput(std::string(who) + ": region has " + std::to_string(region.num_vertices()) +
                       " vertices but the mesh has " + std::to_string(rest.rows()));
  const std::vector<int> free = region.free_vertices();
  if (free.empty())
    throw InvalidInput(std::string(who) + ": the region has no free vertex to measure details on");

  const Positions B0 = fair_region(rest, F, region, fairing);
  const Positions B1 = fair_region(deformed, F, region, fairing);
  NormalDisplacements before, after;
  before.encode(rest, F, B0, F);
  after.encode(deformed, F, B1, F);

  DetailDistortion out;
  out.rest_heights = before.heights();
  out.deformed_heights = after.heights();
  out.fallback_vertices = before.report().fallback + after.report().fallback;
  out.per_vertex = Eigen::VectorXd::Zero(rest.rows());
  double max_height = 0;
  for (int v : free) {
    out.per_vertex[v] = std::abs(out.deformed_heights[v] - out.rest_heights[v]);
    max_height = std::max(max_height, std::abs(out.rest_heights[v]));
  }
  const double diagonal = bounding_box_diagonal(rest);
  out.scale = max_height > 1e-12 * diagonal ? max_height : diagonal;
  if (!(out.scale > 0)) throw InvalidInput(std::string(who) + ": the rest mesh has zero extent");
  out.stats = summarize(out.per_vertex / out.scale, free);
  return out;
}

bool is_closed(const Faces& F, int num_vertices) {
  if (F.rows() == 0) return false;
  std::vector<std::pair<int, int>> forward, backward;
  forward.reserve(3 * F.rows());
  backward.reserve(3 * F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      if (a < 0 || a >= num_vertices)
        throw InvalidInput("is_closed: face " + std::to_string(f) + " has vertex index " + std::to_string(a) +
                           " outside [0, " + std::to_string(num_vertices) + ")");
      forward.emplace_back(a, b);
      backward.emplace_back(b, a);
    }
  std::sort(forward.begin(), forward.end());
  std::sort(backward.begin(), backward.end());
  return forward == backward;
}

std::optional<double> volume(const Positions& P, const Faces& F) {
  check_mesh_arrays(P, F, "volume");
  if (!is_closed(F, static_cast<int>(P.rows()))) return std::nullopt;
  double six_volume = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = P.row(F(f, 0)), b = P.row(F(f, 1)), c = P.row(F(f, 2));
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6.0;
}

std::optional<double> volume_change(const Positions& rest, const Positions& deformed, const Faces& F) {
  require_same_rows(rest, deformed, "volume_change", "rest", "deformed");
  const std::optional<double> v0 = volume(rest, F);
  if (!v0 || *v0 == 0) return std::nullopt;
  const std::optional<double> v1 = volume(deformed, F);
  return *v1 / *v0 - 1.0;
}

ReferenceDistance distance_to_reference(const Positions& P, const Faces& F, const Positions& Q,
                                        const Faces& FQ) {
  const char* who = "distance_to_reference";
  require_same_rows(P, Q, who, "the result", "the reference");
  if (F.rows() != FQ.rows())
    throw InvalidInput(std::string(who) + ": the result has " + std::to_string(F.rows()) +
                       " faces but the reference has " + std::to_string(FQ.rows()) +
                       "; both must share one connectivity");
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    if (F.row(f) != FQ.row(f))
      throw InvalidInput(std::string(who) + ": face " + std::to_string(f) +
                         " differs between the result and the reference; both must share one connectivity");
  require_finite(P, who, "the result");
  require_finite(Q, who, "the reference");
  ReferenceDistance out;
  out.diagonal = bounding_box_diagonal(Q);
  if (!(out.diagonal > 0))
    throw InvalidInput(std::string(who) + ": the reference has a zero bounding-box diagonal");
  if (P.rows() == 0) return out;
  const Eigen::VectorXd d = (P - Q).rowwise().norm();
  out.max = d.maxCoeff() / out.diagonal;
  out.mean = d.mean() / out.diagonal;
  return out;
}

}  // namespace msd
