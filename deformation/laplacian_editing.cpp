#include "msdeform/deformation/laplacian_editing.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/parallel.h"
#include "msdeform/deformation/propagation.h"

namespace msd {

LaplacianEditing::LaplacianEditing(LaplacianEditingOptions options) : options_(options) {}

DeformerTraits LaplacianEditing::traits() const {
  DeformerTraits t;
  t.reproduces_rigid_motions = !options_.implicit;
  return t;
}

namespace {
Positions rest_laplace_coordinates(const LaplaceOperator& lap, const Positions& P) {
  Positions delta = lap.W * P;
  for (Eigen::Index i = 0; i < delta.rows(); ++i) delta.row(i) *= lap.mass[i] > 0 ? 1.0 / lap.mass[i] : 0.0;
  return delta;
}
}  // namespace

void LaplacianEditing::prepare_local(const Positions& P, const Faces& F, const Region& region) {
  rest_ = P;
  constrained_ = region.constrained_vertices();
  handle_of_constrained_.resize(constrained_.size());
  for (size_t c = 0; c < constrained_.size(); ++c) handle_of_constrained_[c] = region.handle_of(constrained_[c]);
  if (options_.implicit)
    prepare_implicit(P, F, region);
  else
    prepare_explicit(P, F, region);
  free_edges_ = FreeEdgeLengths(P, F, region);
}

void LaplacianEditing::check_scale(const Positions& out) {
  if (free_edges_.edges.empty()) return;
  const double scale = free_edges_.mean_scale(out);
  if (!(scale <= kMaxMeanScale))
    frame_report_.warnings.push_back(
        name_ + ": the edges around the free vertices changed length by a factor " + format_number(scale) +
        " on average (grown or shrunk): " +
        (options_.implicit
             ? "the linearised rotations of implicit Laplacian editing scale the surface under large "
               "rotations (seed 9.4.2); use gradient, multiscale or the explicit variant"
             : "the edit stretches the free region"));
}

void LaplacianEditing::prepare_implicit(const Positions& P, const Faces& F, const Region& region) {
  const int nv = static_cast<int>(P.rows());
  const LaplaceOperator lap = cotan_laplacian(P, F);
  // A free vertex without area has no residual rows of its own, yet its neighbours' ring fits still reach it:
  // R^T R is then not singular, only nearly, it factors, and the vertex lands anywhere (measured: CGAL's
  // cow with one one-ring collapsed to a point moved a vertex 7.9 units under a 0.1 translation).
  for (int v : region.free_vertices())
    if (!(lap.mass[v] > 0))
      throw SolverError("laplacian: the least-squares system is singular near vertex " + std::to_string(v) +
                            " (a free vertex whose faces all have zero area: repair the mesh there)",
                        v);
  check_neighbour_coupling(lap.W, 3, "laplacian: the least-squares system R^T R (x, y and z coupled)");
  delta_ = rest_laplace_coordinates(lap, P);
  const VertexAdjacency rings = vertex_adjacency(F, nv);
  // Residual operator R (3#V by 3#V, variable 3v + d): row block i is
  //   √A_i · T_i(p') δ_i − (1/√A_i) · (W p')_i,   so E = ‖R p'‖² is (9.11) with Δ = M⁻¹W.
  constexpr long kBlock = 4096;  // one triplet list per block of vertices, filled in parallel
  std::vector<std::vector<Triplet>> parts(static_cast<size_t>((nv + kBlock - 1) / kBlock));
  parallel_for_chunks(static_cast<long>(parts.size()), [&](long b0, long e0) {
   for (long block = b0; block < e0; ++block) {
    std::vector<Triplet>& out = parts[static_cast<size_t>(block)];
    Eigen::MatrixXd A, pinv;
    for (long i = block * kBlock; i < std::min<long>(nv, (block + 1) * kBlock); ++i) {
      const double mass = lap.mass[i];
      if (!(mass > 0) || rings.degree(i) == 0) continue;
      const double root = std::sqrt(mass);
      for (SparseMatrix::InnerIterator it(lap.W, i); it; ++it)  // W symmetric: column i = row i
        for (int d = 0; d < 3; ++d) out.emplace_back(3 * i + d, 3 * it.row() + d, -it.value() / root);
      // Least-squares fit of (s, h₁, h₂, h₃, t) over the ring {i} ∪ N(i), coordinates relative to p_i.
      const int m = 1 + rings.degree(i);
      A.setZero(3 * m, 7);
      auto ring = [&](int r) { return r == 0 ? static_cast<int>(i) : rings.begin(i)[r - 1]; };
      // The ring in units of its own size ℓ: the similarity columns and the translation columns then have
      // comparable norms, so the pseudo-inverse's rank test does not drop the similarity of a mesh modelled
      // in tiny (or huge) units. The fit gives (ℓs, ℓh, t); C divides ℓ out again.
      double ell = 0;
      for (int r = 1; r < m; ++r) ell = std::max(ell, (P.row(ring(r)) - P.row(i)).norm());
      if (!(ell > 0)) ell = 1;
      for (int r = 0; r < m; ++r) {
        const Vec3 q = (P.row(ring(r)) - P.row(i)) / ell;
        A.row(3 * r + 0) << q.x(), 0, q.z(), -q.y(), 1, 0, 0;
        A.row(3 * r + 1) << q.y(), -q.z(), 0, q.x(), 0, 1, 0;
        A.row(3 * r + 2) << q.z(), q.y(), -q.x(), 0, 0, 0, 1;
      }
      pinv = A.completeOrthogonalDecomposition().pseudoInverse();  // 7 by 3m
      // T_i δ_i = s δ + h × δ = [δ | −[δ]ₓ] (s, h)ᵀ.
      const Vec3 dl = delta_.row(i);
      Eigen::Matrix<double, 3, 4> E;
      E.col(0) = dl;
      E.block<3, 3>(0, 1) << 0, dl.z(), -dl.y(), -dl.z(), 0, dl.x(), dl.y(), -dl.x(), 0;
      const Eigen::MatrixXd C = (root / ell) * (E * pinv.topRows<4>());  // 3 by 3m
      for (int r = 0; r < m; ++r)
        for (int a = 0; a < 3; ++a)
          for (int d = 0; d < 3; ++d)
            if (C(a, 3 * r + d) != 0) out.emplace_back(3 * i + a, 3 * ring(r) + d, C(a, 3 * r + d));
    }
   }
  }, 1);
  std::vector<Triplet> triplets;
  size_t total = 0;
  for (const auto& p : parts) total += p.size();
  triplets.reserve(total);
  for (auto& p : parts) triplets.insert(triplets.end(), p.begin(), p.end());
  SparseMatrix R(3 * nv, 3 * nv);
  R.setFromTriplets(triplets.begin(), triplets.end());
  triplets = {};
  const SparseMatrix Q = SparseMatrix(R.transpose()) * R;
  std::vector<int> known;
  known.reserve(3 * constrained_.size());
  for (int v : constrained_)
    for (int d = 0; d < 3; ++d) known.push_back(3 * v + d);
  try {
    system_.prepare(Q, known);
  } catch (const SolverError& e) {
    if (e.index() < 0) throw SolverError(std::string("laplacian: ") + e.what());  // not singular: e.g. out of memory
    const long v = e.index() >= 0 ? e.index() / 3 : -1;
    throw SolverError("laplacian: the least-squares system is singular near vertex " + std::to_string(v) +
                          " (a free vertex whose faces all have zero area, a one-ring too degenerate to fit, or "
                          "fixed and handle vertices too few or too flat to pin the free region's linearised "
                          "rotations: fix a larger region, or use the explicit variant or gradient editing)",
                      v);
  }
  frame_.prepare(system_, 1);
}

void LaplacianEditing::prepare_explicit(const Positions& P, const Faces& F, const Region& region) {
  const LaplaceOperator lap = cotan_laplacian(P, F);
  delta_ = rest_laplace_coordinates(lap, P);
  W_ = lap.W;
  try {
    ConstrainedQuadratic dirichlet;
    dirichlet.prepare(-lap.W, constrained_);
    weights_ = harmonic_weights(dirichlet, region);
    system_.prepare(polyharmonic_matrix(lap, 2), constrained_);  // W M⁻¹ W
  } catch (const SolverError& e) {
    if (e.index() < 0) throw SolverError(std::string("laplacian (explicit): ") + e.what());  // not singular: e.g. out of memory
    throw SolverError("laplacian (explicit): the system is singular near vertex " + std::to_string(e.index()) +
                          " (a free vertex whose faces all have zero area?)",
                      e.index());
  }
  target_delta_.resize(P.rows(), 3);
  gradients_.assign(region.num_handles(), HandleGradient{});
  frame_.prepare(system_, 3);
}

void LaplacianEditing::deform_local(const std::vector<Mat4>& transforms, Positions& out) {
  Eigen::MatrixXd& known = frame_.known();
  Eigen::MatrixXd& rhs = frame_.rhs();
  for (size_t c = 0; c < constrained_.size(); ++c) {
    const int k = handle_of_constrained_[c], v = constrained_[c];
    const Vec3 p = rest_.row(v);
    out.row(v) = (k < 0 ? p : transform_point(transforms[k], p)).transpose();
  }
  const std::vector<int>& unknown = system_.unknown();
  if (options_.implicit) {
    for (size_t c = 0; c < constrained_.size(); ++c)
      for (int d = 0; d < 3; ++d) known(3 * c + d, 0) = out(constrained_[c], d);
    rhs.setZero();
    frame_.solve();
    const Eigen::MatrixXd& x = frame_.solution();
    parallel_for_chunks(static_cast<long>(unknown.size()), [&](long b, long e) {
      for (long u = b; u < e; ++u) out(unknown[u] / 3, unknown[u] % 3) = x(u, 0);
    });
    check_scale(out);
    return;
  }
  // Explicit: δ'_i = M_i δ_i, right-hand side (W δ')_u on the unknown rows.
  handle_gradients(transforms, gradients_);
  parallel_for_chunks(rest_.rows(), [&](long b, long e) {
    for (long i = b; i < e; ++i)
      target_delta_.row(i) = (blended_gradient(weights_.row(i).data(), gradients_) * delta_.row(i).transpose()).transpose();
  });
  parallel_for_chunks(static_cast<long>(unknown.size()), [&](long b, long e) {
    for (long u = b; u < e; ++u) {
      Vec3 sum = Vec3::Zero();
      for (SparseMatrix::InnerIterator it(W_, unknown[u]); it; ++it) sum += it.value() * target_delta_.row(it.row()).transpose();
      rhs.row(u) = sum.transpose();
    }
  });
  for (size_t c = 0; c < constrained_.size(); ++c) known.row(c) = out.row(constrained_[c]);
  frame_.solve();
  const Eigen::MatrixXd& x = frame_.solution();
  parallel_for_chunks(static_cast<long>(unknown.size()), [&](long b, long e) {
    for (long u = b; u < e; ++u) out.row(unknown[u]) = x.row(u);
  });
  check_scale(out);
}

}  // namespace msd
