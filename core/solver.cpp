#include "msdeform/core/solver.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <optional>
#include <utility>

#include "msdeform/core/blas_kernels.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/memory.h"

#ifdef MSD_HAVE_CHOLMOD
#include <cholmod.h>
#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <mutex>

#include "msdeform/core/supernodal_factorisation.h"
#include "msdeform/core/supernodal_substitution.h"
#else
#include <Eigen/SparseCholesky>
#endif

namespace msd {
namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
void identity_ordering(std::vector<int>& ordering, int n) {
  ordering.resize(n);
  std::iota(ordering.begin(), ordering.end(), 0);
}
// solve_ordered() where the rows are not permuted: Y (n rows of 4) through a column-major solve.
template <class Impl>
void solve_rows(const Impl& impl, double* Y, int k, int n) {
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>> rows(Y, n, 4);
  Eigen::MatrixXd X, B = rows.leftCols(k);
  impl.solve(B, X);
  rows.leftCols(k) = X;
}
}  // namespace

#ifdef MSD_HAVE_CHOLMOD

namespace {
// CHOLMOD's blocks of 128 MB and more (the factor's values: 1 GB for the 1M lift's bi-Laplacian) on
// transparent huge pages where the kernel gives them on request (Debian's default THP mode is madvise).
// The numeric factorisation first zeroes its factor, and on 4 KB pages a sixth of its time went to page
// faults (1M bi-Laplacian 8.3 → 7.1 s). Smaller blocks take plain malloc: CHOLMOD touches its workspaces
// only in part, and huge pages for those raised the peak memory by 13 %.
void* factor_malloc(size_t size) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr size_t kHugePage = size_t{2} << 20;
  if (size >= 64 * kHugePage && size <= SIZE_MAX - kHugePage) {  // larger: malloc refuses it
    void* p = std::aligned_alloc(kHugePage, (size + kHugePage - 1) / kHugePage * kHugePage);
    if (p) madvise(p, size, MADV_HUGEPAGE);  // a hint: the block is usable whatever it answers
    return p;
  }
#endif
  return std::malloc(size);
}
// Installs factor_malloc, once per process, unless the program gave SuiteSparse its own allocator.
void use_factor_malloc() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (SuiteSparse_config.malloc_func == &std::malloc) SuiteSparse_config.malloc_func = &factor_malloc;
  });
}
}  // namespace

// CHOLMOD with 64-bit indices (a 1M-vertex bi-Laplacian factor approaches 2^31 entries).
struct SparseSPDSolver::Impl {
  cholmod_common common;
  cholmod_factor* L = nullptr;
  mutable cholmod_dense *X = nullptr, *Y = nullptr, *E = nullptr;  // solve workspace, reused
  SupernodalSubstitution substitution;  // solves up to 4 right-hand sides, on both cores
  std::vector<int> ordering;            // solve_ordered()'s row order
  int n = 0;
  double analyse_seconds = 0, numeric_seconds = 0;

  static constexpr int kTightRelaxation = 50000;  // unknowns (factor() below)
  Impl() {
    use_factor_malloc();
    cholmod_l_start(&common);
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.print = 0;
    common.error_handler = nullptr;
    // One ordering, AMD. Measured on the 1M-vertex lift bi-Laplacian (630k unknowns, 2 cores): METIS
    // gives 25% less fill (9.7e7 vs 1.3e8) but its ordering takes 6.3 s, for 12.5 s in all; AMD needs
    // 2.0 s + 8.7 s numeric = 10.7 s. CHOLMOD's default tries both and pays for both orderings.
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_AMD;
    common.postorder = true;
  }
  ~Impl() {
    release();
    cholmod_l_finish(&common);
  }
  void release() {
    substitution.clear();
    ordering.clear();
    if (L) cholmod_l_free_factor(&L, &common);
    for (cholmod_dense** d : {&X, &Y, &E})
      if (*d) cholmod_l_free_dense(d, &common);
  }
  // Lower triangle of A as a CHOLMOD matrix (compressed columns, 64-bit indices); caller frees it.
  cholmod_sparse* to_cholmod(const SparseMatrix& A) {
    long nnz = 0;
    for (int j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it) nnz += it.row() >= j;
    const long n = A.rows();
    cholmod_sparse* S = cholmod_l_allocate_sparse(n, n, nnz, true, true, -1, CHOLMOD_REAL, &common);
    if (!S) throw SolverError("SparseSPDSolver: out of memory storing a " + std::to_string(n) + "x" + std::to_string(n) + " matrix");
    auto* colp = static_cast<SuiteSparse_long*>(S->p);
    auto* rowi = static_cast<SuiteSparse_long*>(S->i);
    auto* val = static_cast<double*>(S->x);
    long k = 0;
    for (int j = 0; j < A.outerSize(); ++j) {
      colp[j] = k;
      for (SparseMatrix::InnerIterator it(A, j); it; ++it)
        if (it.row() >= j) rowi[k] = it.row(), val[k++] = it.value();
    }
    colp[n] = k;
    return S;
  }
  // `owned` (A itself, or null) is released once A is in CHOLMOD's format.
  void factor(const SparseMatrix& A, SparseMatrix* owned = nullptr) {
    release();
    n = static_cast<int>(A.rows());
    cholmod_sparse* S = to_cholmod(A);
    if (owned) SparseMatrix().swap(*owned);
    // Before the peak of memory (the analysis and the factor), where the factor's blocks cannot reuse the
    // assembly's freed temporaries in place: their pages back to the system when they are many.
    release_freed_memory_if_large();
    // Relaxed amalgamation merges a supernode with its child when few entries of the merged block are
    // zero; the zeros are stored and read by every solve. CHOLMOD's defaults (nrelax 4 / 16 / 48 columns,
    // zrelax 0.8 / 0.1 / 0.05) suit small systems (10k lift bi-Laplacian: 14 ms vs 20 ms tighter); from
    // kTightRelaxation unknowns on, tighter limits store fewer zeros for the same factorisation time (1M
    // lift, transfer's 3-column substitution: 3.47e7 entries instead of 3.82e7, 37–40 ms instead of 44–47).
    const bool tight = n >= kTightRelaxation;
    const size_t nrelax[3] = {4, tight ? 8u : 16u, tight ? 16u : 48u};
    const double zrelax[3] = {0.8, tight ? 0.05 : 0.1, tight ? 0.02 : 0.05};
    std::copy(nrelax, nrelax + 3, common.nrelax);
    std::copy(zrelax, zrelax + 3, common.zrelax);
    auto t0 = std::chrono::steady_clock::now();
    L = cholmod_l_analyze(S, &common);
    analyse_seconds = seconds_since(t0);
    if (!L || common.status < CHOLMOD_OK) {
      cholmod_l_free_sparse(&S, &common);
      throw SolverError(common.status == CHOLMOD_OUT_OF_MEMORY
                            ? "SparseSPDSolver: out of memory during the symbolic analysis"
                            : "SparseSPDSolver: symbolic analysis failed (CHOLMOD status " + std::to_string(common.status) + ")");
    }
    numeric(S);
  }
  void refactor(const SparseMatrix& A) { numeric(to_cholmod(A)); }
  // Numeric factorisation into L (whose symbolic analysis is done); frees S.
  void numeric(cholmod_sparse* S) {
    const auto t0 = std::chrono::steady_clock::now();
    common.status = CHOLMOD_OK;
    // On two threads where the factor is supernodal (supernodal_factorisation.h), by CHOLMOD otherwise.
    SupernodalFactorisationResult result;
    if (L->is_super && (L->xtype == CHOLMOD_REAL || cholmod_l_change_factor(CHOLMOD_REAL, true, true, true, true, L, &common)))
      result = factorize_supernodal(S, L);
    // CHOLMOD's own supernodal factorisation calls BLAS too, which must find room for its work buffer.
    if (result.status == SupernodalFactorisationResult::kUnsupported && L->is_super && common.status >= CHOLMOD_OK)
      result.room = blas_room();
    if (result.status == SupernodalFactorisationResult::kNoRoomForBlas || result.room.threads == 0) {
      cholmod_l_free_sparse(&S, &common);
      release();
      throw SolverError(no_room_for_blas_message(result.room, "SparseSPDSolver"));
    }
    if (result.status == SupernodalFactorisationResult::kPatternMismatch) {
      cholmod_l_free_sparse(&S, &common);
      release();
      throw UsageError("SparseSPDSolver::refactor: the matrix has an entry outside the sparsity pattern of the last factor() (call factor())");
    }
    if (result.status == SupernodalFactorisationResult::kNotPositiveDefinite)
      common.status = CHOLMOD_NOT_POSDEF, L->minor = static_cast<size_t>(result.column);
    else if (result.status == SupernodalFactorisationResult::kOutOfMemory)
      common.status = CHOLMOD_OUT_OF_MEMORY;
    else if (result.status == SupernodalFactorisationResult::kUnsupported && common.status >= CHOLMOD_OK) {
      std::optional<OneBlasThread> one_blas_thread;
      if (result.room.threads < 2) one_blas_thread.emplace();
      cholmod_l_factorize(S, L, &common);
      if (L->is_super && common.status >= CHOLMOD_OK) blas_call_finished();
    }
    numeric_seconds = seconds_since(t0);
    cholmod_l_free_sparse(&S, &common);
    if (common.status == CHOLMOD_NOT_POSDEF) {
      // L->minor is a column of the permuted system: the row and column of A is Perm[minor].
      const long minor = static_cast<long>(L->minor);
      const long col = L->Perm && minor >= 0 && minor < n ? static_cast<const SuiteSparse_long*>(L->Perm)[minor] : minor;
      release();
      throw SolverError("SparseSPDSolver: matrix is not positive definite (failed at column " + std::to_string(col) + ")", col);
    }
    if (common.status < CHOLMOD_OK) {
      const int status = common.status;
      release();
      throw SolverError(status == CHOLMOD_OUT_OF_MEMORY ? "SparseSPDSolver: out of memory during factorisation"
                                                        : "SparseSPDSolver: factorisation failed (CHOLMOD status " +
                                                              std::to_string(status) + ")");
    }
    if (substitution.planned()) {  // a refactorisation keeps the structure, not the values' copy
      substitution.refresh_values();
    } else if (substitution.plan(L)) {
      const long* perm = substitution.ordering();
      ordering.assign(perm, perm + n);
    }
    if (ordering.empty()) identity_ordering(ordering, n);
  }
  void solve_ordered(double* Y, int k) const {
    if (substitution.planned()) return substitution.solve_ordered(Y, k);
    solve_rows(*this, Y, k, n);
  }
  void set_single_precision_solves(bool on) { substitution.set_single_precision(on); }
  void solve(const Eigen::MatrixXd& B, Eigen::MatrixXd& Xout) const {
    if (substitution.planned() && B.cols() >= 1 && B.cols() <= SupernodalSubstitution::kMaxColumns) {
      if (Xout.rows() != B.rows() || Xout.cols() != B.cols()) Xout.resize(B.rows(), B.cols());
      substitution.solve(B.data(), Xout.data(), static_cast<int>(B.cols()));  // reads all of B before writing
      return;
    }
    cholmod_dense b;
    std::memset(&b, 0, sizeof(b));
    b.nrow = B.rows();
    b.ncol = B.cols();
    b.nzmax = B.size();
    b.d = B.rows();
    b.x = const_cast<double*>(B.data());
    b.xtype = CHOLMOD_REAL;
    b.dtype = CHOLMOD_DOUBLE;
    auto& c = const_cast<cholmod_common&>(common);
    // Under an address-space limit CHOLMOD's solve crashed where its result and workspaces (about three
    // n × k blocks) did not fit (cage-harmonic's many columns on the 10k lift under 680–700 MB).
    if (const BlasRoom room = blas_room(); room.limit_mb > 0) {
      const double need_mb = 3.0 * 8.0 * static_cast<double>(B.size()) / (1 << 20);
      if (room.left_mb < need_mb + 16)
        throw SolverError(address_space_message(
            room, "SparseSPDSolver: out of memory",
            "a solve with " + std::to_string(B.cols()) + " right-hand sides", need_mb + 16));
    }
    if (!cholmod_l_solve2(CHOLMOD_A, L, &b, nullptr, &X, nullptr, &Y, &E, &c))
      throw SolverError("SparseSPDSolver: solve failed (CHOLMOD status " + std::to_string(common.status) + ")");
    if (Xout.rows() != B.rows() || Xout.cols() != B.cols()) Xout.resize(B.rows(), B.cols());
    std::memcpy(Xout.data(), X->x, sizeof(double) * B.size());
  }
  double factor_nonzeros() const {
    if (!L) return 0;
    if (L->is_super) {
      // Supernodal storage holds dense trapezoids; count the lower-triangular part of each.
      const auto* super = static_cast<const SuiteSparse_long*>(L->super);
      const auto* pi = static_cast<const SuiteSparse_long*>(L->pi);
      double total = 0;
      for (size_t s = 0; s < L->nsuper; ++s) {
        const double cols = static_cast<double>(super[s + 1] - super[s]);
        const double rows = static_cast<double>(pi[s + 1] - pi[s]);
        total += cols * rows - cols * (cols - 1) / 2;
      }
      return total;
    }
    return static_cast<double>(static_cast<const SuiteSparse_long*>(L->p)[L->n]);
  }
};

std::string SparseSPDSolver::backend() {
  const std::string kernels = blas_kernels();
  const std::string name = "CHOLMOD AMD and supernodal analysis, two-thread supernodal factorisation";
  return kernels.empty() ? name : name + ", OpenBLAS " + kernels + " kernels";
}

#else

struct SparseSPDSolver::Impl {
  Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower> ldlt;
  std::vector<int> ordering;  // solve_ordered() takes the rows as they are
  bool ok = false;
  int n = 0;
  double analyse_seconds = 0, numeric_seconds = 0;
  void factor(const SparseMatrix& A, SparseMatrix* owned = nullptr) {
    ok = false;
    ordering.clear();
    n = static_cast<int>(A.rows());
    const auto t0 = std::chrono::steady_clock::now();
    ldlt.analyzePattern(A);
    analyse_seconds = seconds_since(t0);
    struct Release {  // also when refactor() throws
      SparseMatrix* m;
      ~Release() { if (m) SparseMatrix().swap(*m); }
    } release_owned{owned};
    refactor(A);
  }
  void refactor(const SparseMatrix& A) {
    ok = false;
    const auto t0 = std::chrono::steady_clock::now();
    ldlt.factorize(A);
    numeric_seconds = seconds_since(t0);
    if (ldlt.info() != Eigen::Success) throw SolverError("SparseSPDSolver: factorisation failed");
    const auto& D = ldlt.vectorD();
    for (int i = 0; i < n; ++i)
      if (!(D[i] > 0)) {
        // Row i of the permuted matrix is column P⁻¹(i) of A.
        const long orig = ldlt.permutationPinv().indices()[i];
        throw SolverError("SparseSPDSolver: matrix is not positive definite (failed at column " + std::to_string(orig) + ")", orig);
      }
    ok = true;
    identity_ordering(ordering, n);
  }
  void solve(const Eigen::MatrixXd& B, Eigen::MatrixXd& X) const { X = ldlt.solve(B); }
  void solve_ordered(double* Y, int k) const { solve_rows(*this, Y, k, n); }
  void set_single_precision_solves(bool) {}  // the Eigen backend solves in double
  double factor_nonzeros() const { return ok ? static_cast<double>(ldlt.matrixL().nestedExpression().nonZeros()) + n : 0; }
  void release() {
    ok = false;
    ordering.clear();
  }
};

std::string SparseSPDSolver::backend() { return "Eigen SimplicialLDLT"; }

#endif

SparseSPDSolver::SparseSPDSolver() : impl_(std::make_unique<Impl>()) {}
SparseSPDSolver::~SparseSPDSolver() = default;
SparseSPDSolver::SparseSPDSolver(SparseSPDSolver&&) noexcept = default;
SparseSPDSolver& SparseSPDSolver::operator=(SparseSPDSolver&&) noexcept = default;

namespace {
void check_factorable(const SparseMatrix& A) {
  if (A.rows() != A.cols())
    throw SolverError("SparseSPDSolver: matrix is " + std::to_string(A.rows()) + "x" + std::to_string(A.cols()) + ", not square");
  if (A.rows() == 0) throw SolverError("SparseSPDSolver: empty matrix");
}
}  // namespace

void SparseSPDSolver::factor(const SparseMatrix& A) {
  check_factorable(A);
  impl_->factor(A);
}

void SparseSPDSolver::factor(SparseMatrix&& A) {
  check_factorable(A);
  impl_->factor(A, &A);
}

void SparseSPDSolver::refactor(const SparseMatrix& A) {
  if (!factored()) throw UsageError("SparseSPDSolver::refactor: call factor() first");
  if (A.rows() != impl_->n || A.cols() != impl_->n)
    throw UsageError("SparseSPDSolver::refactor: matrix is " + std::to_string(A.rows()) + "x" + std::to_string(A.cols()) +
                     ", the factored one " + std::to_string(impl_->n) + "x" + std::to_string(impl_->n));
  impl_->refactor(A);
}

bool SparseSPDSolver::factored() const { return impl_ && impl_->n > 0 && impl_->factor_nonzeros() > 0; }
int SparseSPDSolver::size() const { return impl_ ? impl_->n : 0; }
double SparseSPDSolver::factor_nonzeros() const { return impl_ ? impl_->factor_nonzeros() : 0; }
double SparseSPDSolver::analyse_seconds() const { return impl_ ? impl_->analyse_seconds : 0; }
double SparseSPDSolver::numeric_seconds() const { return impl_ ? impl_->numeric_seconds : 0; }
void SparseSPDSolver::set_single_precision_solves(bool on) { impl_->set_single_precision_solves(on); }

void SparseSPDSolver::solve(const Eigen::MatrixXd& B, Eigen::MatrixXd& X) const {
  if (!factored()) throw UsageError("SparseSPDSolver::solve: call factor() first");
  if (B.rows() != impl_->n)
    throw UsageError("SparseSPDSolver::solve: right-hand side has " + std::to_string(B.rows()) + " rows, matrix has " +
                     std::to_string(impl_->n));
  impl_->solve(B, X);
}

void SparseSPDSolver::solve_ordered(double* Y, int k) const {
  if (!factored()) throw UsageError("SparseSPDSolver::solve_ordered: call factor() first");
  if (k < 1 || k > 4)
    throw UsageError("SparseSPDSolver::solve_ordered: " + std::to_string(k) + " right-hand sides, 1 to 4 allowed");
  impl_->solve_ordered(Y, k);
}

const std::vector<int>& SparseSPDSolver::ordering() const {
  static const std::vector<int> none;  // a moved-from solver
  return impl_ ? impl_->ordering : none;
}

Eigen::MatrixXd SparseSPDSolver::solve(const Eigen::MatrixXd& B) const {
  Eigen::MatrixXd X;
  solve(B, X);
  return X;
}

void ConstrainedQuadratic::prepare(const SparseMatrix& Q, const std::vector<int>& known) {
  factor_unknowns(split(Q, known));
}

void ConstrainedQuadratic::prepare(SparseMatrix&& Q, const std::vector<int>& known) {
  SparseMatrix Quu = split(Q, known);
  SparseMatrix().swap(Q);
  factor_unknowns(std::move(Quu));
}

SparseMatrix ConstrainedQuadratic::split(const SparseMatrix& Q, const std::vector<int>& known) {
  n_ = static_cast<int>(Q.rows());
  if (Q.rows() != Q.cols()) throw InvalidInput("ConstrainedQuadratic: Q is not square");
  std::vector<char> is_known(n_, 0);
  for (int k : known) {
    if (k < 0 || k >= n_) throw InvalidInput("ConstrainedQuadratic: known index " + std::to_string(k) + " out of range");
    if (is_known[k]) throw InvalidInput("ConstrainedQuadratic: known index " + std::to_string(k) + " given twice");
    is_known[k] = 1;
  }
  known_ = known;
  unknown_.clear();
  for (int i = 0; i < n_; ++i)
    if (!is_known[i]) unknown_.push_back(i);
  Quk_ = submatrix(Q, unknown_, known_);
  return unknown_.empty() ? SparseMatrix() : submatrix(Q, unknown_, unknown_);
}

void ConstrainedQuadratic::factor_unknowns(SparseMatrix&& Quu) {
  if (unknown_.empty()) return;
  try {
    solver_.factor(std::move(Quu));
  } catch (const SolverError& e) {
    if (e.index() < 0) throw;
    const int var = unknown_[e.index()];
    throw SolverError("ConstrainedQuadratic: the system on the unknowns is not positive definite at variable " +
                          std::to_string(var) + " (is every unknown coupled to a known value?)",
                      var);
  }
}

void ConstrainedQuadratic::solve(const Eigen::MatrixXd& known_values, Eigen::MatrixXd& x, const Eigen::MatrixXd* linear) const {
  if (n_ == 0) throw UsageError("ConstrainedQuadratic::solve: call prepare() first");
  if (known_values.rows() != static_cast<Eigen::Index>(known_.size()))
    throw UsageError("ConstrainedQuadratic::solve: " + std::to_string(known_values.rows()) + " known rows for " +
                     std::to_string(known_.size()) + " known variables");
  const Eigen::Index k = known_values.cols();
  if (linear && (linear->rows() != n_ || linear->cols() != k))
    throw UsageError("ConstrainedQuadratic::solve: linear term must be " + std::to_string(n_) + " by " + std::to_string(k));
  if (x.rows() != n_ || x.cols() != k) x.resize(n_, k);
  for (size_t i = 0; i < known_.size(); ++i) x.row(known_[i]) = known_values.row(i);
  if (unknown_.empty()) return;
  // Q_uu x_u = -(Q_uk x_k + f_u)
  rhs_.noalias() = -(Quk_ * known_values);
  if (linear)
    for (size_t i = 0; i < unknown_.size(); ++i) rhs_.row(i) -= linear->row(unknown_[i]);
  solver_.solve(rhs_, xu_);
  for (size_t i = 0; i < unknown_.size(); ++i) x.row(unknown_[i]) = xu_.row(i);
}

Eigen::MatrixXd ConstrainedQuadratic::solve(const Eigen::MatrixXd& known_values, const Eigen::MatrixXd* linear) const {
  Eigen::MatrixXd x;
  solve(known_values, x, linear);
  return x;
}

}  // namespace msd
