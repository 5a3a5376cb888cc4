#pragma once
//! \file Eigen aliases used across msdeform. Bulk data travels as Eigen matrices, one row per element.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>

// msdeform's libraries are built with Eigen's alignment pinned to 16 bytes and Eigen's own aligned
// allocation (core/CMakeLists.txt): types in these headers must have the same layout, and heap blocks the
// same allocator, in the library and in the code that uses it, whatever either's instruction set.
static_assert(EIGEN_MAX_ALIGN_BYTES == 16 && EIGEN_MALLOC_ALREADY_ALIGNED == 0,
              "msdeform: compile with EIGEN_MAX_ALIGN_BYTES=16 and EIGEN_MALLOC_ALREADY_ALIGNED=0, as msdeform's "
              "libraries are (the msdeform:: CMake targets add both; define them before any Eigen header)");

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
