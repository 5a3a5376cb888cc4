#include "msdeform/core/supernodal_factorisation.h"

#include <cholmod.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <atomic>
#include <climits>
#include <cstdio>
#include <memory>
#include <optional>
#include <vector>

#include "msdeform/core/blas_kernels.h"
#include "msdeform/core/supernodal_tree.h"

// BLAS and LAPACK as CHOLMOD calls them (32-bit integers: Debian's OpenBLAS and reference BLAS).
extern "C" {
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha, const double* a,
            const int* lda, const double* beta, double* c, const int* ldc);
void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k, const double* alpha,
            const double* a, const int* lda, const double* b, const int* ldb, const double* beta, double* c,
            const int* ldc);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m, const int* n,
            const double* alpha, const double* a, const int* lda, double* b, const int* ldb);
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info);
}

namespace msd {
namespace {

using Int = SuiteSparse_long;

// The lower triangle of P A Pᵀ by columns of the factor: column j holds its entries (i, j), i ≥ j, in no
// particular order.
struct PermutedLower {
  std::vector<Int> p, i;
  std::vector<double> x;
};

// A: lower triangle stored (entries above the diagonal are ignored, as CHOLMOD does for stype -1). Two
// threads, each writing the columns of one half of the factor (both read all of A, in order).
PermutedLower permute(const cholmod_sparse* A, const std::vector<Int>& pinv) {
  const long n = static_cast<long>(pinv.size());
  const auto* ap = static_cast<const Int*>(A->p);
  const auto* ai = static_cast<const Int*>(A->i);
  const auto* ax = static_cast<const double*>(A->x);
  const auto* anz = static_cast<const Int*>(A->nz);
  // f(i, j, value) for every entry of the lower triangle of P A Pᵀ whose column j is in [begin, end).
  auto for_each_entry = [&](long begin, long end, auto&& f) {
    for (long c = 0; c < n; ++c) {
      const Int last = A->packed ? ap[c + 1] : ap[c] + anz[c], k = pinv[c];
      for (Int q = ap[c]; q < last; ++q)
        if (ai[q] >= c) {
          const Int r = pinv[ai[q]], j = std::min(r, k);
          if (j >= begin && j < end) f(std::max(r, k), j, ax[q]);
        }
    }
  };
  PermutedLower C;
  C.p.assign(n + 1, 0);
  const long half = n / 2;
  tbb::parallel_invoke([&] { for_each_entry(0, half, [&](Int, Int j, double) { ++C.p[j + 1]; }); },
                       [&] { for_each_entry(half, n, [&](Int, Int j, double) { ++C.p[j + 1]; }); });
  for (long j = 0; j < n; ++j) C.p[j + 1] += C.p[j];
  C.i.resize(C.p[n]);
  C.x.resize(C.p[n]);
  std::vector<Int> next(C.p.begin(), C.p.end() - 1);
  auto fill = [&](Int i, Int j, double v) {
    C.i[next[j]] = i;
    C.x[next[j]++] = v;
  };
  tbb::parallel_invoke([&] { for_each_entry(0, half, fill); }, [&] { for_each_entry(half, n, fill); });
  return C;
}

class Factorisation {
 public:
  Factorisation(const cholmod_sparse* A, cholmod_factor* L)
      : n_(static_cast<long>(L->n)),
        ns_(static_cast<long>(L->nsuper)),
        super_(static_cast<const Int*>(L->super)),
        pi_(static_cast<const Int*>(L->pi)),
        px_(static_cast<const Int*>(L->px)),
        rows_(static_cast<const Int*>(L->s)),
        perm_(static_cast<const Int*>(L->Perm)),
        x_(static_cast<double*>(L->x)),
        max_update_(L->maxcsize > 0 ? static_cast<long>(L->maxcsize) : LONG_MAX),
        pinv_(n_),
        next_(ns_, -1),
        position_(ns_, 0),
        failed_column_(LONG_MAX) {
    for (long k = 0; k < n_; ++k) pinv_[perm_[k]] = k;
    A_ = permute(A, pinv_);
    postordered_ = supernodal_elimination_tree(L, super_of_, parent_);
  }

  // Factors L: the two groups in parallel, each summing its updates to the supernodes above the split
  // (group 0's in L, group 1's in a buffer laid out alike), then those supernodes.
  SupernodalFactorisationResult run() {
    SupernodalFactorisationResult result;
    const std::vector<int> group = split();
    if (group.empty()) return result;  // not postordered: kUnsupported
    std::vector<long> order[3], in_l, in_buffer;  // the groups' supernodes; where the top's sums go
    long buffer_size = 0;
    for (long s = 0; s < ns_; ++s) {
      order[group[s]].push_back(s);
      if (group[s] == 2) in_l.push_back(px_[s]), in_buffer.push_back(buffer_size), buffer_size += size(s);
    }
    std::unique_ptr<double[]> buffer(new double[std::max<long>(buffer_size, 1)]);
    allocate(work_[0], order[0]);
    allocate(work_[1], order[1]);
    // Asked now, with the factor and the workspaces allocated: OpenBLAS's buffers come on top of them.
    const BlasRoom room = blas_room();
    if (room.threads == 0) {
      result.status = SupernodalFactorisationResult::kNoRoomForBlas;
      result.room = room;
      return result;
    }
    std::optional<OneBlasThread> one_blas_thread;  // all along where BLAS has room for one thread only
    if (room.threads < 2) one_blas_thread.emplace();
    if (room.threads >= 2) {
      OneBlasThread one_thread;
      tbb::parallel_invoke([&] { factor_group(0, order[0], order[2], x_, in_l); },
                           [&] { factor_group(1, order[1], order[2], buffer.get(), in_buffer); });
    } else {
      factor_group(0, order[0], order[2], x_, in_l);
      factor_group(1, order[1], order[2], buffer.get(), in_buffer);
    }
    blas_call_finished();  // OpenBLAS keeps the buffer it found for the next call
    work_[0] = Workspace(), work_[1] = Workspace();
    if (!failed()) {
      allocate(work_[2], order[2]);
      factor_top(order[2], buffer.get(), in_buffer);
    }
    if (pattern_mismatch_) {
      result.status = SupernodalFactorisationResult::kPatternMismatch;
      return result;
    }
    if (failed()) {
      result.status = SupernodalFactorisationResult::kNotPositiveDefinite;
      result.column = failed_column_;
      return result;
    }
    result.status = SupernodalFactorisationResult::kDone;
    return result;
  }

 private:
  // The group of every supernode (split_elimination_tree), or an empty vector when L is not postordered.
  std::vector<int> split() const {
    if (!postordered_) return {};
    std::vector<double> work(ns_);  // flops, up to a constant: the supernode's own and its updates
    for (long s = 0; s < ns_; ++s) {
      const double nrow = static_cast<double>(pi_[s + 1] - pi_[s]);
      work[s] = static_cast<double>(super_[s + 1] - super_[s]) * nrow * nrow;
    }
    return split_elimination_tree(parent_, work);
  }

  // Group g's part (workspace g): factors its supernodes (ascending), then sums their updates to the
  // supernodes above the split (`top`, ascending) into `top_sums`: L's own storage for group 0, a buffer
  // laid out alike (offsets top_offset) for group 1.
  void factor_group(int g, const std::vector<long>& supernodes, const std::vector<long>& top, double* top_sums,
                    const std::vector<long>& top_offset) {
    Workspace& w = work_[g];
    for (long s : supernodes) {
      if (failed()) return;
      double* Ls = x_ + px_[s];
      start(s, Ls, w);
      if (!add_matrix(s, Ls, w)) return mismatch();
      add_updates(s, Ls, w);
      if (!finish(s, Ls, w)) return;
    }
    for (size_t t = 0; t < top.size(); ++t) {
      const long s = top[t];
      double* sum = top_sums + top_offset[t];
      start(s, sum, w);
      add_updates(s, sum, w);
    }
  }

  // The supernodes above the split (workspace 2), after both groups: L holds group 0's sums, `group1_sums`
  // group 1's.
  void factor_top(const std::vector<long>& top, const double* group1_sums, const std::vector<long>& top_offset) {
    Workspace& w = work_[2];
    for (size_t t = 0; t < top.size(); ++t) {
      const long s = top[t];
      double* Ls = x_ + px_[s];
      const double* other = group1_sums + top_offset[t];
      for (long k = 0, end = size(s); k < end; ++k) Ls[k] += other[k];
      set_map(s, w);
      if (!add_matrix(s, Ls, w)) return mismatch();
      add_updates(s, Ls, w);
      if (!finish(s, Ls, w)) return;
    }
  }

  bool failed() const {
    return pattern_mismatch_.load(std::memory_order_relaxed) || failed_column_.load(std::memory_order_relaxed) != LONG_MAX;
  }
  struct Workspace {
    std::unique_ptr<Int[]> map;        // row → its position in the current supernode
    std::unique_ptr<double[]> update;  // one descendant's update (allocate() sizes it)
    std::vector<Int> head;             // per supernode, the descendants waiting to update it (linked by next_)
  };

  // Workspace for factoring `supernodes`: its update block holds the largest update one of them makes
  // (rows below the diagonal block, squared; at most L->maxcsize).
  void allocate(Workspace& w, const std::vector<long>& supernodes) const {
    long largest = 1;
    for (long s : supernodes) {
      const long below = (pi_[s + 1] - pi_[s]) - (super_[s + 1] - super_[s]);
      largest = std::max(largest, below * below);
    }
    w.map.reset(new Int[n_]());  // zeros: add_matrix checks any entry it reads
    w.update.reset(new double[std::min(largest, max_update_)]);
    w.head.assign(ns_, -1);
  }
  long size(long s) const { return (super_[s + 1] - super_[s]) * (pi_[s + 1] - pi_[s]); }
  void set_map(long s, Workspace& w) const {
    for (Int k = pi_[s]; k < pi_[s + 1]; ++k) w.map[rows_[k]] = k - pi_[s];
  }
  // Zeroes Ls, supernode s's values (rows × columns, column-major), and maps its rows.
  void start(long s, double* Ls, Workspace& w) const {
    std::fill(Ls, Ls + size(s), 0.0);
    set_map(s, w);
  }
  // Adds the lower triangle of P A Pᵀ in columns of s. False for an entry outside L's pattern (A is not
  // the matrix L was analysed for).
  bool add_matrix(long s, double* Ls, const Workspace& w) const {
    const Int k1 = super_[s], first = pi_[s], nrow = pi_[s + 1] - first;
    for (Int j = k1; j < super_[s + 1]; ++j) {
      double* column = Ls + (j - k1) * nrow;
      for (Int q = A_.p[j]; q < A_.p[j + 1]; ++q) {
        const Int i = A_.i[q], k = w.map[i];
        if (k >= nrow || rows_[first + k] != i) return false;
        column[k] += A_.x[q];
      }
    }
    return true;
  }
  // Subtracts from Ls the updates of the descendants queued for s in w's lists: each the product of its
  // rows from the first in s's columns down, with its rows in s's columns, transposed. Then queues each
  // for the supernode of its next row. (A group's descendants are queued in its own workspace; the top's
  // lists hold only top supernodes: the groups applied theirs to the top's sums.)
  void add_updates(long s, double* Ls, Workspace& w) {
    static const double one = 1, zero = 0;
    const Int k1 = super_[s], k2 = super_[s + 1], nrow = pi_[s + 1] - pi_[s];
    Int d = w.head[s];
    w.head[s] = -1;
    while (d >= 0) {
      const Int following = next_[d];
      const Int p1 = position_[d], end = pi_[d + 1];
      Int p2 = p1;
      while (p2 < end && rows_[p2] < k2) ++p2;
      const int rows1 = static_cast<int>(p2 - p1), rows2 = static_cast<int>(end - p1), rows3 = rows2 - rows1;
      const int dcol = static_cast<int>(super_[d + 1] - super_[d]), drow = static_cast<int>(end - pi_[d]);
      const double* Ld = x_ + px_[d] + (p1 - pi_[d]);
      double* C = w.update.get();  // rows2 × rows1, lower trapezoid
      dsyrk_("L", "N", &rows1, &dcol, &one, Ld, &drow, &zero, C, &rows2);
      if (rows3 > 0) dgemm_("N", "T", &rows3, &rows1, &dcol, &one, Ld + rows1, &drow, Ld, &drow, &zero, C + rows1, &rows2);
      for (int jj = 0; jj < rows1; ++jj) {
        double* column = Ls + (rows_[p1 + jj] - k1) * nrow;
        const double* c = C + static_cast<long>(jj) * rows2;
        for (int ii = jj; ii < rows2; ++ii) column[w.map[rows_[p1 + ii]]] -= c[ii];
      }
      if (p2 < end) {
        position_[d] = p2;
        link(d, w);
      }
      d = following;
    }
  }
  // Factors s's diagonal block and solves the block below; queues s for its parent. False (the failing
  // column recorded) when the block is not positive definite.
  bool finish(long s, double* Ls, Workspace& w) {
    static const double one = 1;
    const int ncol = static_cast<int>(super_[s + 1] - super_[s]), nrow = static_cast<int>(pi_[s + 1] - pi_[s]);
    int info = 0;
    dpotrf_("L", &ncol, Ls, &nrow, &info);
    if (info != 0) {
      const long column = super_[s] + (info > 0 ? info - 1 : 0);
      long seen = failed_column_.load();
      while (column < seen && !failed_column_.compare_exchange_weak(seen, column)) {
      }
      return false;
    }
    if (nrow > ncol) {
      const int below = nrow - ncol;
      dtrsm_("R", "L", "T", "N", &below, &ncol, &one, Ls, &nrow, Ls + ncol, &nrow);
      position_[s] = pi_[s] + ncol;
      link(s, w);
    }
    return true;
  }
  void mismatch() { pattern_mismatch_ = true; }
  // Queues supernode d, whose rows from position_[d] on are not yet applied, for the supernode of its next
  // row.
  void link(long d, Workspace& w) {
    const long t = super_of_[rows_[position_[d]]];
    next_[d] = w.head[t];
    w.head[t] = d;
  }

  const long n_, ns_;
  const Int *super_, *pi_, *px_, *rows_, *perm_;
  double* x_;
  const long max_update_;  // L->maxcsize, the largest update block of all (no bound when it is not set)
  std::vector<Int> pinv_;
  PermutedLower A_;
  std::vector<long> super_of_, parent_;  // supernodal_elimination_tree
  bool postordered_ = false;
  std::vector<Int> next_, position_;  // per supernode: its link in a waiting list, its first row not applied
  Workspace work_[3];                 // the two groups' and the top's
  std::atomic<long> failed_column_;
  std::atomic<bool> pattern_mismatch_{false};
};

}  // namespace

SupernodalFactorisationResult factorize_supernodal(const cholmod_sparse* A, cholmod_factor* L) {
  SupernodalFactorisationResult result;
  if (!A || !L || !L->is_super || !L->is_ll || L->xtype != CHOLMOD_REAL || L->itype != CHOLMOD_LONG || !L->x ||
      L->n == 0 || L->n > static_cast<size_t>(INT_MAX) || A->itype != CHOLMOD_LONG || A->xtype != CHOLMOD_REAL ||
      A->dtype != CHOLMOD_DOUBLE || A->stype >= 0 || A->nrow != L->n || A->ncol != L->n)
    return result;
  try {
    const SupernodalFactorisationResult done = Factorisation(A, L).run();
    if (done.status == SupernodalFactorisationResult::kDone) L->minor = L->n;
    return done;
  } catch (const std::bad_alloc&) {
    result.status = SupernodalFactorisationResult::kOutOfMemory;
    return result;
  }
}

}  // namespace msd
