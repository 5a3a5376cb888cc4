#include "msdeform/deformation/space_deformer.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/solver.h"

namespace msd {
namespace {
constexpr int kDenseLimit = 4000;
// A frame warns when some point moves this many times farther than the farthest-moving constraint target.
constexpr double kOvershoot = 2.0;
// A frame warns when a constrained vertex ends farther than this fraction of the diagonal from its target.
constexpr double kMissed = 0.05;
}  // namespace

// The least-norm solve of (9.13): N (#C×m) and the factor of NᵀN + εI; the affine fit's
// E = (XᵀX + Λ)⁻¹Xᵀ (4×#C) on centred, scaled coordinates X = [(p − centre)/scale, 1].
struct SpaceDeformer::LeastNorm {
  Eigen::SparseMatrix<double, Eigen::RowMajor> N;
  Eigen::LLT<Eigen::MatrixXd> dense;  // up to kDenseLimit basis functions
  SparseSPDSolver sparse;             // beyond
  bool affine_part = true;
  Eigen::MatrixXd E;
  Vec3 centre = Vec3::Zero();
  double scale = 1;
  Positions controls;  // rest positions of the control points (for the affine part)
};

DeformerTraits SpaceDeformer::traits() const {
  DeformerTraits t;
  t.domain = DeformerDomain::Space;
  t.solve = DeformerSolve::Linear;
  t.vertex_targets = true;
  t.exact_constraints = exact_constraints();
  t.cotan_laplacian = false;
  return t;
}

Positions SpaceDeformer::control_points() const {
  throw UsageError(name() + " has no control points: its coefficients are not displacements of points");
}

void LeastNormOptions::validate(const std::string& who) const {
  if (!(regularization > 0) || !std::isfinite(regularization))
    throw InvalidInput(who + ": the least-norm regularization must be positive and finite (got " +
                       format_number(regularization) + ")");
}

void SpaceDeformer::prepare_solve(const Positions& P, const std::vector<int>& constrained) {
  const LeastNormOptions options = least_norm_options();
  options.validate(name());
  auto ln = std::make_shared<LeastNorm>();
  const int m = basis_size();
  const int nc = static_cast<int>(constrained.size());
  // N: the basis at the constrained vertices.
  std::vector<BasisRow> rows(nc);
  parallel_for_chunks(nc, [&](long c0, long c1) {
    for (long c = c0; c < c1; ++c) prepared_basis(P, constrained[c], rows[c]);
  }, 256);
  // Filled as compressed rows directly (indices sorted within each row).
  ln->N.resize(nc, m);
  long nonzeros = 0;
  for (const BasisRow& row : rows) nonzeros += static_cast<long>(row.index.size());
  ln->N.resizeNonZeros(nonzeros);
  int* outer = ln->N.outerIndexPtr();
  outer[0] = 0;
  for (int c = 0; c < nc; ++c) {
    BasisRow& row = rows[c];
    if (!std::is_sorted(row.index.begin(), row.index.end())) {
      std::vector<int> order(row.index.size());
      std::iota(order.begin(), order.end(), 0);
      std::sort(order.begin(), order.end(), [&](int a, int b) { return row.index[a] < row.index[b]; });
      BasisRow sorted;
      for (int j : order) sorted.add(row.index[j], row.value[j]);
      row = std::move(sorted);
    }
    std::copy(row.index.begin(), row.index.end(), ln->N.innerIndexPtr() + outer[c]);
    std::copy(row.value.begin(), row.value.end(), ln->N.valuePtr() + outer[c]);
    outer[c + 1] = outer[c] + static_cast<int>(row.index.size());
  }
  std::vector<BasisRow>().swap(rows);
  // NᵀN + ε·mean(diag)·I: accumulated densely for up to kDenseLimit basis functions (a lattice of 8
  // cells or a cage), by a sparse product beyond.
  if (m <= kDenseLimit) {
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(m, m);
    if (4 * ln->N.nonZeros() > static_cast<Eigen::Index>(nc) * m) {
      // Dense rows (a cage's coordinates): rank updates by blocks of rows (blocked, vectorised SYRK).
      Eigen::MatrixXd block;
      for (int c0 = 0; c0 < nc; c0 += 2048) {
        block = ln->N.middleRows(c0, std::min(2048, nc - c0));
        normal.selfadjointView<Eigen::Lower>().rankUpdate(block.transpose());
      }
    } else {
      for (int c = 0; c < nc; ++c)
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator a(ln->N, c); a; ++a)
          for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator b(ln->N, c); b; ++b)
            if (b.col() <= a.col()) normal(a.col(), b.col()) += a.value() * b.value();
    }
    double mean = normal.diagonal().sum() / m;
    normal.diagonal().array() += options.regularization * (mean > 0 ? mean : 1.0);
    ln->dense.compute(normal.selfadjointView<Eigen::Lower>());
    if (ln->dense.info() != Eigen::Success) throw SolverError(name() + ": the least-norm normal equations are singular");
  } else {
    SparseMatrix normal = SparseMatrix(ln->N.transpose()) * ln->N;
    double mean = normal.diagonal().sum() / m;
    SparseMatrix shift(m, m);
    shift.setIdentity();
    normal += (options.regularization * (mean > 0 ? mean : 1.0)) * shift;
    ln->sparse.factor(normal);
  }
  // The affine fit, on coordinates centred at the constraints' mean and scaled by their RMS radius.
  ln->affine_part = options.affine_part;
  if (ln->affine_part) {
    for (int c = 0; c < nc; ++c) ln->centre += P.row(constrained[c]).transpose();
    ln->centre /= nc;
    double rms = 0;
    for (int c = 0; c < nc; ++c) rms += (P.row(constrained[c]).transpose() - ln->centre).squaredNorm();
    ln->scale = std::sqrt(rms / nc);
    if (!(ln->scale > 0)) ln->scale = 1;
    Eigen::MatrixXd X(nc, 4);
    for (int c = 0; c < nc; ++c) X.row(c) << (P.row(constrained[c]) - ln->centre.transpose()) / ln->scale, 1.0;
    Eigen::Matrix4d XtX = X.transpose() * X;
    // Λ: directions of the linear part the constraints do not span (coplanar or collinear constraints)
    // keep a zero gradient instead of an arbitrary one.
    XtX.diagonal().head<3>().array() += 1e-10 * nc;
    ln->E = XtX.ldlt().solve(X.transpose());
    ln->controls = control_points();
  }
  least_norm_ = std::move(ln);
}

void SpaceDeformer::solve(const Eigen::MatrixXd& values, Eigen::MatrixXd& coefficients) const {
  const LeastNorm& ln = *least_norm_;
  Eigen::MatrixXd residual = values;
  coefficients.setZero(ln.N.cols(), values.cols());
  if (ln.affine_part) {
    const Eigen::MatrixXd theta = ln.E * values;  // 4 × k: [x̃ 1] θ is the best affine fit
    Eigen::MatrixXd Xc(ln.controls.rows(), 4);
    Xc.leftCols<3>() = (ln.controls.rowwise() - ln.centre.transpose()) / ln.scale;
    Xc.col(3).setOnes();
    coefficients = Xc * theta;
    residual -= ln.N * coefficients;
  }
  const Eigen::MatrixXd rhs = ln.N.transpose() * residual;
  coefficients += ln.sparse.factored() ? ln.sparse.solve(rhs) : Eigen::MatrixXd(ln.dense.solve(rhs));
}

void SpaceDeformer::do_prepare(const Positions& P, const Faces&, const Region& region) {
  rest_ = P;
  rest_diagonal_ = bounding_box_diagonal(P);
  constrained_ = region.constrained_vertices();
  handle_of_.clear();
  for (int v : constrained_) handle_of_.push_back(region.handle_of(v));
  num_handles_ = region.num_handles();
  least_norm_.reset();
  fit_basis(P, region);
  const int m = basis_size();

  // The basis at every point, cached for methods with control points when it fits (every method here
  // gives each point the same number of basis values; a point with another count switches the cache
  // off): the solve and the affine basis below then read it instead of evaluating it again, and so do
  // deform_controls() and deform_to().
  const long n = P.rows();
  BasisRow probe;
  basis(P.row(0).transpose(), probe);
  const size_t width = probe.index.size();
  // Dense rows (ψ_0 .. ψ_{m−1} in order: a cage, RBF) are cached without their indices.
  cache_dense_ = static_cast<int>(width) == m;
  for (size_t j = 0; j < width && cache_dense_; ++j) cache_dense_ = probe.index[j] == static_cast<int>(j);
  cache_width_ = 0;
  cache_index_.resize(0);
  cache_value_.resize(0);
  if (has_control_points() &&
      static_cast<size_t>(n) * width * (sizeof(double) + (cache_dense_ ? 0 : sizeof(int))) <= basis_cache_bytes_) {
    if (!cache_dense_) cache_index_.resize(n * width);  // uninitialised: filled in parallel below
    cache_value_.resize(n * width);
    std::atomic<bool> uneven{false};
    parallel_for_chunks(n, [&](long i0, long i1) {
      BasisRow row;
      for (long i = i0; i < i1; ++i) {
        basis(P.row(i).transpose(), row);
        if (row.index.size() != width || (cache_dense_ && row.index.back() != m - 1)) {
          uneven = true;
          continue;
        }
        if (!cache_dense_) std::copy(row.index.begin(), row.index.end(), cache_index_.data() + i * width);
        std::copy(row.value.begin(), row.value.end(), cache_value_.data() + i * width);
      }
    }, 1024);
    cache_width_ = uneven ? 0 : width;
    if (uneven) {
      cache_index_.resize(0);
      cache_value_.resize(0);
    }
  }
  prepare_solve(P, constrained_);

  // Handle k's affine basis: the solve of the data (x, y, z, 1) on its vertices, zero elsewhere, with
  // x, y, z relative to the bounding box's centre (a model far from the origin keeps its precision).
  origin_ = bounding_box_centre(P);
  const int nc = static_cast<int>(constrained_.size());
  const int cols = 4 * num_handles_;
  Eigen::MatrixXd data = Eigen::MatrixXd::Zero(nc, cols);
  for (int c = 0; c < nc; ++c)
    if (handle_of_[c] >= 0) data.row(c).segment<4>(4 * handle_of_[c]) << P.row(constrained_[c]) - origin_.transpose(), 1.0;
  solve(data, handle_coefficients_);
  const Eigen::MatrixXd& G = handle_coefficients_;

  // b = Ψ(P) G at every point.
  point_basis_.setZero(n, cols);
  parallel_for_chunks(n, [&](long i0, long i1) {
    BasisRow row;
    Eigen::RowVectorXd b(cols);
    for (long i = i0; i < i1; ++i) {
      prepared_basis(P, i, row);
      b.setZero();
      for (size_t j = 0; j < row.index.size(); ++j) b += row.value[j] * G.row(row.index[j]);
      point_basis_.row(i) = b;
    }
  }, 1024);
  coefficients_.setZero(m, 3);
  frame_matrices_.assign(static_cast<size_t>(12) * num_handles_, 0.0);
}

void SpaceDeformer::prepared_basis(const Positions& P, long v, BasisRow& row) const {
  if (cache_width_ == 0) return basis(P.row(v).transpose(), row);
  if (cache_dense_) {
    row.index.resize(cache_width_);
    for (size_t j = 0; j < cache_width_; ++j) row.index[j] = static_cast<int>(j);
  } else {
    row.index.assign(cache_index_.data() + v * cache_width_, cache_index_.data() + (v + 1) * cache_width_);
  }
  row.value.assign(cache_value_.data() + v * cache_width_, cache_value_.data() + (v + 1) * cache_width_);
}

void SpaceDeformer::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  const int K = num_handles_;
  // Handle k: T_k p − p = (A − I)(p − o) + (A − I) o + t for the centre o, as a row-major 3×4.
  double* M = frame_matrices_.data();
  for (int k = 0; k < K; ++k) {
    const Mat3 linear = transforms[k].topLeftCorner<3, 3>() - Mat3::Identity();
    const Vec3 shift = linear * origin_ + transforms[k].topRightCorner<3, 1>();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) M[12 * k + 4 * r + c] = linear(r, c);
      M[12 * k + 4 * r + 3] = shift[r];
    }
  }
  // By blocks of points that stay in cache, one coordinate at a time over contiguous columns (rest,
  // out and b are column-major), so the products vectorise across points.
  const long n = rest_.rows();
  const double* B = point_basis_.data();
  const double* rest = rest_.data();
  double* o = out.data();
  std::atomic<double> largest{0.0};  // largest squared displacement of any point
  parallel_for_chunks(n, [&](long i0, long i1) {
    double local = 0;
    for (long s0 = i0; s0 < i1; s0 += 1024) {
      const long s1 = std::min(i1, s0 + 1024);
      for (int r = 0; r < 3; ++r) {
        const double* p = rest + r * n;
        double* x = o + r * n;
        for (long i = s0; i < s1; ++i) x[i] = p[i];
        for (int k = 0; k < K; ++k) {
          const double* Mk = M + 12 * k + 4 * r;
          const double *b0 = B + (4 * k) * n, *b1 = b0 + n, *b2 = b1 + n, *b3 = b2 + n;
          for (long i = s0; i < s1; ++i) x[i] += Mk[0] * b0[i] + Mk[1] * b1[i] + Mk[2] * b2[i] + Mk[3] * b3[i];
        }
      }
      for (long i = s0; i < s1; ++i) {
        const double dx = o[i] - rest[i], dy = o[n + i] - rest[n + i], dz = o[2 * n + i] - rest[2 * n + i];
        local = std::max(local, dx * dx + dy * dy + dz * dz);
      }
    }
    for (double seen = largest.load(); local > seen && !largest.compare_exchange_weak(seen, local);) {
    }
  }, 16384);
  // The map's coefficients: δc = Σ_k G_k (T_k − I)ᵀ (for evaluate()).
  for (Eigen::Index l = 0; l < coefficients_.rows(); ++l)
    for (int r = 0; r < 3; ++r) {
      double s = 0;
      for (int k = 0; k < K; ++k)
        for (int c = 0; c < 4; ++c) s += handle_coefficients_(l, 4 * k + c) * M[12 * k + 4 * r + c];
      coefficients_(l, r) = s;
    }
  measure_constraints(out, nullptr, &transforms);
  check_overshoot(std::sqrt(largest.load()));
}

void SpaceDeformer::do_deform_to(const Positions& targets, Positions& out) {
  Eigen::MatrixXd displacements(targets.rows(), 3);
  for (size_t c = 0; c < constrained_.size(); ++c)
    displacements.row(c) = targets.row(c) - rest_.row(constrained_[c]);
  Eigen::MatrixXd coefficients;
  solve(displacements, coefficients);
  coefficients_ = coefficients;
  apply_coefficients(out);
  measure_constraints(out, &targets, nullptr);
  check_overshoot((out - rest_).rowwise().norm().maxCoeff());
}

void SpaceDeformer::deform_controls(const Eigen::MatrixX3d& displacements, Positions& out) {
  if (!has_control_points())
    throw UsageError(name() + " has no control points to edit; use deform() or deform_to()");
  if (!prepared()) throw UsageError(name() + ": deform_controls() called before prepare()");
  if (displacements.rows() != coefficients_.rows())
    throw UsageError(name() + ": " + std::to_string(displacements.rows()) + " control displacements given for " +
                     std::to_string(coefficients_.rows()) + " control points");
  check_finite(displacements, name().c_str(), "the control displacements");
  begin_frame(out);
  coefficients_ = displacements;
  apply_coefficients(out);
  end_frame(out);
}

void SpaceDeformer::do_reset() { coefficients_.setZero(); }

void SpaceDeformer::apply_coefficients(Positions& out) const {
  const long n = rest_.rows();
  if (cache_width_ > 0) {
    const size_t w = cache_width_;
    parallel_for_chunks(n, [&](long i0, long i1) {
      for (long i = i0; i < i1; ++i) {
        Eigen::RowVector3d d = Eigen::RowVector3d::Zero();
        if (cache_dense_)
          for (size_t j = 0; j < w; ++j) d += cache_value_[i * w + j] * coefficients_.row(j);
        else
          for (size_t j = i * w; j < (i + 1) * w; ++j) d += cache_value_[j] * coefficients_.row(cache_index_[j]);
        out.row(i) = rest_.row(i) + d;
      }
    });
    return;
  }
  do_evaluate(rest_, out);
}

void SpaceDeformer::do_evaluate(const Positions& points, Positions& out) const {
  parallel_for_chunks(points.rows(), [&](long i0, long i1) {
    BasisRow row;
    for (long i = i0; i < i1; ++i) {
      basis(points.row(i).transpose(), row);
      Eigen::RowVector3d d = Eigen::RowVector3d::Zero();
      for (size_t j = 0; j < row.index.size(); ++j) d += row.value[j] * coefficients_.row(row.index[j]);
      out.row(i) = points.row(i) + d;
    }
  }, 1024);
}

void SpaceDeformer::check_overshoot(double largest_move) {
  if (!(largest_move > kOvershoot * largest_target_move_) || !(largest_move > 1e-12 * rest_diagonal_)) return;
  char figures[160];
  std::snprintf(figures, sizeof(figures), "%.3g times farther than any constrained vertex's target (%.3g vs %.3g of the "
                "bounding-box diagonal)", largest_move / largest_target_move_, largest_move / rest_diagonal_,
                largest_target_move_ / rest_diagonal_);
  frame_report_.warnings.push_back(name() + ": points move up to " + figures + "; " + overshoot_advice());
}

std::string SpaceDeformer::missed_advice() const {
  return "the method meets its constraints only in the least-squares sense, and these it cannot separate";
}

std::string SpaceDeformer::overshoot_advice() const {
  return "constraints close together with different motions are amplified; move them apart or use another method";
}

void SpaceDeformer::measure_constraints(const Positions& out, const Positions* targets,
                                        const std::vector<Mat4>* transforms) {
  double error = 0, move = 0;
  for (size_t c = 0; c < constrained_.size(); ++c) {
    const Vec3 p = rest_.row(constrained_[c]);
    const Vec3 target = targets ? Vec3(targets->row(c)) : handle_of_[c] < 0 ? p : transform_point((*transforms)[handle_of_[c]], p);
    error = std::max(error, (Vec3(out.row(constrained_[c])) - target).norm());
    move = std::max(move, (target - p).norm());
  }
  frame_report_.constraint_error = error;
  largest_target_move_ = move;
  if (error > kMissed * rest_diagonal_) {
    char figures[96];
    std::snprintf(figures, sizeof(figures), "%.3g of the bounding-box diagonal", error / rest_diagonal_);
    frame_report_.warnings.push_back(name() + ": a constrained vertex ends " + figures + " from its target; " +
                                     missed_advice());
  }
}

}  // namespace msd
