#pragma once
//! \file Sparse symmetric positive-definite solves and constrained quadratic minimisation (seed appendix).

#include <memory>
#include <string>
#include <vector>

#include "msdeform/core/types.h"

namespace msd {

//! Factors a sparse SPD matrix once and solves for any number of right-hand sides. Uses a supernodal
//! Cholesky factorisation when msdeform was built with SuiteSparse, else Eigen's SimplicialLDLT; the class
//! hides which. With SuiteSparse, CHOLMOD orders and analyses the matrix (AMD), the numeric factorisation
//! runs on both cores (supernodal_factorisation.h; it sets OpenBLAS to one thread meanwhile), up to 4
//! right-hand sides (a mesh's x, y, z) are solved by SupernodalSubstitution on both cores, more by
//! CHOLMOD's solve. solve() reuses internal workspace, so it is not safe to call concurrently on one
//! object.
class SparseSPDSolver {
 public:
  SparseSPDSolver();
  ~SparseSPDSolver();
  SparseSPDSolver(SparseSPDSolver&&) noexcept;
  SparseSPDSolver& operator=(SparseSPDSolver&&) noexcept;

  //! Factors A (n by n, symmetric; only its lower triangle is read).
  //! \throw SolverError if A is not square, not positive definite (index() = the row and column of A,
  //! in A's own order, whose pivot was not positive), or the factor does not fit in memory.
  void factor(const SparseMatrix& A);
  //! The same, releasing A's storage once it is copied into the factorisation's own format (with CHOLMOD
  //! before the numeric factorisation, the peak of memory; the Eigen fallback after it): for callers that
  //! need A no longer. A square, non-empty A is left empty, also when the factorisation fails.
  void factor(SparseMatrix&& A);
  //! Numeric refactorisation of a matrix with the same size and sparsity pattern as the last factor()
  //! (iterative methods whose values change each step): the ordering and symbolic analysis are reused.
  //! Entries of the last pattern may be missing from A (they count as zeros).
  //! \throw UsageError without a previous factor(), for another size, or (with SuiteSparse) for an entry
  //! outside the last pattern, after which the solver is not factored; SolverError as factor().
  void refactor(const SparseMatrix& A);
  bool factored() const;
  int size() const;

  //! Solves A X = B for B n by k; X is resized only when its shape differs, and may be B itself.
  //! \throw UsageError before factor() or on a row-count mismatch.
  void solve(const Eigen::MatrixXd& B, Eigen::MatrixXd& X) const;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& B) const;
  //! Solves A X = B for 1 ≤ k ≤ 4 right-hand sides (a mesh's x, y, z) in the factor's row order, without
  //! permuting them: Y holds n rows of 4 doubles (row-major), row i the right-hand sides of row
  //! ordering()[i] of A in its first k entries, and is overwritten with X's rows in the same order. The
  //! entries beyond k may be overwritten, with values of no meaning (keep them finite, e.g. zero). For
  //! frame loops that assemble B and read X row by row: visiting the rows in this order saves solve()'s two
  //! permutation passes (about 5 of the 1M lift transfer frame's ms). Allocates nothing where
  //! SupernodalSubstitution solves; elsewhere it goes through solve().
  //! \throw UsageError before factor() or for k outside 1..4.
  void solve_ordered(double* Y, int k) const;
  //! The rows of A in the order solve_ordered() takes them (n entries): the factor's fill-reducing
  //! ordering where SupernodalSubstitution solves, else 0, 1, …, n − 1. Empty before factor().
  const std::vector<int>& ordering() const;

  //! Which backend this build uses: "CHOLMOD AMD and supernodal analysis, two-thread supernodal
  //! factorisation" (CHOLMOD orders and analyses, core/supernodal_factorisation.h factors; with the
  //! OpenBLAS kernels in use appended, e.g. ", OpenBLAS SkylakeX kernels") or "Eigen SimplicialLDLT".
  static std::string backend();
  //! Non-zeros of the Cholesky factor (fill-in measure), 0 before factor().
  double factor_nonzeros() const;
  //! Seconds the last factor() spent on ordering and symbolic analysis, and on the numeric factorisation.
  double analyse_seconds() const;
  double numeric_seconds() const;
  //! Solves of up to 4 right-hand sides (where SupernodalSubstitution solves them) read a single-precision
  //! copy of the factor: half the memory traffic, and the exact solution of a nearby positive definite
  //! system (the factor's entries rounded to float), so a relative error of about κ(A) · 6e-8: for a
  //! preconditioner (low_pass.cpp), not for an answer. The copy (4 bytes per factor entry) is refreshed
  //! by every factor() and refactor(). Off by default; no effect with the Eigen backend.
  void set_single_precision_solves(bool on);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

//! Minimises ½ xᵀQx + xᵀf over x (n by k) subject to x(known, :) = given values (libigl's
//! min_quad_with_fixed, split into prepare and solve). prepare() factors Q restricted to the unknowns.
class ConstrainedQuadratic {
 public:
  //! Q: n by n symmetric. known: indices of the fixed variables (any order, no repeats).
  //! \throw InvalidInput on a bad index; SolverError (index() = the variable) when Q on the unknowns is
  //! not positive definite, e.g. a group of unknowns is not coupled to any known variable.
  void prepare(const SparseMatrix& Q, const std::vector<int>& known);
  //! The same, releasing Q's storage once its blocks are taken, before the factorisation (at 10M vertices
  //! the bi-Laplacian Q alone holds 2.3 GB). Q is left empty once its blocks are taken, also when the
  //! factorisation then fails.
  void prepare(SparseMatrix&& Q, const std::vector<int>& known);

  //! known_values: |known| by k, rows in the order of `known`; linear: n by k or null. Writes all n
  //! rows of x (resized only when its shape differs). \throw UsageError before prepare or on shapes.
  void solve(const Eigen::MatrixXd& known_values, Eigen::MatrixXd& x, const Eigen::MatrixXd* linear = nullptr) const;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& known_values, const Eigen::MatrixXd* linear = nullptr) const;

  const std::vector<int>& known() const { return known_; }
  const std::vector<int>& unknown() const { return unknown_; }
  //! Q(unknown, known): maps known values to the right-hand side of the reduced system.
  const SparseMatrix& coupling() const { return Quk_; }
  const SparseSPDSolver& solver() const { return solver_; }

 private:
  int n_ = 0;
  std::vector<int> known_, unknown_;
  SparseMatrix Quk_;
  SparseSPDSolver solver_;
  mutable Eigen::MatrixXd rhs_, xu_;
  // prepare() in two steps: checks `known`, sets known_, unknown_ and Quk_, and returns Q(unknown, unknown);
  // then factors that (releasing it).
  SparseMatrix split(const SparseMatrix& Q, const std::vector<int>& known);
  void factor_unknowns(SparseMatrix&& Quu);
};

}  // namespace msd
