#include "msdeform/core/rotation.h"

#include <algorithm>
#include <cmath>

#include <Eigen/SVD>

namespace msd {

Mat3 best_rotation(const Mat3& covariance) {
  // R = V Uᵀ maximises tr(R C) for C = U Σ Vᵀ; flipping the column of the smallest singular value keeps
  // R a rotation when V Uᵀ would be a reflection.
  const Eigen::JacobiSVD<Mat3> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  Mat3 R = svd.matrixV() * U.transpose();
  if (R.determinant() < 0) {
    U.col(2) = -U.col(2);
    R = svd.matrixV() * U.transpose();
  }
  return R;
}

PolarDecomposition polar_decomposition(const Mat3& A) {
  const Eigen::JacobiSVD<Mat3> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3& U = svd.matrixU();
  const Mat3& V = svd.matrixV();
  Vec3 sigma = svd.singularValues();
  Mat3 flip = Mat3::Identity();
  if ((U * V.transpose()).determinant() < 0) {
    flip(2, 2) = -1;
    sigma[2] = -sigma[2];
  }
  PolarDecomposition out;
  out.rotation = U * flip * V.transpose();
  out.stretch = V * sigma.asDiagonal() * V.transpose();
  return out;
}

double turn_degrees(const Mat3& A) {
  const Mat3 R = polar_decomposition(A).rotation;
  return std::acos(std::clamp((R.trace() - 1) / 2, -1.0, 1.0)) * 180 / 3.14159265358979323846;
}

}  // namespace msd
