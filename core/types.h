#pragma once
//! \file Eigen aliases used across msdeform. Bulk data travels as Eigen matrices, one row per element.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>

#include "msdeform/config.h"

// Eigen's layout of fixed-size types and its heap allocator follow the instruction set and EIGEN_* defines
// (cmake/EigenAbi.cmake). Code built with other settings than msdeform's libraries would misread the
// objects it exchanges with them or free their blocks wrongly, so it stops here instead.
static_assert(EIGEN_MAX_STATIC_ALIGN_BYTES == MSD_EIGEN_MAX_STATIC_ALIGN_BYTES &&
                  EIGEN_MAX_ALIGN_BYTES == MSD_EIGEN_MAX_ALIGN_BYTES &&
                  EIGEN_DEFAULT_ALIGN_BYTES == MSD_EIGEN_DEFAULT_ALIGN_BYTES &&
                  EIGEN_MALLOC_ALREADY_ALIGNED == MSD_EIGEN_MALLOC_ALREADY_ALIGNED,
              "msdeform: Eigen's alignment here differs from msdeform's libraries, which were compiled with "
              MSD_ABI_FLAGS ". Compile this code with the same -march/-m flags and EIGEN_* defines, or rebuild "
              "msdeform with yours (-DMSD_NATIVE=ON for -march=native, or -DCMAKE_CXX_FLAGS=...).");

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
