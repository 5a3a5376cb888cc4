#include "msdeform/core/supernodal_substitution.h"

#include <algorithm>
#include <climits>
#include <cstdint>
#include <limits>

#include <cholmod.h>
#include <tbb/parallel_invoke.h>

#include "msdeform/core/parallel.h"
#include "msdeform/core/supernodal_tree.h"

namespace msd {
namespace {

using Int = SuiteSparse_long;
// The right-hand sides of one row, padded to 4; aligned(8): rows sit in plain double arrays.
typedef double Row __attribute__((vector_size(32), aligned(8)));

// AVX2 and FMA where the CPU has them, chosen when the library loads; SSE2 elsewhere.
#if defined(__GNUC__) && defined(__x86_64__) && defined(__ELF__) && !defined(__AVX2__)
#define MSD_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define MSD_VECTOR_CLONES
#endif

// Supernode s of L: columns j0 .. j0 + ncol - 1, its first ncol rows are those columns, the other m rows
// (below the diagonal block) are `below`; values column-major with leading dimension ncol + m, read from
// `values` (L's own, or their single-precision copy) at L's offsets.
template <class T>
struct Supernode {
  long j0, ncol, m;
  const Int* below;
  const T* x;
  Supernode(const cholmod_factor* L, long s, const T* values) {
    const Int *super = static_cast<const Int*>(L->super), *pi = static_cast<const Int*>(L->pi);
    j0 = super[s];
    ncol = super[s + 1] - j0;
    m = pi[s + 1] - pi[s] - ncol;
    below = static_cast<const Int*>(L->s) + pi[s] + ncol;
    x = values + static_cast<const Int*>(L->px)[s];
  }
};

// Forward substitution through one supernode: solves its diagonal block for its rows of Y, then subtracts
// the block below times them from the rows below (through top_update where top_slot sends a row there).
// Arithmetic in double whatever the values' type T. Inlined into forward() below, one clone per type.
template <class T>
__attribute__((always_inline)) inline void forward_t(const Supernode<T>& S, Row* __restrict Y,
                                                     Row* __restrict W, const int* top_slot,
                                                     Row* __restrict top_update) {
  const long ld = S.ncol + S.m, m = S.m;
  Row* __restrict y = Y + S.j0;
  for (long j = 0; j < S.ncol; ++j) {
    const T* __restrict a = S.x + j * ld;
    const Row x = y[j] / double(a[j]);
    y[j] = x;
    for (long i = j + 1; i < S.ncol; ++i) y[i] -= double(a[i]) * x;
  }
  if (m == 0) return;
  for (long i = 0; i < m; ++i) W[i] = Row{0, 0, 0, 0};
  long j = 0;
  for (; j + 4 <= S.ncol; j += 4) {  // four columns per pass over W
    const T* __restrict a0 = S.x + j * ld + S.ncol;
    const T* __restrict a1 = a0 + ld, * __restrict a2 = a1 + ld, * __restrict a3 = a2 + ld;
    const Row x0 = y[j], x1 = y[j + 1], x2 = y[j + 2], x3 = y[j + 3];
    for (long i = 0; i < m; ++i)
      W[i] += (double(a0[i]) * x0 + double(a1[i]) * x1) + (double(a2[i]) * x2 + double(a3[i]) * x3);
  }
  for (; j < S.ncol; ++j) {
    const T* __restrict a = S.x + j * ld + S.ncol;
    const Row x = y[j];
    for (long i = 0; i < m; ++i) W[i] += double(a[i]) * x;
  }
  if (!top_slot) {
    for (long i = 0; i < m; ++i) Y[S.below[i]] -= W[i];
    return;
  }
  for (long i = 0; i < m; ++i) {
    const long r = S.below[i];
    const int t = top_slot[r];
    if (t < 0)
      Y[r] -= W[i];
    else
      top_update[t] += W[i];
  }
}

MSD_VECTOR_CLONES void forward(const Supernode<double>& S, Row* __restrict Y, Row* __restrict W,
                               const int* top_slot, Row* __restrict top_update) {
  forward_t(S, Y, W, top_slot, top_update);
}
MSD_VECTOR_CLONES void forward(const Supernode<float>& S, Row* __restrict Y, Row* __restrict W,
                               const int* top_slot, Row* __restrict top_update) {
  forward_t(S, Y, W, top_slot, top_update);
}

// Back substitution through one supernode: subtracts the transposed block below times the (solved) rows
// below from its rows, then solves the transposed diagonal block. Arithmetic in double, as forward_t.
template <class T>
__attribute__((always_inline)) inline void back_t(const Supernode<T>& S, Row* __restrict Y,
                                                  Row* __restrict W) {
  const long ld = S.ncol + S.m, m = S.m;
  Row* __restrict y = Y + S.j0;
  if (m > 0) {
    for (long i = 0; i < m; ++i) W[i] = Y[S.below[i]];
    long j = 0;
    for (; j + 4 <= S.ncol; j += 4) {  // four columns per pass over W, two partial sums each
      const T* __restrict a0 = S.x + j * ld + S.ncol;
      const T* __restrict a1 = a0 + ld, * __restrict a2 = a1 + ld, * __restrict a3 = a2 + ld;
      Row s0{0, 0, 0, 0}, s1 = s0, s2 = s0, s3 = s0, t0 = s0, t1 = s0, t2 = s0, t3 = s0;
      long i = 0;
      for (; i + 2 <= m; i += 2) {
        const Row w = W[i], v = W[i + 1];
        s0 += double(a0[i]) * w, s1 += double(a1[i]) * w, s2 += double(a2[i]) * w, s3 += double(a3[i]) * w;
        t0 += double(a0[i + 1]) * v, t1 += double(a1[i + 1]) * v, t2 += double(a2[i + 1]) * v,
            t3 += double(a3[i + 1]) * v;
      }
      if (i < m)
        s0 += double(a0[i]) * W[i], s1 += double(a1[i]) * W[i], s2 += double(a2[i]) * W[i],
            s3 += double(a3[i]) * W[i];
      y[j] -= s0 + t0, y[j + 1] -= s1 + t1, y[j + 2] -= s2 + t2, y[j + 3] -= s3 + t3;
    }
    for (; j < S.ncol; ++j) {
      const T* __restrict a = S.x + j * ld + S.ncol;
      Row s{0, 0, 0, 0}, t = s;
      long i = 0;
      for (; i + 2 <= m; i += 2) s += double(a[i]) * W[i], t += double(a[i + 1]) * W[i + 1];
      if (i < m) s += double(a[i]) * W[i];
      y[j] -= s + t;
    }
  }
  for (long j = S.ncol - 1; j >= 0; --j) {
    const T* __restrict a = S.x + j * ld;
    Row s = y[j], t{0, 0, 0, 0};
    long i = j + 1;
    for (; i + 2 <= S.ncol; i += 2) s -= double(a[i]) * y[i], t -= double(a[i + 1]) * y[i + 1];
    if (i < S.ncol) s -= double(a[i]) * y[i];
    y[j] = (s + t) / double(a[j]);
  }
}

MSD_VECTOR_CLONES void back(const Supernode<double>& S, Row* __restrict Y, Row* __restrict W) {
  back_t(S, Y, W);
}
MSD_VECTOR_CLONES void back(const Supernode<float>& S, Row* __restrict Y, Row* __restrict W) {
  back_t(S, Y, W);
}

Row* rows(std::vector<double>& v) { return reinterpret_cast<Row*>(v.data()); }

// Streams the factor's values into the cache a fixed distance ahead of the supernodes a thread solves. A
// thread walks its supernodes' values in address order (ascending forward, descending back), but each
// column is first touched at a stride of its leading dimension and the supernodes are short, so the
// hardware prefetcher does not keep up: without this, a 1M lift solve waited on memory for a quarter of
// its time (3 columns, 630k unknowns: 45.6 → 34 ms, cache flushed between solves; 100k: 3.2 → 2.35 ms).
class StreamPrefetch {
 public:
  explicit StreamPrefetch(bool ascending)
      : ascending_(ascending), next_(ascending ? 0 : std::numeric_limits<std::uintptr_t>::max()) {}
  // Prefetches what lies kDistance bytes beyond S's values in the walking direction and was not yet
  // (addresses as integers: the distance may run past the factor's array, which a prefetch tolerates).
  template <class T>
  void before(const Supernode<T>& S) {
    const auto begin = reinterpret_cast<std::uintptr_t>(S.x);
    const auto end = reinterpret_cast<std::uintptr_t>(S.x + S.ncol * (S.ncol + S.m));
    if (ascending_) {
      std::uintptr_t p = std::max(next_, begin) + kDistance;
      for (; p < end + kDistance; p += kLine) __builtin_prefetch(reinterpret_cast<const void*>(p));
      next_ = p - kDistance;
    } else {
      std::uintptr_t p = std::min(next_, end) - kDistance;
      for (; p > begin - kDistance; p -= kLine) __builtin_prefetch(reinterpret_cast<const void*>(p - kLine));
      next_ = p + kDistance;
    }
  }

 private:
  static constexpr std::uintptr_t kDistance = 4096, kLine = 64;  // 2, 4 and 8 KB measured alike
  const bool ascending_;
  std::uintptr_t next_;
};

}  // namespace

void SupernodalSubstitution::clear() {
  L_ = nullptr;
  for (auto* v : {&group_[0], &group_[1], &top_}) v->clear();
  top_slot_.clear();
  num_top_columns_ = 0;
  parallel_share_ = 0;
  for (auto* v : {&y_, &w_[0], &w_[1], &w_[2], &top_update_[0], &top_update_[1]}) std::vector<double>().swap(*v);
  std::vector<float>().swap(values_f_);
}

bool SupernodalSubstitution::plan(const cholmod_factor_struct* factor) {
  clear();
  const cholmod_factor* L = factor;
  if (!L || !L->is_super || L->xtype != CHOLMOD_REAL || L->itype != CHOLMOD_LONG || L->n == 0 ||
      L->n > static_cast<size_t>(INT_MAX))
    return false;
  const long n = static_cast<long>(L->n), ns = static_cast<long>(L->nsuper);
  std::vector<long> super_of, parent;
  if (!supernodal_elimination_tree(L, super_of, parent)) return false;
  std::vector<double> work(ns);  // entries read per supernode
  for (long s = 0; s < ns; ++s) {
    const Supernode<double> S(L, s, static_cast<const double*>(L->x));
    work[s] = static_cast<double>(S.ncol) * static_cast<double>(S.ncol + S.m);
  }
  const std::vector<int> group = split_elimination_tree(parent, work, &parallel_share_);
  top_slot_.assign(n, -1);
  for (long s = 0; s < ns; ++s) {
    if (group[s] < 2) {
      group_[group[s]].push_back(s);
      continue;
    }
    top_.push_back(s);
    const Supernode<double> S(L, s, static_cast<const double*>(L->x));
    for (long j = S.j0; j < S.j0 + S.ncol; ++j) top_slot_[j] = static_cast<int>(num_top_columns_++);
  }
  y_.assign(4 * n, 0.0);
  for (auto& w : w_) w.assign(4 * std::max<size_t>(L->maxesize, 1), 0.0);
  for (auto& t : top_update_) t.assign(4 * std::max<long>(num_top_columns_, 1), 0.0);
  L_ = factor;
  refresh_values();
  return true;
}

void SupernodalSubstitution::set_single_precision(bool on) {
  single_ = on;
  refresh_values();
}

void SupernodalSubstitution::refresh_values() {
  if (!single_ || !L_) {
    std::vector<float>().swap(values_f_);
    return;
  }
  const auto* x = static_cast<const double*>(L_->x);
  const long size = static_cast<const Int*>(L_->px)[L_->nsuper];
  values_f_.resize(size);
  parallel_for_chunks(size, [&](long begin, long end) {
    for (long i = begin; i < end; ++i) values_f_[i] = static_cast<float>(x[i]);
  });
}

const long* SupernodalSubstitution::ordering() const {
  static_assert(sizeof(Int) == sizeof(long), "CHOLMOD's long indices are long");
  return reinterpret_cast<const long*>(L_->Perm);
}

void SupernodalSubstitution::solve(const double* B, double* X, int k) const {
  const long n = static_cast<long>(L_->n);
  const long* perm = ordering();
  Row* Y = rows(y_);
  parallel_for_chunks(n, [&](long begin, long end) {  // Y = Pᵀ B, four to a row
    for (long i = begin; i < end; ++i) {
      Row r{0, 0, 0, 0};
      for (int c = 0; c < k; ++c) r[c] = B[perm[i] + c * n];
      Y[i] = r;
    }
  });
  solve_ordered(y_.data(), k);
  parallel_for_chunks(n, [&](long begin, long end) {  // X = P Y
    for (long i = begin; i < end; ++i)
      for (int c = 0; c < k; ++c) X[perm[i] + c * n] = Y[i][c];
  });
}

void SupernodalSubstitution::solve_ordered(double* Y4, int) const {
  if (single_)
    solve_with(values_f_.data(), Y4);
  else
    solve_with(static_cast<const double*>(L_->x), Y4);
}

template <class T>
void SupernodalSubstitution::solve_with(const T* values, double* Y4) const {
  const cholmod_factor* L = L_;
  Row* Y = reinterpret_cast<Row*>(Y4);
  auto forward_through = [&](const std::vector<long>& supernodes, Row* W, const int* top_slot, Row* top_update) {
    StreamPrefetch prefetch(true);
    for (long s : supernodes) {
      const Supernode<T> S(L, s, values);
      prefetch.before(S);
      forward(S, Y, W, top_slot, top_update);
    }
  };
  // Forward: the two groups in parallel, their updates to top rows collected apart, then the top.
  auto forward_group = [&](int g) {
    std::fill(top_update_[g].begin(), top_update_[g].end(), 0.0);
    forward_through(group_[g], rows(w_[g]), top_slot_.data(), rows(top_update_[g]));
  };
  tbb::parallel_invoke([&] { forward_group(0); }, [&] { forward_group(1); });
  for (long s : top_) {
    const Supernode<T> S(L, s, values);
    for (long j = S.j0; j < S.j0 + S.ncol; ++j) {
      const int t = top_slot_[j];
      Y[j] -= rows(top_update_[0])[t] + rows(top_update_[1])[t];
    }
  }
  forward_through(top_, rows(w_[2]), nullptr, nullptr);
  // Back: the top first, then the two groups in parallel (each reads the top and writes only its rows).
  auto back_through = [&](const std::vector<long>& supernodes, Row* W) {
    StreamPrefetch prefetch(false);
    for (auto s = supernodes.rbegin(); s != supernodes.rend(); ++s) {
      const Supernode<T> S(L, *s, values);
      prefetch.before(S);
      back(S, Y, W);
    }
  };
  back_through(top_, rows(w_[2]));
  auto back_group = [&](int g) { back_through(group_[g], rows(w_[g])); };
  tbb::parallel_invoke([&] { back_group(0); }, [&] { back_group(1); });
}

}  // namespace msd
