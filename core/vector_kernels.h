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

//! a · b lane by lane in the order of Eigen's dot() of 3-vectors: (a_x b_x + a_y b_y) + a_z b_z.
MSD_AVX2 inline __m256d dot_x4(__m256d ax, __m256d ay, __m256d az, __m256d bx, __m256d by, __m256d bz) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(ax, bx), _mm256_mul_pd(ay, by)), _mm256_mul_pd(az, bz));
}

//! c = a × b lane by lane, as Eigen's cross(): (a_y b_z − a_z b_y, a_z b_x − a_x b_z, a_x b_y − a_y b_x).
MSD_AVX2 inline void cross_x4(__m256d ax, __m256d ay, __m256d az, __m256d bx, __m256d by, __m256d bz,
                              __m256d& cx, __m256d& cy, __m256d& cz) {
  cx = _mm256_sub_pd(_mm256_mul_pd(ay, bz), _mm256_mul_pd(az, by));
  cy = _mm256_sub_pd(_mm256_mul_pd(az, bx), _mm256_mul_pd(ax, bz));
  cz = _mm256_sub_pd(_mm256_mul_pd(ax, by), _mm256_mul_pd(ay, bx));
}

//! Transposes the 4×4 block whose rows are r0..r3: afterwards r_j holds element j of each former row (a
//! record of four doubles per lane, e.g. (x, y, z, w) of four points, becomes one vector per field).
MSD_AVX2 inline void transpose_x4(__m256d& r0, __m256d& r1, __m256d& r2, __m256d& r3) {
  const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);
  const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
  r0 = _mm256_permute2f128_pd(t0, t2, 0x20), r1 = _mm256_permute2f128_pd(t1, t3, 0x20);
  r2 = _mm256_permute2f128_pd(t0, t2, 0x31), r3 = _mm256_permute2f128_pd(t1, t3, 0x31);
}
#endif

}  // namespace msd
