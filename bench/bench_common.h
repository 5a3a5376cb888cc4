#pragma once
// Timing and argument helpers shared by the benchmarks.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "msdeform/core/blas_kernels.h"
#include "msdeform/core/parallel.h"

namespace msd::bench {

// A bad argument (an unknown size, a mesh too small for a scene) ends a benchmark with the exception's
// message and exit status 2, not with an abort.
inline const bool kExitWithMessage = [] {
  std::set_terminate([] {
    try {
      if (const std::exception_ptr e = std::current_exception()) std::rethrow_exception(e);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
    } catch (...) {
    }
    std::_Exit(2);
  });
  return true;
}();

// CHOLMOD's BLAS on the kernels this CPU allows (core/blas_kernels.h), before main: no thread uses BLAS yet.
inline const std::string kBlasKernels = msd::select_blas_kernels();

using Clock = std::chrono::steady_clock;

inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The resolutions given on the command line (e.g. 100k 1M), or `defaults` when there are none.
inline std::vector<std::string> sizes(int argc, char** argv, std::vector<std::string> defaults) {
  std::vector<std::string> out(argv + 1, argv + argc);
  return out.empty() ? defaults : out;
}

// Milliseconds of each of `frames` calls of frame(f), sorted (front = fastest, middle = median).
template <class Frame>
std::vector<double> time_frames(int frames, Frame&& frame) {
  std::vector<double> ms;
  for (int f = 0; f < frames; ++f) {
    const auto t0 = Clock::now();
    frame(f);
    ms.push_back(ms_since(t0));
  }
  std::sort(ms.begin(), ms.end());
  return ms;
}

// Best of 10 triads over arrays far larger than the caches, counting the three streams (no write-allocate).
inline double triad_gigabytes_per_second() {
  const long n = 64L << 20;
  std::vector<double> a(n), b(n, 1.0), c(n, 2.0);
  msd::parallel_for_chunks(n, [&](long i0, long i1) { std::fill(a.begin() + i0, a.begin() + i1, 0.0); });
  double best = 1e30;
  for (int rep = 0; rep < 10; ++rep) {
    const auto t0 = Clock::now();
    msd::parallel_for_chunks(
        n,
        [&](long i0, long i1) {
          for (long i = i0; i < i1; ++i) a[i] = b[i] + 3.0 * c[i];
        },
        1 << 20);
    best = std::min(best, seconds_since(t0));
  }
  return 3.0 * sizeof(double) * n / best / 1e9;
}

}  // namespace msd::bench
