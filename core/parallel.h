#pragma once
//! \file Parallel loops over index ranges (TBB underneath), for per-vertex and per-face kernels.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace msd {

//! Calls body(begin, end) on disjoint chunks covering [0, n), in parallel. Chunks hold at least
//! `grain` indices so small loops stay on one thread.
template <class Body>
void parallel_for_chunks(long n, Body&& body, long grain = 4096) {
  if (n <= grain) {
    if (n > 0) body(0L, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<long>(0, n, grain),
                    [&](const tbb::blocked_range<long>& r) { body(r.begin(), r.end()); });
}

}  // namespace msd
