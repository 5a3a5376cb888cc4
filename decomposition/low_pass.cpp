#include "msdeform/decomposition/low_pass.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/solver.h"

namespace msd {
namespace {

constexpr const char* kWho = "low_pass_base";
constexpr double kPi = 3.14159265358979323846;
// Fidelity weight of vertices without area, relative to the mean mass: B = S there.
constexpr double kMassFloor = 1e-12;
// Automatic scale: vertices whose details may fold at rest (mesh defects: slivers, near-duplicates),
// as a fraction of all vertices, before a candidate counts as folding.
constexpr double kDefectFraction = 1e-3;
// Automatic scale: a base with less than this fraction of S's area has lost the shape (a tube smoothed
// towards its axis), whatever its details look like.
constexpr double kMinAreaRatio = 0.5;
// An rms detail height below this fraction of the diameter, or below this many units in the last place of
// S's largest coordinate, is rounding (of the solve, at 1e-13 of the coordinates, and of S itself: a plane 1
// across moved to 1e7 shows rms heights of 2.4e-10), not a layer: a plateau of the automatic scale must
// start above it, and a given scale that removes no more is no layer either.
constexpr double kNoiseHeight = 1e-10;
constexpr double kNoiseUlps = 16;
// A given detail scale above this many diameters of S is refused (see low_pass_base).
constexpr double kMaxScaleOverDiameter = 1e6;
// The iterative solve (LowPassSystem::solve_iteratively) stops when every coordinate's residual, in the
// preconditioner's norm, is below this fraction of its right-hand side's; it gives up (and the system is
// factored instead) after kMaxIterations, which the preconditioner's bound κ ≤ 2 never needs (about 17).
constexpr double kTolerance = 1e-13;
constexpr int kMaxIterations = 60;

// Y = A X for a symmetric A (n by n, both triangles stored), X n by 3: each row of Y is a column of A
// times X (A's columns are its rows), so rows run on both cores without sharing a write.
void symmetric_product(const SparseMatrix& A, const Eigen::MatrixX3d& X, Eigen::MatrixX3d& Y) {
  Y.resize(A.cols(), 3);
  parallel_for_chunks(A.cols(), [&](long begin, long end) {
    for (long j = begin; j < end; ++j) {
      double x = 0, y = 0, z = 0;
      for (SparseMatrix::InnerIterator it(A, j); it; ++it) {
        const double a = it.value();
        const long i = it.row();
        x += a * X(i, 0), y += a * X(i, 1), z += a * X(i, 2);
      }
      Y(j, 0) = x, Y(j, 1) = y, Y(j, 2) = z;
    }
  });
}

// Twice the largest distance from the centroid: a size that, unlike the bounding box, does not change
// when S is rotated.
double diameter(const Positions& S) {
  const Eigen::RowVector3d c = S.colwise().mean();
  return 2 * std::sqrt((S.rowwise() - c).rowwise().squaredNorm().maxCoeff());
}

// The rms detail height at rounding level for S of diameter `size` (kNoiseHeight, kNoiseUlps).
double noise_height(const Positions& S, double size) {
  return std::max(kNoiseHeight * size,
                  kNoiseUlps * std::numeric_limits<double>::epsilon() * S.cwiseAbs().maxCoeff());
}

// (M + ℓ⁴ W M̃⁻¹ W) B = M S on the vertices off the mesh boundary, B = S on it; prepared once per mesh,
// solve() for each ℓ. Coordinates are relative to the centroid of S.
//
// With conjugate gradients (LowPassSolver; every unknown must have area), the system A = D + ℓ⁴ W D⁻¹ W on
// the unknowns (D their masses, W the cotan Laplacian's block on them, negative semi-definite) is
// preconditioned with P = C D⁻¹ C, C = D − ℓ²W: P − A = −2ℓ²W, and on a generalised eigenvector of (−W, D)
// with eigenvalue μ ≥ 0 (x = ℓ²μ) the preconditioned operator P⁻¹A is (1 + x²) / (1 + x)², within
// [1/2, 1]: a condition number at most 2 on any mesh and at any ℓ, so 15–17 iterations reach 1e-13 (each
// two solves with C's factor and two products with W). C has the Laplacian's sparsity: on the 1M lift its
// factor holds 7.4e7 entries against A's 2.3e8. Its solves read a single-precision copy of the factor
// (SparseSPDSolver::set_single_precision_solves): P is then the exact P of a matrix within 1e-7 of C,
// still symmetric positive definite with the same bound to 1e-3, while A and the residuals stay in double,
// so the result is as accurate (3.9 → 3.3 s for the 1M lift's 15 iterations). Elsewhere (a vertex
// without area, C not positive definite, no convergence) A itself is factored, as before.
class LowPassSystem {
 public:
  LowPassSystem(const Positions& S, const Faces& F, LowPassSolver solver) {
    const LaplaceOperator lap = cotan_laplacian(S, F);
    const int nv = static_cast<int>(S.rows());
    mass_ = lap.mass;
    const double floor = kMassFloor * std::max(mass_.mean(), 1e-300);
    Eigen::VectorXd inverse(nv);
    std::vector<char> boundary(nv, 1);  // the mesh boundary and vertices no face uses keep their place
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int k = 0; k < 3; ++k) boundary[F(f, k)] = 0;
    for (int v : boundary_vertices(F, nv)) boundary[v] = 1;
    for (int v = 0; v < nv; ++v) {
      inverse[v] = (mass_[v] > 0 && !boundary[v]) ? 1 / mass_[v] : 0.0;
      mass_[v] = std::max(mass_[v], floor);
      (boundary[v] ? known_ : unknown_).push_back(v);
    }
    if (unknown_.empty()) return;  // every vertex on the boundary: B = S, no system to build
    mass_u_.resize(static_cast<Eigen::Index>(unknown_.size()));
    inverse_u_.resize(mass_u_.size());
    iterative_ = solver != LowPassSolver::Factorisation;
    for (size_t u = 0; u < unknown_.size(); ++u) {
      mass_u_[u] = mass_[unknown_[u]];
      inverse_u_[u] = inverse[unknown_[u]];
      if (iterative_ && !(inverse_u_[u] > 0)) {
        iterative_ = false;
        fallback_reason_ = "vertex " + std::to_string(unknown_[u]) + " has no area (its faces have none)";
      }
    }
    W_uu_ = submatrix(lap.W, unknown_, unknown_);
    if (!known_.empty()) W_uk_ = submatrix(lap.W, unknown_, known_);
    W_ = std::move(lap.W);
    inverse_ = std::move(inverse);
    centroid_ = S.colwise().mean();
    centred_ = S.rowwise() - centroid_.transpose();
    known_values_.resize(static_cast<Eigen::Index>(known_.size()), 3);
    for (size_t c = 0; c < known_.size(); ++c) known_values_.row(c) = centred_.row(known_[c]);
  }

  //! Every vertex lies on the mesh boundary (a single triangle, a strip): nothing to smooth, B = S.
  bool all_known() const { return unknown_.empty(); }
  //! Conjugate-gradient iterations of the last solve(); 0 where it factored the system.
  int iterations() const { return iterations_; }
  //! Why conjugate gradients were asked for (LowPassSolver) and the system was factored; empty otherwise.
  const std::string& fallback_reason() const { return fallback_reason_; }

  Positions solve(double detail_scale) {
    const double l = detail_scale / (2 * kPi), l4 = l * l * l * l;
    Eigen::MatrixX3d X;
    iterations_ = 0;  // solve_iteratively() counts them, give_up() zeroes them again
    if (iterative_ && solve_iteratively(l * l, X)) return positions(X);
    if (bending_uu_.size() == 0) {  // the factored path's matrices, once
      const SparseMatrix bending = weighted_square(W_, inverse_);
      bending_uu_ = submatrix(bending, unknown_, unknown_);
      if (!known_.empty()) bending_uk_ = submatrix(bending, unknown_, known_);
    }
    SparseMatrix Auu = l4 * bending_uu_;  // + M on the diagonal; the mass is 0 off the diagonal of (u, k)
    for (Eigen::Index u = 0; u < Auu.cols(); ++u) Auu.coeffRef(u, u) += mass_u_[u];
    try {
      if (solver_.factored())
        solver_.refactor(Auu);
      else
        solver_.factor(std::move(Auu));  // released before the numeric factorisation
    } catch (const SolverError& e) {
      if (e.index() < 0) throw SolverError(std::string(kWho) + ": " + e.what());  // not singular: e.g. out of memory
      const long v = e.index() >= 0 ? unknown_[e.index()] : -1;
      // Far beyond the mesh's size ℓ⁴ swamps the data term and the system is singular in floating point.
      const double size = diameter(centred_);
      if (detail_scale > size)
        throw SolverError(std::string(kWho) + ": the detail scale " + format_number(detail_scale) + " is " +
                              format_number(detail_scale / size) + " times the mesh's diameter " + format_number(size) +
                              ", too large for the smoothing system (singular in floating point); a detail scale "
                              "is a feature length on the mesh, below its diameter",
                          v);
      throw SolverError(std::string(kWho) + ": the smoothing system is singular" +
                            (v >= 0 ? " near vertex " + std::to_string(v) : std::string()) +
                            " (degenerate faces around it?): " + e.what(),
                        v);
    }
    Eigen::MatrixXd rhs(static_cast<Eigen::Index>(unknown_.size()), 3), Y;
    for (size_t u = 0; u < unknown_.size(); ++u) rhs.row(u) = mass_[unknown_[u]] * centred_.row(unknown_[u]);
    if (!known_.empty()) rhs -= l4 * (bending_uk_ * known_values_);
    solver_.solve(rhs, Y);
    if (!Y.allFinite())
      throw SolverError(std::string(kWho) + ": the smoothed positions are not finite at the detail scale " +
                        format_number(detail_scale) + " (degenerate faces, or a scale too large for this mesh?)");
    return positions(Y);
  }

 private:
  // B from the unknowns' rows X (centred) and the known values.
  template <class Matrix>
  Positions positions(const Matrix& X) const {
    Positions B(centred_.rows(), 3);
    for (size_t u = 0; u < unknown_.size(); ++u) B.row(unknown_[u]) = X.row(u);
    for (size_t c = 0; c < known_.size(); ++c) B.row(known_[c]) = known_values_.row(c);
    return B.rowwise() + centroid_.transpose();
  }

  // Y = A X = D X + ℓ⁴ W D⁻¹ W X on the unknowns (l2 = ℓ²).
  void apply(double l2, const Eigen::MatrixX3d& X, Eigen::MatrixX3d& Y) {
    symmetric_product(W_uu_, X, work_);
    work_.array().colwise() *= (l2 * l2) * inverse_u_.array();
    symmetric_product(W_uu_, work_, Y);
    Y += mass_u_.asDiagonal() * X;
  }

  // Z = P⁻¹ R = C⁻¹ D C⁻¹ R.
  void precondition(const Eigen::MatrixX3d& R, Eigen::MatrixX3d& Z) {
    Eigen::MatrixXd T = R;
    preconditioner_.solve(T, T);
    T.array().colwise() *= mass_u_.array() / (scale_ * scale_);
    preconditioner_.solve(T, T);
    Z = T;
  }

  // The unknowns' rows X of the base at ℓ² = l2 by preconditioned conjugate gradients (the class comment),
  // one sequence per coordinate. False where this path does not apply: C not positive definite (it is
  // wherever the cotan weights are, see cotan_laplacian), a non-finite value, or no convergence within
  // kMaxIterations; the caller then factors A.
  bool solve_iteratively(double l2, Eigen::MatrixX3d& X) {
    // C / s with s the mean mass: entries of order 1 + ℓ²μ at any size of S, within single precision's
    // range (C itself overflows it beyond coordinates of about 1e19); precondition() divides D by s².
    scale_ = mass_u_.mean();
    SparseMatrix C = (-l2 / scale_) * W_uu_;
    for (Eigen::Index u = 0; u < C.cols(); ++u) C.coeffRef(u, u) += mass_u_[u] / scale_;
    try {
      if (preconditioner_.factored())
        preconditioner_.refactor(C);
      else {
        preconditioner_.set_single_precision_solves(true);  // a preconditioner: see the class comment
        preconditioner_.factor(std::move(C));
      }
    } catch (const SolverError& e) {
      give_up(std::string("the preconditioner could not be factored (") + e.what() + ")");
      return false;
    }
    const Eigen::Index n = static_cast<Eigen::Index>(unknown_.size());
    // Right-hand side M S_u − ℓ⁴ W D⁻¹ W_uk S_k (the known values enter through the Laplacian of the unknowns
    // next to them; D⁻¹ is zero on the known rows of W M̃⁻¹ W, so only W_uu carries it on).
    Eigen::MatrixX3d R(n, 3), Z, P, Q;
    for (Eigen::Index u = 0; u < n; ++u) R.row(u) = mass_u_[u] * centred_.row(unknown_[u]);
    if (!known_.empty()) {
      Eigen::MatrixX3d coupling = W_uk_ * known_values_;
      coupling.array().colwise() *= (l2 * l2) * inverse_u_.array();
      symmetric_product(W_uu_, coupling, Q);
      R -= Q;
    }
    X.setZero(n, 3);
    precondition(R, Z);
    P = Z;
    Eigen::Array3d rz = (R.array() * Z.array()).colwise().sum().transpose();
    const Eigen::Array3d target = rz * (kTolerance * kTolerance);
    for (int it = 0; it < kMaxIterations; ++it) {
      iterations_ = it;
      if ((rz <= target).all()) return X.allFinite();
      apply(l2, P, Q);
      const Eigen::Array3d pq = (P.array() * Q.array()).colwise().sum().transpose();
      Eigen::Array3d alpha = Eigen::Array3d::Zero();
      for (int c = 0; c < 3; ++c)
        if (rz[c] > target[c] && pq[c] > 0) alpha[c] = rz[c] / pq[c];
      X += P * alpha.matrix().asDiagonal();
      R -= Q * alpha.matrix().asDiagonal();
      precondition(R, Z);
      const Eigen::Array3d next = (R.array() * Z.array()).colwise().sum().transpose();
      if (!next.allFinite()) {
        give_up("a non-finite residual after " + std::to_string(it + 1) + " iterations");
        return false;
      }
      const Eigen::Array3d beta = (rz > 0).select(next / rz, 0.0);
      P = Z + P * beta.matrix().asDiagonal();
      rz = next;
    }
    char why[160];
    std::snprintf(why, sizeof why, "no convergence in %d iterations (residual %.3g of the right-hand side's)",
                  kMaxIterations, std::sqrt((rz / target.max(1e-300)).maxCoeff()) * kTolerance);
    give_up(why);
    return false;
  }

  // Conjugate gradients do not apply: A is factored from now on, and the preconditioner's memory released.
  void give_up(const std::string& why) {
    iterative_ = false;
    iterations_ = 0;
    fallback_reason_ = why;
    preconditioner_ = SparseSPDSolver();
    release_freed_memory();
  }

  Eigen::VectorXd mass_;
  SparseMatrix W_, W_uu_, W_uk_;  // the cotan Laplacian, its blocks (unknown, unknown), (unknown, known)
  Eigen::VectorXd inverse_, inverse_u_;  // M̃⁻¹ (0 on the boundary and without area), on the unknowns
  SparseMatrix bending_uu_, bending_uk_;  // W M̃⁻¹ W on (unknown, unknown), (unknown, known): factored path
  bool iterative_ = false;                // conjugate gradients (LowPassSolver), while they apply
  int iterations_ = 0;
  std::string fallback_reason_;
  double scale_ = 1;                // the mean mass s: the preconditioner factors C / s
  SparseSPDSolver preconditioner_;  // C / s, C = D − ℓ²W
  Eigen::MatrixX3d work_;
  Eigen::VectorXd mass_u_;                // M on the unknowns
  Vec3 centroid_;
  Positions centred_;
  std::vector<int> known_, unknown_;  // mesh-boundary vertices (B = S) and the others
  Eigen::MatrixXd known_values_;
  SparseSPDSolver solver_;
};

}  // namespace

void LowPassOptions::validate(const std::string& who) const {
  if (!(detail_scale >= 0) || !std::isfinite(detail_scale))
    throw InvalidInput(who + ": the detail scale must be finite and >= 0 (0 = automatic), got " +
                       format_number(detail_scale));
  if (!(max_fold_ratio > 0 && max_fold_ratio <= 1))
    throw InvalidInput(who + ": max_fold_ratio must be in (0, 1]");
  if (!(plateau_growth > 1) || !std::isfinite(plateau_growth))
    throw InvalidInput(who + ": plateau_growth must be finite and > 1");
  if (!(max_scale_fraction > 0) || !std::isfinite(max_scale_fraction))
    throw InvalidInput(who + ": max_scale_fraction must be positive and finite");
}

Positions low_pass_base(const Positions& S, const Faces& F, const LowPassOptions& options, LowPassReport* report,
                        const std::function<void(const std::string&)>& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  check_mesh_arrays(S, F, kWho);
  if (F.rows() == 0) throw InvalidInput(std::string(kWho) + ": the mesh has no faces");
  check_extent(S, kWho);
  options.validate(kWho);

  // Far beyond the diameter the filter keeps only S's affine part, and (L/2π)⁴ overflows the system's
  // entries long before L reaches the largest double.
  const double size = diameter(S);
  if (options.detail_scale > kMaxScaleOverDiameter * size)
    throw InvalidInput(std::string(kWho) + ": the detail scale " + format_number(options.detail_scale) +
                       " is more than " + format_number(kMaxScaleOverDiameter) + " times the mesh's diameter " +
                       format_number(size) + " (mesh units); a detail scale is a feature length on the mesh");
  LowPassReport r;
  r.mean_edge_length = mean_edge_length(S, F);
  auto owned = std::make_unique<LowPassSystem>(S, F, options.solver);
  LowPassSystem& system = *owned;
  Positions B;
  if (system.all_known()) {  // no detail layer: the base is S
    r.all_boundary = true;
    r.no_layer_reason = "every vertex lies on the mesh boundary, which the low-pass keeps in place";
    r.automatic = options.detail_scale == 0;
    B = S;
    r.check = check_details(S, B, F);
  } else if (options.detail_scale > 0) {
    r.detail_scale = options.detail_scale;
    B = system.solve(r.detail_scale);
    r.iterations = system.iterations();
    r.check = check_details(S, B, F);
    if (r.check.rms_height <=
        noise_height(S, size)) {  // far below the edge length: the solve's rounding alone
      r.no_layer_reason = "the detail scale " + format_number(r.detail_scale) +
                          " removes nothing measurable (rms detail height " +
                          format_number(r.check.rms_height) + ", rounding; the mean edge length is " +
                          format_number(r.mean_edge_length) + ")";
      B = S;
      r.check = check_details(S, B, F);
    }
  } else {
    r.automatic = true;
    const double smallest = 4 * r.mean_edge_length, largest = options.max_scale_fraction * size;
    const double noise = noise_height(S, size);
    const double area = face_areas(S, F).sum();
    const long allowed_folds = static_cast<long>(kDefectFraction * static_cast<double>(S.rows()));
    double previous_rms = 0;
    int most = 0;  // candidates up to the largest scale (none when every edge has zero length)
    while (smallest > 0 && smallest * std::pow(std::sqrt(2.0), most) <= largest) ++most;
    for (int k = 0; k < most; ++k) {
      const auto started = std::chrono::steady_clock::now();
      const double L = smallest * std::pow(std::sqrt(2.0), k);
      Positions trial = system.solve(L);
      r.iterations = system.iterations();
      const DetailCheck check = check_details(S, trial, F);
      const double area_ratio = face_areas(trial, F).sum() / area;
      r.candidates.push_back({L, check, area_ratio});
      if (progress) {
        char growth[96] = "";
        if (k > 0)
          std::snprintf(growth, sizeof growth, ", x%.3g of the last (a plateau needs less than x%.3g)",
                        check.rms_height / previous_rms, options.plateau_growth);
        char line[256];
        std::snprintf(line, sizeof line, "detail scale candidate %d of at most %d: %.4g, rms detail height %.4g%s, %.1f s",
                      k + 1, most, L, check.rms_height, growth,
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
        progress(line);
      }
      if (check.fold_ratio_p999 > options.max_fold_ratio || check.folding_vertices > allowed_folds ||
          area_ratio < kMinAreaRatio) {  // from here on the base loses the shape, not just the details
        char why[240];
        if (check.folding_vertices > allowed_folds)
          std::snprintf(why, sizeof why, "the details of %d vertices fold over it", check.folding_vertices);
        else if (area_ratio < kMinAreaRatio)
          std::snprintf(why, sizeof why, "its area is %.3g of the mesh's", area_ratio);
        else
          std::snprintf(why, sizeof why,
                        "its details come close to folding: fold ratio %.3g at the 99.9th "
                        "percentile, above %.3g",
                        check.fold_ratio_p999, options.max_fold_ratio);
        r.no_layer_reason = "the candidate scale " + format_number(L) + " already removes shape (" + why +
                            ") before the detail heights stopped growing";
        break;
      }
      if (k > 0 && previous_rms > noise && check.rms_height < options.plateau_growth * previous_rms) {
        r.detail_scale = L;
        r.check = check;
        B.swap(trial);
        break;
      }
      previous_rms = check.rms_height;
    }
    if (r.detail_scale == 0) {  // no separate detail layer: the base is S itself
      if (r.candidates.size() < 2 && r.no_layer_reason.empty())  // no growth to judge
        r.no_layer_reason =
            r.candidates.empty()
                ? "no candidate scale fits the mesh (the smallest, 4 mean edge lengths = " +
                      format_number(smallest) + ", is beyond " + format_number(options.max_scale_fraction) +
                      " of its diameter " + format_number(size) + ")"
                : "only one candidate scale fits the mesh (" + format_number(smallest) + ", up to " +
                      format_number(options.max_scale_fraction) + " of its diameter): a plateau needs two";
      if (r.no_layer_reason.empty() && !r.candidates.empty() && r.candidates.back().check.rms_height <= noise)
        r.no_layer_reason = "the low-pass removes nothing measurable at any scale tried (up to " +
                            format_number(options.max_scale_fraction) +
                            " of the diameter; rms detail height " +
                            format_number(r.candidates.back().check.rms_height) + ", rounding)";
      if (r.no_layer_reason.empty())
        r.no_layer_reason = "the detail heights grow with every scale tried (up to " +
                            format_number(options.max_scale_fraction) + " of the diameter)";
      B = S;
      r.check = check_details(S, B, F);
    }
  }
  r.solver_fallback = system.fallback_reason();
  owned.reset();
  release_freed_memory();  // the factor's holes below B: the shell factors next (core/memory.h)
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (report) *report = std::move(r);
  return B;
}

Positions LowPassCache::base(const Positions& S, const Faces& F, const LowPassOptions& options,
                             LowPassReport* report, const std::function<void(const std::string&)>& progress) {
  const std::lock_guard<std::mutex> lock(mutex_);
  static_assert(sizeof(LowPassOptions) == 5 * sizeof(double), "a new option must be compared here too");
  const auto same = [](const LowPassOptions& a, const LowPassOptions& b) {
    return a.detail_scale == b.detail_scale && a.max_fold_ratio == b.max_fold_ratio &&
           a.plateau_growth == b.plateau_growth && a.max_scale_fraction == b.max_scale_fraction &&
           a.solver == b.solver;
  };
  const bool hit =
      valid_ && same(options, options_) && S.rows() == S_.rows() && F.rows() == F_.rows() && S == S_ && F == F_;
  if (!hit) {
    LowPassReport r;
    Positions B = low_pass_base(S, F, options, &r, progress);  // throws before anything is replaced
    valid_ = false;
    S_ = S, F_ = F, B_ = std::move(B), options_ = options, report_ = std::move(r);
    valid_ = true;
  }
  if (report) {
    *report = report_;
    report->reused = hit;
  }
  return B_;
}

}  // namespace msd
