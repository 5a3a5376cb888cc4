#include <catch2/catch.hpp>
#include <strings.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "msdeform/core/blas_kernels.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/solver.h"
#include "test_util.h"

#ifdef MSD_HAVE_CHOLMOD
#include <cholmod.h>

#include "msdeform/core/supernodal_factorisation.h"
#include "msdeform/core/supernodal_substitution.h"
#endif

using namespace msd;

namespace {
// Bi-Laplacian plus a small Laplacian term on a sphere: a realistic SPD-after-constraints matrix.
SparseMatrix test_matrix(Positions& P, Faces& F) {
  test::icosphere(2, P, F);
  const LaplaceOperator lap = cotan_laplacian(P, F);
  return SparseMatrix(-lap.W + lap.W * lap.mass.cwiseInverse().asDiagonal() * lap.W);
}
// The same made positive definite without constraints.
SparseMatrix test_matrix_spd() {
  Positions P;
  Faces F;
  SparseMatrix A = test_matrix(P, F);
  A.diagonal().array() += 1.0;
  return A;
}
}  // namespace

TEST_CASE("SparseSPDSolver solves several right-hand sides at once", "[core][solver]") {
  const SparseMatrix A = test_matrix_spd();
  SparseSPDSolver solver;
  solver.factor(A);
  INFO("backend " << SparseSPDSolver::backend());
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 5);
  const Eigen::MatrixXd X = solver.solve(B);
  CHECK((A * X - B).norm() <= 1e-10 * B.norm());
  Eigen::MatrixXd X2(3, 3);  // wrong shape: resized
  solver.solve(B, X2);
  CHECK((X2 - X).norm() == 0.0);
  CHECK(solver.factor_nonzeros() > 0);
}

TEST_CASE("OpenBLAS behind CHOLMOD uses the kernels the CPU allows, not its Prescott fallback", "[core][solver]") {
  // OpenBLAS 0.3.21 (Debian 12) falls back to SSE3 kernels on CPU models it does not know;
  // select_blas_kernels() then selects them by the CPU's features. Only meaningful with OpenBLAS as the BLAS, on
  // an x86 CPU with AVX2 and FMA, and without a user's OPENBLAS_CORETYPE.
#if defined(__x86_64__) || defined(__i386__)
  const bool modern = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  const bool modern = false;
#endif
  if (blas_kernels().empty() || !modern || std::getenv("OPENBLAS_CORETYPE")) return;
  const std::string kernels = select_blas_kernels();
  CHECK(strcasecmp(kernels.c_str(), "prescott") != 0);
  CHECK(select_blas_kernels() == kernels);  // a second call changes nothing
  const SparseMatrix A = test_matrix_spd();
  SparseSPDSolver solver;
  solver.factor(A);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 3);
  CHECK((A * solver.solve(B) - B).norm() <= 1e-10 * B.norm());
  CHECK(SparseSPDSolver::backend() ==
        "CHOLMOD AMD and supernodal analysis, two-thread supernodal factorisation, OpenBLAS " + kernels + " kernels");
}

namespace {
// The cotan Laplacian of a jittered n x n grid on its interior vertices (the boundary fixed): the matrix of
// a Poisson solve on a mesh, with many small supernodes.
SparseMatrix grid_laplacian(int n) {
  Positions P;
  Faces F;
  std::vector<bool> interior;
  test::jittered_grid(n, 0.3, P, F, interior);
  std::vector<int> inner;
  for (int v = 0; v < P.rows(); ++v)
    if (interior[v]) inner.push_back(v);
  return submatrix(SparseMatrix(-cotan_laplacian(P, F).W), inner, inner);
}
// n×n, 4 on the diagonal and -1 on the `bandwidth` diagonals on either side: diagonally dominant, so positive
// definite, for bandwidth <= 2.
SparseMatrix band_matrix(int n, int bandwidth) {
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < n; ++i)
    for (int j = std::max(0, i - bandwidth); j <= std::min(n - 1, i + bandwidth); ++j) entries.emplace_back(i, j, i == j ? 4 : -1);
  SparseMatrix A(n, n);
  A.setFromTriplets(entries.begin(), entries.end());
  return A;
}
}  // namespace

TEST_CASE("SparseSPDSolver: 1 to 4 right-hand sides equal the same columns solved among 5, also in place",
          "[core][solver]") {
  // Up to 4 columns take the solver's own substitution (two threads), 5 take CHOLMOD's solve.
  for (const SparseMatrix& A : {grid_laplacian(120), test_matrix_spd()}) {
    SparseSPDSolver solver;
    solver.factor(A);
    const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 5);
    const Eigen::MatrixXd all = solver.solve(B);
    REQUIRE((A * all - B).norm() <= 1e-10 * B.norm());
    for (int k = 1; k <= 4; ++k) {
      INFO(k << " columns, " << A.rows() << " unknowns");
      const Eigen::MatrixXd X = solver.solve(B.leftCols(k));
      CHECK((X - all.leftCols(k)).cwiseAbs().maxCoeff() <= 1e-12 * all.cwiseAbs().maxCoeff());
      Eigen::MatrixXd in_place = B.leftCols(k);
      solver.solve(in_place, in_place);
      CHECK((in_place - X).cwiseAbs().maxCoeff() == 0.0);
    }
  }
  // Matrices without a tree to split: a diagonal one (every column its own root) and a 1 x 1.
  SparseMatrix D(50, 50);
  for (int i = 0; i < 50; ++i) D.insert(i, i) = 1.0 + i;
  SparseSPDSolver diagonal;
  diagonal.factor(D);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(50, 3);
  const Eigen::MatrixXd x = diagonal.solve(b);
  for (int i = 0; i < 50; ++i) CHECK((x.row(i) * (1.0 + i) - b.row(i)).norm() <= 1e-15 * b.row(i).norm());
  SparseMatrix one(1, 1);
  one.insert(0, 0) = 4.0;
  SparseSPDSolver single;
  single.factor(one);
  CHECK((single.solve(Eigen::MatrixXd::Constant(1, 2, 2.0)).array() == 0.5).all());
}

TEST_CASE("SparseSPDSolver::solve_ordered equals solve() in the factor's row order, 1 to 4 columns",
          "[core][solver]") {
  const SparseMatrix A = grid_laplacian(120);
  SparseSPDSolver solver;
  REQUIRE(solver.ordering().empty());
  double unused[4] = {0, 0, 0, 0};
  CHECK_THROWS_AS(solver.solve_ordered(unused, 3), UsageError);
  solver.factor(A);
  const long n = A.rows();
  // ordering() is a permutation of the rows.
  std::vector<int> order = solver.ordering();
  REQUIRE(static_cast<long>(order.size()) == n);
  std::sort(order.begin(), order.end());
  for (long i = 0; i < n; ++i) REQUIRE(order[i] == i);
  const std::vector<int>& ordering = solver.ordering();
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, 4);
  for (int k = 1; k <= 4; ++k) {
    INFO(k << " columns");
    const Eigen::MatrixXd X = solver.solve(B.leftCols(k));
    // Rows in the factor's order; the columns beyond k hold values the solve must ignore.
    Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> Y(n, 4);
    for (long i = 0; i < n; ++i) Y.row(i) = B.row(ordering[i]);
    solver.solve_ordered(Y.data(), k);
    double diff = 0;
    for (long i = 0; i < n; ++i) diff = std::max(diff, (Y.row(i).head(k) - X.row(ordering[i])).cwiseAbs().maxCoeff());
    CHECK(diff <= 1e-14 * X.cwiseAbs().maxCoeff());
  }
  CHECK_THROWS_AS(solver.solve_ordered(unused, 0), UsageError);
  CHECK_THROWS_AS(solver.solve_ordered(unused, 5), UsageError);
  SparseSPDSolver moved(std::move(solver));
  CHECK(solver.ordering().empty());  // NOLINT(bugprone-use-after-move): a moved-from solver is empty
  CHECK(moved.ordering().size() == static_cast<size_t>(n));
}

#ifdef MSD_HAVE_CHOLMOD
namespace {
// A's stored entries (compressed columns) as CHOLMOD's matrix, marked lower (stype -1): CHOLMOD reads the
// lower triangle, and ignores an upper one if A stores it too.
cholmod_sparse* to_cholmod(SparseMatrix A, cholmod_common& common) {
  A.makeCompressed();
  cholmod_sparse* S = cholmod_l_allocate_sparse(A.rows(), A.cols(), A.nonZeros(), true, true, -1, CHOLMOD_REAL, &common);
  for (Eigen::Index j = 0; j <= A.cols(); ++j) static_cast<SuiteSparse_long*>(S->p)[j] = A.outerIndexPtr()[j];
  for (Eigen::Index k = 0; k < A.nonZeros(); ++k) {
    static_cast<SuiteSparse_long*>(S->i)[k] = A.innerIndexPtr()[k];
    static_cast<double*>(S->x)[k] = A.valuePtr()[k];
  }
  return S;
}
}  // namespace

TEST_CASE("SupernodalSubstitution equals CHOLMOD's solve, splits the tree, refuses other factors", "[core][solver]") {
  const SparseMatrix A = grid_laplacian(150);
  cholmod_common common;
  cholmod_l_start(&common);
  cholmod_sparse* S = to_cholmod(A.triangularView<Eigen::Lower>(), common);
  common.supernodal = CHOLMOD_SUPERNODAL;
  cholmod_factor* L = cholmod_l_analyze(S, &common);
  REQUIRE(cholmod_l_factorize(S, L, &common));
  SupernodalSubstitution substitution;
  REQUIRE(substitution.plan(L));
  CHECK(substitution.parallel_share() > 0.5);  // two subtrees hold most of the work
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 4);
  cholmod_dense b;
  b.nrow = B.rows(), b.ncol = B.cols(), b.nzmax = B.size(), b.d = B.rows();
  b.x = const_cast<double*>(B.data()), b.z = nullptr, b.xtype = CHOLMOD_REAL, b.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* reference = cholmod_l_solve(CHOLMOD_A, L, &b, &common);
  const Eigen::Map<const Eigen::MatrixXd> expected(static_cast<const double*>(reference->x), B.rows(), B.cols());
  Eigen::MatrixXd X(B.rows(), B.cols());
  substitution.solve(B.data(), X.data(), 4);
  CHECK((X - expected).cwiseAbs().maxCoeff() <= 1e-12 * expected.cwiseAbs().maxCoeff());
  Eigen::MatrixXd x1(B.rows(), 1);
  substitution.solve(B.data(), x1.data(), 1);
  CHECK((x1.col(0) - expected.col(0)).cwiseAbs().maxCoeff() <= 1e-12 * expected.cwiseAbs().maxCoeff());
  // A simplicial factor is not planned (CHOLMOD's solve serves it).
  cholmod_factor* simplicial = cholmod_l_copy_factor(L, &common);
  REQUIRE(cholmod_l_change_factor(CHOLMOD_REAL, true, false, true, true, simplicial, &common));
  CHECK_FALSE(substitution.plan(simplicial));
  CHECK_FALSE(substitution.planned());
  cholmod_l_free_factor(&simplicial, &common);
  cholmod_l_free_dense(&reference, &common);
  cholmod_l_free_factor(&L, &common);
  cholmod_l_free_sparse(&S, &common);
  cholmod_l_finish(&common);
}

TEST_CASE("The two-thread supernodal factorisation equals CHOLMOD's and reports a pivot that is not positive",
          "[core][solver]") {
  // A grid bi-Laplacian: supernodes from 1 to a few hundred columns, the tree split between both threads.
  const SparseMatrix lap = grid_laplacian(90);
  SparseMatrix A = lap * lap;
  A.makeCompressed();
  cholmod_common common;
  cholmod_l_start(&common);
  common.supernodal = CHOLMOD_SUPERNODAL;
  cholmod_sparse* S = to_cholmod(A, common);
  cholmod_factor* reference = cholmod_l_analyze(S, &common);
  REQUIRE(reference);
  REQUIRE(reference->is_super);
  cholmod_factor* L = cholmod_l_copy_factor(reference, &common);
  REQUIRE(cholmod_l_factorize(S, reference, &common));
  REQUIRE(reference->minor == reference->n);
  // Not numeric yet: refused, nothing touched.
  CHECK(factorize_supernodal(S, L).status == SupernodalFactorisationResult::kUnsupported);
  REQUIRE(cholmod_l_change_factor(CHOLMOD_REAL, true, true, true, true, L, &common));
  const auto done = factorize_supernodal(S, L);
  REQUIRE(done.status == SupernodalFactorisationResult::kDone);
  CHECK(L->minor == L->n);
  const Eigen::Map<const Eigen::VectorXd> expected(static_cast<const double*>(reference->x), reference->xsize);
  const Eigen::Map<const Eigen::VectorXd> got(static_cast<const double*>(L->x), L->xsize);
  REQUIRE(got.size() == expected.size());
  CHECK((got - expected).cwiseAbs().maxCoeff() <= 1e-12 * expected.cwiseAbs().maxCoeff());
  // A refactorisation with new values on the same structure.
  SparseMatrix A2 = A;
  A2.coeffs() *= 3.0;
  cholmod_sparse* S2 = to_cholmod(A2, common);
  REQUIRE(factorize_supernodal(S2, L).status == SupernodalFactorisationResult::kDone);
  CHECK((got - std::sqrt(3.0) * expected).cwiseAbs().maxCoeff() <= 1e-12 * expected.cwiseAbs().maxCoeff());
  // Shifted below its smallest eigenvalue but not its largest: indefinite. CHOLMOD fails too.
  SparseMatrix shifted = A;
  shifted.diagonal().array() -= 0.5 * shifted.diagonal().mean();
  cholmod_sparse* S3 = to_cholmod(shifted, common);
  const auto failed = factorize_supernodal(S3, L);
  CHECK(failed.status == SupernodalFactorisationResult::kNotPositiveDefinite);
  CHECK(failed.column >= 0);
  CHECK(failed.column < static_cast<long>(L->n));
  cholmod_l_factorize(S3, reference, &common);
  CHECK(common.status == CHOLMOD_NOT_POSDEF);
  // An entry outside the analysed pattern is named (CHOLMOD would drop it): a tridiagonal matrix on the
  // analysis of a diagonal one.
  cholmod_sparse* S4 = to_cholmod(band_matrix(50, 0), common);
  cholmod_sparse* S5 = to_cholmod(band_matrix(50, 1), common);
  cholmod_factor* diagonal_factor = cholmod_l_analyze(S4, &common);
  REQUIRE(cholmod_l_change_factor(CHOLMOD_REAL, true, true, true, true, diagonal_factor, &common));
  CHECK(factorize_supernodal(S4, diagonal_factor).status == SupernodalFactorisationResult::kDone);
  CHECK(factorize_supernodal(S5, diagonal_factor).status == SupernodalFactorisationResult::kPatternMismatch);
  // A simplicial factor is refused.
  common.supernodal = CHOLMOD_SIMPLICIAL;
  cholmod_factor* simplicial = cholmod_l_analyze(S, &common);
  REQUIRE(cholmod_l_factorize(S, simplicial, &common));
  CHECK(factorize_supernodal(S, simplicial).status == SupernodalFactorisationResult::kUnsupported);
  for (cholmod_sparse** m : {&S, &S2, &S3, &S4, &S5}) cholmod_l_free_sparse(m, &common);
  for (cholmod_factor** f : {&simplicial, &reference, &L, &diagonal_factor}) cholmod_l_free_factor(f, &common);
  cholmod_l_finish(&common);
}
#endif

TEST_CASE("SparseSPDSolver::refactor reuses the analysis for new values on the same pattern", "[core][solver]") {
  const SparseMatrix A = test_matrix_spd();
  SparseSPDSolver solver;
  CHECK_THROWS_AS(solver.refactor(A), UsageError);
  solver.factor(A);
  SparseMatrix A2 = A;
  A2.diagonal().array() += 3.0;
  A2.coeffs() *= 2.0;
  solver.refactor(A2);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 2);
  CHECK((A2 * solver.solve(B) - B).norm() <= 1e-10 * B.norm());
  CHECK_THROWS_AS(solver.refactor(SparseMatrix(3, 3)), UsageError);
#ifdef MSD_HAVE_CHOLMOD
  // An entry outside the factored pattern is refused (CHOLMOD's factorisation dropped it silently).
  solver.factor(band_matrix(40, 0));
  try {
    solver.refactor(band_matrix(40, 1));
    FAIL("expected UsageError");
  } catch (const UsageError& e) {
    CHECK(std::string(e.what()).find("outside the sparsity pattern") != std::string::npos);
  }
  CHECK_FALSE(solver.factored());
#endif
}

TEST_CASE("SparseSPDSolver reports a matrix that is not positive definite", "[core][solver]") {
  Positions P;
  Faces F;
  const SparseMatrix A = test_matrix(P, F);  // singular: constants are in the kernel
  SparseSPDSolver solver;
  CHECK_THROWS_AS(solver.factor(A), SolverError);
  SparseMatrix N(3, 3);
  N.insert(0, 0) = 1;
  N.insert(1, 1) = -2;
  N.insert(2, 2) = 1;
  try {
    solver.factor(N);
    FAIL("expected SolverError");
  } catch (const SolverError& e) {
    CHECK(std::string(e.what()).find("not positive definite") != std::string::npos);
    CHECK(e.index() == 1);
  }
  CHECK_THROWS_AS(solver.solve(Eigen::MatrixXd::Ones(3, 1)), UsageError);
#ifdef MSD_HAVE_CHOLMOD
  // index() is the row of A, not the column of the permuted system the factorisation failed at (that
  // named a wrong vertex in every "singular near vertex" message): a grid Laplacian, whose principal
  // submatrices are all positive definite, with one diagonal entry made negative fails there and only
  // there, wherever the ordering puts it.
  const SparseMatrix grid = grid_laplacian(40);
  for (int row : {0, 77, 500, static_cast<int>(grid.rows()) - 1}) {
    SparseMatrix bad = grid;
    bad.coeffRef(row, row) = -1;
    try {
      solver.factor(bad);
      FAIL("expected SolverError");
    } catch (const SolverError& e) {
      CHECK(e.index() == row);
    }
  }
#endif
}

TEST_CASE("ConstrainedQuadratic equals a dense reference solve, several right-hand sides", "[core][solver]") {
  Positions P;
  Faces F;
  const SparseMatrix Q = test_matrix(P, F);
  const int n = static_cast<int>(Q.rows());
  std::vector<int> known;
  for (int i = 0; i < n; i += 7) known.push_back(i);
  std::reverse(known.begin(), known.end());  // any order
  const Eigen::MatrixXd values = Eigen::MatrixXd::Random(known.size(), 3);
  const Eigen::MatrixXd linear = Eigen::MatrixXd::Random(n, 3);
  ConstrainedQuadratic cq;
  cq.prepare(Q, known);
  const Eigen::MatrixXd x = cq.solve(values, &linear);

  // Dense reference: KKT system [Q Cᵀ; C 0] [x; λ] = [-f; values].
  const int m = static_cast<int>(known.size());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n + m, n + m);
  K.topLeftCorner(n, n) = Eigen::MatrixXd(Q);
  for (int k = 0; k < m; ++k) K(n + k, known[k]) = K(known[k], n + k) = 1.0;
  Eigen::MatrixXd rhs(n + m, 3);
  rhs << -linear, values;
  const Eigen::MatrixXd ref = K.fullPivLu().solve(rhs).topRows(n);
  CHECK((x - ref).cwiseAbs().maxCoeff() <= 1e-9 * ref.cwiseAbs().maxCoeff());
  for (int k = 0; k < m; ++k) REQUIRE(x.row(known[k]) == values.row(k));

  // Without a linear term, one column at a time gives the same as all at once.
  const Eigen::MatrixXd all = cq.solve(values);
  for (int c = 0; c < 3; ++c) CHECK((cq.solve(values.col(c)) - all.col(c)).norm() <= 1e-12 * all.norm());
}

TEST_CASE("factor and prepare from a matrix the caller gives up: same result, the matrix released", "[core][solver]") {
  Positions P;
  Faces F;
  const SparseMatrix Q = test_matrix(P, F);
  const std::vector<int> known = {0, 5, 9};
  const Eigen::MatrixXd values = Eigen::MatrixXd::Random(3, 2);
  ConstrainedQuadratic kept, released;
  kept.prepare(Q, known);
  SparseMatrix moved = Q;
  released.prepare(std::move(moved), known);
  CHECK(moved.nonZeros() == 0);
  CHECK(moved.rows() == 0);
  CHECK((released.solve(values) - kept.solve(values)).cwiseAbs().maxCoeff() == 0.0);

  SparseMatrix A = Q;
  A.diagonal().array() += 1.0;
  const SparseMatrix A_copy = A;
  SparseSPDSolver a, b;
  a.factor(A_copy);
  b.factor(std::move(A));
  CHECK(A.nonZeros() == 0);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A_copy.rows(), 2);
  CHECK((b.solve(B) - a.solve(B)).cwiseAbs().maxCoeff() == 0.0);
  // Released also when the factorisation fails.
  SparseMatrix singular = Q;
  CHECK_THROWS_AS(b.factor(std::move(singular)), SolverError);
  CHECK(singular.nonZeros() == 0);
}

TEST_CASE("ConstrainedQuadratic: bad use gives clear errors", "[core][solver]") {
  Positions P;
  Faces F;
  const SparseMatrix Q = test_matrix(P, F);
  ConstrainedQuadratic cq;
  CHECK_THROWS_AS(cq.solve(Eigen::MatrixXd::Zero(1, 1)), UsageError);
  CHECK_THROWS_AS(cq.prepare(Q, {0, 0}), InvalidInput);
  CHECK_THROWS_AS(cq.prepare(Q, {-1}), InvalidInput);
  CHECK_THROWS_AS(cq.prepare(Q, {}), SolverError);  // nothing known: constants undetermined
  cq.prepare(Q, {0, 1, 2});
  CHECK_THROWS_AS(cq.solve(Eigen::MatrixXd::Zero(2, 3)), UsageError);
}
