#pragma once
//! \file The BLAS kernels behind CHOLMOD's supernodal factorisation, which spends most of its time in BLAS
//! (dgemm, dsyrk, dtrsm).
//!
//! OpenBLAS before 0.3.25 (Debian 12 ships 0.3.21) chooses its kernels by CPU model number and, on a model
//! it does not know (Sapphire and Emerald Rapids, recent client CPUs, many virtual machines), falls back to
//! its Prescott (SSE3) kernels whatever the CPU supports (OpenBLAS issue #4267, fixed by PR #4268).
//! Measured on a Xeon of model 207 with AVX-512: the 1M-vertex lift bi-Laplacian factors in 4.7-5.6 s with
//! the SkylakeX kernels and in 8.2-8.4 s with Prescott's.

#include <string>

namespace msd {

//! Where OpenBLAS (CHOLMOD's BLAS in this process) fell back to its Prescott kernels, reruns OpenBLAS's own
//! kernel selection with the kernels the CPU's features allow: SkylakeX with AVX-512 (F, CD, BW, DQ, VL),
//! Haswell with AVX2 and FMA (the path OPENBLAS_CORETYPE takes when the library loads). Does nothing when
//! OPENBLAS_CORETYPE is set (the user's choice), when CHOLMOD's BLAS is not OpenBLAS, or on a CPU without
//! AVX2. Returns blas_kernels() after the call.
//!
//! Process-wide: every user of that OpenBLAS (numpy too) gets the new kernels, whose results differ from
//! the old ones by rounding. Call it at program start, before any thread uses BLAS: a BLAS call running
//! in another thread while the kernels change can return garbage or hang. The msdeform tool and the
//! benchmarks call it first thing; the library never calls it on its own. Safe to call more than once.
std::string select_blas_kernels();

//! The OpenBLAS kernels CHOLMOD's BLAS calls run on (e.g. "SkylakeX", "Prescott"), or "" when that BLAS
//! is not OpenBLAS.
std::string blas_kernels();

//! How many threads may call BLAS at once within the process's address-space limit (RLIMIT_AS, ulimit -v).
//! OpenBLAS (0.3.21) gives each thread that calls it, its own worker threads included, a work buffer
//! (128 MB of address space on x86-64) and retries that allocation forever when it fails: under a tight
//! limit the first BLAS call hangs. Measured: a shell prepare of the 10k lift hung below 700 MB.
struct BlasRoom {
  //! 2 without a limit (or with another BLAS), or with 512 MB or more left; 1 with room for one buffer,
  //! or when an earlier call found its buffer (OpenBLAS keeps it for the next); 0: a call would hang.
  int threads = 2;
  double left_mb = 0;   //!< address space left under the limit, MB (0 without a limit)
  double limit_mb = 0;  //!< the limit, MB (0: none)
};
BlasRoom blas_room();
//! Tells blas_room() that a BLAS call on one thread finished (OpenBLAS then holds a buffer to reuse).
void blas_call_finished();
//! "who: the address-space limit (ulimit -v) of L MB leaves M MB, and `what` needs N MB: raise the limit to
//! at least K MB": why an allocation of need_mb would not fit under the limit, and what to change.
std::string address_space_message(const BlasRoom& room, const char* who, const std::string& what,
                                  double need_mb);
//! address_space_message for BLAS's work buffer: why `who` cannot call BLAS (room.threads 0).
std::string no_room_for_blas_message(const BlasRoom& room, const char* who);

//! OpenBLAS on one thread for the lifetime of the object (its own threads would share themselves between
//! several callers, spinning, and each needs a work buffer); restores the count on destruction. Does
//! nothing with another BLAS.
class OneBlasThread {
 public:
  OneBlasThread();
  ~OneBlasThread();
  OneBlasThread(const OneBlasThread&) = delete;
  OneBlasThread& operator=(const OneBlasThread&) = delete;

 private:
  int saved_ = 0;
};

}  // namespace msd
