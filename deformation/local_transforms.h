#pragma once
//! \file Shared pieces of the linear differential-coordinate editors (seed 9.4): the propagation of
//! deformation gradients (9.4.3) — each handle's linear part split by polar decomposition and blended
//! with its harmonic weight — and the allocation-free frame solve of a system factored once with the
//! constrained vertices as known rows.

#include <vector>

#include "msdeform/core/region.h"
#include "msdeform/core/solver.h"
#include "msdeform/core/types.h"

namespace msd {

//! One handle's gradient M = A (of T(x) = A x + t) split as A = R·S (core/rotation.h polar_decomposition).
struct HandleGradient {
  Vec3 rotation_vector = Vec3::Zero();          //!< θ·axis of R, θ ∈ [0, π]
  Mat3 stretch_minus_identity = Mat3::Zero();   //!< S − I
};

//! The gradients of the handle transforms (#h 4x4 affine) into out (resized only when the count differs,
//! so a frame with the same handle count allocates nothing).
void handle_gradients(const std::vector<Mat4>& transforms, std::vector<HandleGradient>& out);

//! The damped local transform of a face or vertex with handle weights s[0..h) (each in [0, 1], summing to
//! at most 1), seed 9.4.3:
//!   M = exp(Σ_k s_k · log R_k) · (I + Σ_k s_k (S_k − I)).
//! With one handle this is the seed's slerp(I, R, s)·((1 − s)I + s S): rotation by s·θ about R's axis
//! (the shortest arc), stretch blended linearly. Several handles blend their rotation vectors (log R_k)
//! and stretches with the same weights, so where the weights sum to 1 and all handles share one transform
//! the blend is that transform's linear part exactly (a common rigid motion is reproduced).
Mat3 blended_gradient(const double* s, const std::vector<HandleGradient>& handles);

//! Harmonic propagation weights (seed (9.2), as propagation_field(..., Harmonic) defines them) from an
//! already factored Dirichlet system: system must be ConstrainedQuadratic prepared with Q = −W (cotan)
//! and known = region.constrained_vertices(). #V by h: clamped to [0, 1], exactly 1 on handle k in column
//! k and 0 on fixed vertices and other handles, rows summing above 1 divided by their sum.
Eigen::MatrixXd harmonic_weights(const ConstrainedQuadratic& system, const Region& region);

//! The frame solve of a quadratic ½xᵀQx − xᵀb with known rows, factored once (ConstrainedQuadratic),
//! without heap allocation per frame: Q_uu x_u = b_u − Q_uk x_k. The caller fills known() (|K| by k, rows
//! in ConstrainedQuadratic::known() order) and rhs() (|U| by k, b on the unknown rows, in unknown() order),
//! then calls solve(): rhs() becomes b_u − Q_uk x_k and solution() holds x_u. Q_uk x_k is a parallel
//! row-major product.
class KnownRowSolve {
 public:
  //! Uses system's coupling and factor (system must outlive this object); columns: k right-hand sides.
  void prepare(const ConstrainedQuadratic& system, int columns);
  Eigen::MatrixXd& known() { return known_; }
  Eigen::MatrixXd& rhs() { return rhs_; }
  const Eigen::MatrixXd& solution() const { return xu_; }
  void solve();

 private:
  const ConstrainedQuadratic* system_ = nullptr;
  Eigen::SparseMatrix<double, Eigen::RowMajor> coupling_;  // Q_uk, row-major for a parallel product
  Eigen::MatrixXd known_, rhs_, xu_;
};

}  // namespace msd
