#include <catch2/catch.hpp>
#include <strings.h>

#include <cstdlib>
#include <utility>

#include <Eigen/Dense>

#include "msdeform/core/blas_kernels.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/solver.h"
#include "test_util.h"

using namespace msd;

namespace {
// Bi-Laplacian plus a small Laplacian term on a sphere: a realistic SPD-after-constraints matrix.
SparseMatrix test_matrix(Positions& P, Faces& F) {
  test::icosphere(2, P, F);
  const LaplaceOperator lap = cotan_laplacian(P, F);
  return SparseMatrix(-lap.W + lap.W * lap.mass.cwiseInverse().asDiagonal() * lap.W);
}
}  // namespace

TEST_CASE("SparseSPDSolver solves several right-hand sides at once", "[core][solver]") {
  Positions P;
  Faces F;
  SparseMatrix A = test_matrix(P, F);
  A.diagonal().array() += 1.0;  // make it SPD without constraints
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
  Positions P;
  Faces F;
  SparseMatrix A = test_matrix(P, F);
  A.diagonal().array() += 1.0;
  SparseSPDSolver solver;
  solver.factor(A);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 3);
  CHECK((A * solver.solve(B) - B).norm() <= 1e-10 * B.norm());
  CHECK(SparseSPDSolver::backend() == "CHOLMOD supernodal, OpenBLAS " + kernels + " kernels");
}

TEST_CASE("SparseSPDSolver::refactor reuses the analysis for new values on the same pattern", "[core][solver]") {
  Positions P;
  Faces F;
  SparseMatrix A = test_matrix(P, F);
  A.diagonal().array() += 1.0;
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
