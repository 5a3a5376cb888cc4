#pragma once
//! \file Eigen aliases used across msdeform. Bulk data travels as Eigen matrices, one row per element.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>

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
