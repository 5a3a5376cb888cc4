#pragma once
//! \file Numeric supernodal Cholesky factorisation on two threads into a CHOLMOD factor (internal, behind
//! SparseSPDSolver).
//!
//! CHOLMOD's supernodal factorisation walks the supernodes one after another and leaves parallelism to
//! the BLAS, which a mesh Laplacian's supernodes are too small to use: measured, it ran on one core (the
//! same time with OPENBLAS_NUM_THREADS=1). This one is the same left-looking algorithm (each supernode
//! gathers the updates of the supernodes below it, then factors its diagonal block and solves the block
//! below; Ng and Peyton 1993), on CHOLMOD's symbolic analysis and storage, with the elimination tree split
//! into two groups of subtrees of about equal work that are factored in parallel. Each thread then sums
//! its group's updates to the supernodes above the split, which are factored last (OpenBLAS may use both
//! cores there). The factor is CHOLMOD's: cholmod_solve and SupernodalSubstitution use it unchanged.

#include "msdeform/core/blas_kernels.h"

struct cholmod_factor_struct;
struct cholmod_sparse_struct;

namespace msd {

struct SupernodalFactorisationResult {
  enum Status { kDone, kNotPositiveDefinite, kPatternMismatch, kOutOfMemory, kNoRoomForBlas, kUnsupported } status =
      kUnsupported;
  long column = -1;  //!< kNotPositiveDefinite: the factor's column whose pivot was not positive
  BlasRoom room;     //!< kNoRoomForBlas: what the address-space limit left when BLAS was to start
};

//! L = chol(P A Pᵀ) into L, a supernodal factor with 64-bit indices from a postordered analysis of A
//! (cholmod_l_analyze with CHOLMOD's default postorder), whose values L already holds (CHOLMOD_REAL, LLᵀ,
//! as cholmod_l_change_factor makes them). A: the lower triangle of a symmetric n×n matrix with the pattern
//! L was analysed for (stype -1, real, 64-bit indices; entries above the diagonal are ignored).
//! Returns kUnsupported for any other factor or matrix (touching nothing); kPatternMismatch for an entry of
//! A outside L's pattern (CHOLMOD's own factorisation drops such entries silently); kNotPositiveDefinite
//! with the first failing column found (after either, L's values are of no use); kOutOfMemory when the
//! workspace does not fit (4 n indices, the permuted A, three update blocks of L->maxcsize entries and the
//! values of the supernodes above the split once more). Calls BLAS from two threads, with OpenBLAS on one
//! thread meanwhile (a process-wide setting, restored after), and lets OpenBLAS use its threads for the
//! supernodes above the split. Under an address-space limit it asks blas_room() once everything else is
//! allocated: with room for one OpenBLAS work buffer only, everything runs on the calling thread with
//! OpenBLAS on one thread; with none it returns kNoRoomForBlas before any BLAS call (OpenBLAS would wait
//! for its buffer forever).
SupernodalFactorisationResult factorize_supernodal(const cholmod_sparse_struct* A, cholmod_factor_struct* L);

}  // namespace msd
