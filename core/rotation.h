#pragma once
//! \file Rotation fitting, shared by the methods and the metrics: the best rotation of a weighted
//! cross-covariance (Kabsch / orthogonal Procrustes, the local step of ARAP) and the polar decomposition
//! of a linear map with a proper rotation factor.

#include "msdeform/core/types.h"

namespace msd {

//! The rotation R (det R = +1) that maximises tr(R·C) for a 3x3 cross-covariance C = Σ_j w_j e_j e'_jᵀ,
//! i.e. minimises Σ_j w_j |e'_j − R e_j|² (Kabsch 1976; Sorkine & Alexa 2007, eq. 6). With the SVD
//! C = U Σ Vᵀ, R = V Uᵀ; when that is a reflection the column of U of the smallest singular value is
//! negated, giving the nearest rotation. A rank-deficient C (collinear or planar edges) still yields a
//! rotation, one of the optimal ones.
Mat3 best_rotation(const Mat3& covariance);

//! A = R·S with R a rotation (det R = +1) and S symmetric.
struct PolarDecomposition {
  Mat3 rotation;  //!< R
  Mat3 stretch;   //!< S = Rᵀ A, symmetric; for det A < 0 it keeps the negative eigenvalue (a reflection)
};

//! Polar decomposition of a 3x3 linear map from its SVD A = U Σ Vᵀ: R = U D Vᵀ, S = V D Σ Vᵀ, with
//! D = diag(1, 1, ±1) so that det R = +1 (Σ is sorted decreasingly, so the flipped direction is the one of
//! the smallest singular value). A singular A still gives a rotation R and R·S = A.
PolarDecomposition polar_decomposition(const Mat3& A);

//! The angle of A's polar rotation, in degrees in [0, 180] (scale and shear left out): how far a handle
//! transform turns the handle from rest, up to whole turns (a matrix cannot tell 200° from −160°).
double turn_degrees(const Mat3& A);

}  // namespace msd
