#pragma once
//! \file Gradient-based editing (seed 9.4.1) with propagation of deformation gradients (9.4.3): each
//! triangle's Jacobian J_T is transformed by a damped copy M_T of the handle's gradient, and the surface
//! whose gradients best match J'_T = M_T J_T is found from the Poisson system (9.10), factored once.

#include <string>
#include <vector>

#include "msdeform/core/solver.h"
#include "msdeform/deformation/deformer.h"
#include "msdeform/deformation/local_transforms.h"

namespace msd {

//! Gradient-based editing (Yu et al. 2004, Zayer et al. 2005; Botsch & Sorkine 2008, §4.1).
//!
//! prepare(): one harmonic field s_k per handle ((9.2): Δs = 0 on the free vertices, 1 on handle k, 0 on
//! the fixed part and the other handles; rows summing above 1 are normalised, as TransformationPropagation
//! does), the per-face mean s_T = (s_i + s_j + s_k)/3, and the Poisson matrix −W = Gᵀ A G (cotan weights,
//! face areas A) factored once with the fixed and handle vertices as known rows.
//!
//! A frame: each handle's linear part A_k = R_k S_k (polar decomposition), per face
//!   M_T = exp(Σ_k s_kT log R_k) · (I + Σ_k s_kT (S_k − I))   (one handle: slerp(I, R, s_T)·(I + s_T(S − I)),
//! see blended_gradient), target Jacobians J'_T = M_T J_T (J_T the rest gradient of the coordinate
//! functions on T), and the minimiser of Σ_T A_T ‖∇p'|_T − J'_T‖² with p' = p on fixed and T_k p on
//! handle vertices: −W p' = Gᵀ A J' on the free rows (9.10), one back-substitution for 3 columns. The
//! right-hand side is assembled per vertex from precomputed corner vectors (O(#F), parallel, no
//! allocation).
//!
//! Translation insensitivity (seed 9.4.3, 9.7): a translation does not change any gradient, so a
//! translated handle gives J' = J and the free region merely interpolates the displacement harmonically
//! (a membrane, C⁰ at the region's boundary), unlike shell's smooth bending.
class GradientEditing : public Deformer {
 public:
  GradientEditing() = default;
  const std::string& name() const override { return name_; }
  //! Surface, linear, exact constraints, affine handles only. Reproduces rigid motions: when every
  //! constrained vertex follows one rigid motion the weights are 1 everywhere, J'_T = R J_T is
  //! integrable and R p + t is the exact minimiser.
  DeformerTraits traits() const override;

  //! #V by h propagation weights (empty before prepare).
  const Eigen::MatrixXd& weights() const { return weights_; }
  //! The target Jacobian of the last frame's face f (after at least one frame): M_T J_T (3x3), for tests and pictures.
  Mat3 target_jacobian(int f) const;
  //! The rest Jacobian J_T of face f (rows: gradients of x, y, z on T; 3x3).
  Mat3 rest_jacobian(int f) const;

 protected:
  //! \throw SolverError naming the vertex when the Poisson system is singular (a free vertex whose faces
  //! all have zero area).
  void do_prepare(const Positions& P, const Faces& F, const Region& region) override;
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) override;

 private:
  std::string name_ = "gradient";
  Positions rest_;
  Vec3 origin_ = Vec3::Zero();  // the rest shape's bounding-box centre; the solve works relative to it
  Faces faces_;
  ConstrainedQuadratic system_;
  KnownRowSolve frame_;
  Eigen::MatrixXd weights_;                               // #V by h
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> face_weights_;  // #F by h, s_T
  Eigen::Matrix<double, Eigen::Dynamic, 9, Eigen::RowMajor> face_transforms_;           // #F by 9, M_T row-major
  // Per unknown vertex u, its corners (T, c) in compressed rows: corner_face_[corner_offsets_[u] ..) and
  // the vector e_{T,c} = A_T J_Tᵀ ∇φ_c, so that (Gᵀ A J')_u = Σ M_T e_{T,c}.
  std::vector<int> corner_offsets_, corner_face_;
  RowPositions corner_vectors_;
  std::vector<int> handle_of_known_;  // handle of each known row (−1 fixed)
  std::vector<HandleGradient> gradients_;
};

}  // namespace msd
