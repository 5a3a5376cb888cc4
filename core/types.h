#pragma once
//! \file Eigen aliases used across msdeform. Bulk data travels as Eigen matrices, one row per element.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>

#include "msdeform/config.h"

// Eigen's layout of fixed-size types, its heap allocator and its index type follow the instruction set
// and EIGEN_* defines (cmake/EigenAbi.cmake). Code built with other settings than msdeform's libraries
// would misread the objects it exchanges with them or free their blocks wrongly, so it stops here, at
// the first setting that differs.
#define MSD_ABI_FIX                                                                                        \
  " msdeform's libraries were compiled with " MSD_ABI_FLAGS ". Compile this code with the same -march/-m " \
  "flags and EIGEN_* defines, or rebuild msdeform with yours (-DMSD_NATIVE=ON for -march=native, or "     \
  "-DCMAKE_CXX_FLAGS=...)."
static_assert(EIGEN_MAX_STATIC_ALIGN_BYTES == MSD_EIGEN_MAX_STATIC_ALIGN_BYTES && EIGEN_MAX_ALIGN_BYTES == MSD_EIGEN_MAX_ALIGN_BYTES,
              "msdeform: Eigen's alignment here differs from msdeform's libraries (EIGEN_MAX_STATIC_ALIGN_BYTES, "
              "EIGEN_MAX_ALIGN_BYTES: compare msdeform/config.h)." MSD_ABI_FIX);
static_assert(EIGEN_DEFAULT_ALIGN_BYTES == MSD_EIGEN_DEFAULT_ALIGN_BYTES,
              "msdeform: Eigen's alignment here differs from msdeform's libraries (heap arrays, "
              "EIGEN_DEFAULT_ALIGN_BYTES: compare msdeform/config.h)." MSD_ABI_FIX);
static_assert(EIGEN_MALLOC_ALREADY_ALIGNED == MSD_EIGEN_MALLOC_ALREADY_ALIGNED,
              "msdeform: Eigen's alignment here differs from msdeform's libraries (its allocator, "
              "EIGEN_MALLOC_ALREADY_ALIGNED: compare msdeform/config.h). Under -fsanitize=address Eigen aligns "
              "heap blocks by hand; add -DEIGEN_MALLOC_ALREADY_ALIGNED=1 to match a library built without it."
              MSD_ABI_FIX);
static_assert(sizeof(Eigen::Index) == MSD_EIGEN_INDEX_BYTES,
              "msdeform: Eigen's index type here differs from msdeform's libraries (EIGEN_DEFAULT_DENSE_INDEX_TYPE: "
              "compare msdeform/config.h)." MSD_ABI_FIX);
#undef MSD_ABI_FIX

namespace msd {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;
//! #V by 3 vertex positions (column-major, as Eigen and the solvers like them).
using Positions = Eigen::MatrixX3d;
//! #V by 3 positions stored row by row: for buffers read by random access (one cache line per point).
using RowPositions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
//! #F by 3 vertex indices of triangles, row-major so a face's three indices sit together.
using Faces = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;
using SparseMatrix = Eigen::SparseMatrix<double>;
using Triplet = Eigen::Triplet<double>;

}  // namespace msd
