#pragma once
//! \file AVX2 kernels chosen at run time: the portable build (x86-64 baseline) compiles a frame loop's
//! vector version with MSD_AVX2 and calls it where cpu_has_avx2() says the CPU runs it. The kernels do a
//! scalar loop's operations lane by lane (no fused multiply-add), so results keep every bit.

#include <cstdlib>
#include <cstring>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define MSD_HAVE_AVX2_KERNELS 1
#define MSD_AVX2 __attribute__((target("avx2")))
#else
#define MSD_HAVE_AVX2_KERNELS 0
#define MSD_AVX2
#endif

namespace msd {

//! True where the CPU runs AVX2 code (always false off x86-64 or without GCC's builtins), unless the
//! environment variable MSD_SCALAR_KERNELS is set to anything but "" or "0" (to compare the two, e.g. in
//! the benchmarks).
inline bool cpu_has_avx2() {
#if MSD_HAVE_AVX2_KERNELS
  static const bool has = [] {
    const char* scalar = std::getenv("MSD_SCALAR_KERNELS");
    return __builtin_cpu_supports("avx2") && !(scalar && *scalar && std::strcmp(scalar, "0") != 0);
  }();
  return has;
#else
  return false;
#endif
}

#if MSD_HAVE_AVX2_KERNELS
//! x[index[0..3]] from four scalar loads. AMD's cores run vgatherdpd as microcode: on the development
//! machine's EPYC the gathers made the 1M-vertex normals 11.5 ms, the scalar loads 4.4–5.0 ms.
MSD_AVX2 inline __m256d gather(const double* x, const int* index) {
  return _mm256_set_pd(x[index[3]], x[index[2]], x[index[1]], x[index[0]]);
}

//! (x² + y²) + z² lane by lane: Eigen's squaredNorm() of a 3-vector, in the same order.
MSD_AVX2 inline __m256d square_sum_x4(__m256d x, __m256d y, __m256d z) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x, x), _mm256_mul_pd(y, y)), _mm256_mul_pd(z, z));
}
#endif

}  // namespace msd
