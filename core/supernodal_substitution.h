#pragma once
//! \file Forward and back substitution with a CHOLMOD supernodal Cholesky factor for a few right-hand
//! sides (the x, y, z of a mesh), on two threads. SparseSPDSolver's frame-time solve.
//!
//! CHOLMOD's own solve calls BLAS (dtrsm, dgemm) twice per supernode; a mesh Laplacian's supernodes are
//! small (8 columns and 20 rows below the diagonal on average on the 1M lift), so those calls run far
//! below the memory bandwidth, on one core. Here each supernode is a few vector loops over its columns,
//! all right-hand sides of a row in one 4-wide vector, and the elimination tree is split into two
//! subtrees of about equal work that run in parallel, the few supernodes above them after (forward) or
//! before (back) them. Each thread streams the factor's values into the cache a few KB ahead of the
//! supernode it solves (the hardware prefetcher alone left the solve waiting on memory). The result
//! equals CHOLMOD's to rounding (2e-15 relative, measured). 3-column solve on the 1M lift's Laplacian
//! (630k unknowns): 82–89 ms against CHOLMOD's 211–228 ms on a 2-core Xeon; 34 ms on a 2-core EPYC, 45.6
//! ms there without the prefetch (README, Benchmarks).

#include <vector>

struct cholmod_factor_struct;

namespace msd {

class SupernodalSubstitution {
 public:
  //! Right-hand sides solved at once; more go to CHOLMOD's solve.
  static constexpr int kMaxColumns = 4;

  //! Plans the substitution for L, a supernodal LLᵀ factor with 64-bit indices from a postordered
  //! analysis (CHOLMOD's default). L must outlive the plan; a numeric refactorisation keeps it valid, a
  //! new analysis does not. Returns false, planning nothing, for any other factor.
  bool plan(const cholmod_factor_struct* L);
  bool planned() const { return L_ != nullptr; }
  void clear();

  //! X = A⁻¹ B with A = P Lᵀ L Pᵀ: B and X are n×k column-major (leading dimension n), 1 ≤ k ≤ 4; X may
  //! be B (all of B is read before X is written). Allocates nothing; not safe to call concurrently on one
  //! object.
  void solve(const double* B, double* X, int k) const;
  //! The same without the permutations: Y holds n rows of 4 doubles, row i the right-hand sides of row
  //! ordering()[i] of A in its first k entries, and is overwritten with X's rows in the same order (the
  //! entries beyond k are solved too, into values of no meaning: keep them finite). For frame loops that
  //! assemble B and read X row by row in that order.
  void solve_ordered(double* Y, int k) const;
  //! The factor's fill-reducing ordering (CHOLMOD's Perm, n entries): row i of the factored system is
  //! row ordering()[i] of A.
  const long* ordering() const;

  //! Share of the factor's entries in the two parallel subtrees (the rest is solved on one thread).
  double parallel_share() const { return parallel_share_; }

  //! Solves read a single-precision copy of the factor's values (half the bytes; arithmetic stays in
  //! double), made now and by refresh_values(): the solve is then exact for a factor whose entries are
  //! rounded to float, i.e. for a nearby positive definite matrix, a relative error of about κ · 6e-8 in
  //! the result: for a preconditioner, not for an answer. Off by default.
  void set_single_precision(bool on);
  //! Copies the factor's values again after a numeric refactorisation (nothing unless single precision).
  void refresh_values();

 private:
  template <class T>
  void solve_with(const T* values, double* Y) const;

  const cholmod_factor_struct* L_ = nullptr;
  std::vector<long> group_[2], top_;  // supernodes of the two subtree groups and of the rest, ascending
  std::vector<int> top_slot_;         // column → its row in the top buffers, -1 outside the top
  long num_top_columns_ = 0;
  double parallel_share_ = 0;
  // Workspace: the permuted right-hand sides (4 per row), one supernode's rows below its diagonal per
  // thread, and each group's updates to top rows.
  mutable std::vector<double> y_, w_[3], top_update_[2];
  bool single_ = false;
  std::vector<float> values_f_;  // the factor's values in single precision, when single_
};

}  // namespace msd
