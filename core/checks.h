#pragma once
//! \file The input checks of bulk arrays, one definition for every module: each names what is wrong and
//! where (vertex or face id), so no method has to repeat them.

#include "msdeform/core/types.h"

namespace msd {

//! Whether the n doubles at x are all finite (no NaN or infinity); one thread, branch-free. For a pass that
//! checks what it has just written while it is still in the cache.
bool all_finite(const double* x, long n);
//! The first row of X (#V by 3) with a NaN or infinite coordinate, or -1 when all are finite. One pass
//! over the three columns on both cores (a frame's output check: 1M rows in about 1 ms).
long first_non_finite_row(const Positions& X);
//! \throw InvalidInput "<who>: vertex v of <what> has a non-finite coordinate" for the first such row of X.
void check_finite(const Positions& X, const char* who, const char* what);
//! \throw InvalidInput "<who>: face f of <what> has vertex index i out of range [0, n)" for the first such face.
void check_faces(const Faces& F, Eigen::Index num_vertices, const char* who, const char* what);
//! Both for a mesh (P #V×3, F #F×3), the indices first: \throw InvalidInput, prefixed with `who`, naming
//! the face with an index outside [0, #V) or the vertex with a non-finite coordinate.
void check_mesh_arrays(const Positions& P, const Faces& F, const char* who);

}  // namespace msd
