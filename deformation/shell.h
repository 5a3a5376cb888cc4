#pragma once
//! \file Shell-based deformation (seed 9.2): minimise the linearised thin-shell energy (9.4) of the
//! displacement, i.e. solve −ks·Δd + kb·Δ²d = 0 (9.5) on the free vertices with the handle and fixed
//! displacements as boundary conditions (9.6, 9.7).

#include "msdeform/core/solver.h"
#include "msdeform/deformation/deformer.h"

namespace msd {

struct ShellOptions {
  //! Stretching stiffness ks (membrane term). Lengths are mesh units: ks and kb trade off as ks·ℓ² : kb
  //! for a feature of size ℓ. ks = 0 (pure bending) is scale-invariant. Only the ratio ks : kb matters, at
  //! any finite magnitude (1e-320 or 1e308 as well): the same bits when both differ by a power of four or
  //! one is zero, the same result to rounding otherwise.
  double ks = 0.0;
  //! Bending stiffness kb (thin-plate term). Fig. 9.4: (1, 0) pure stretching, (0, 1) pure bending,
  //! (1, 10) a mix on the unit plane.
  double kb = 1.0;
};

//! Shell deformation with precomputed basis functions (Botsch & Kobbelt 2004). The system
//!   Q = ks·(−W) + kb·(W M⁻¹ W)        (cotan weights W, mixed-Voronoi mass M; symmetric, SPD on free rows)
//! is factored once. Displacements depend linearly on the handle transforms, so prepare() also solves
//! for 4 basis fields per handle and a frame is p' = p + Σ_k B_k · [A_k − I | t_k]ᵀ, a #V×(4h) by
//! (4h)×3 product: no solve per frame. Constraining all fixed and handle vertices fixes the first two
//! rings around the free region, which gives C¹ continuity there (seed 9.2).
class ShellDeformer : public Deformer {
 public:
  explicit ShellDeformer(ShellOptions options = {});
  const std::string& name() const override { return name_; }
  //! Surface, linear, exact constraints, accepts per-vertex targets; reproduces translations and affine
  //! maps of a plane, not rotations of a curved surface (seed 9.4).
  DeformerTraits traits() const override;
  const ShellOptions& options() const { return options_; }

  //! The same frame as deform(), but by a direct back-substitution instead of the basis: the reference
  //! the basis path is tested against. \throw as deform().
  void deform_by_solve(const std::vector<Mat4>& transforms, Positions& out);
  //! Region::constrained_vertices() of the prepared region, ascending.
  const std::vector<int>& constrained_vertices() const { return constrained_; }

  //! Basis fields: #V by 4h (handle k in columns 4k..4k+3); rows of handle vertices hold (p, 1).
  Eigen::MatrixXd basis() const { return fields_.rightCols(fields_.cols() - 3); }

 protected:
  void do_prepare(const Positions& P, const Faces& F, const Region& region) override;
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) override;
  //! One back-substitution for the displacements targets − rest.
  void do_deform_to(const Positions& targets, Positions& out) override;

 private:
  std::string name_ = "shell";
  ShellOptions options_;
  Positions rest_;
  std::vector<int> constrained_;
  ConstrainedQuadratic system_;
  //! #V by (3 + 4h), column-major: rest positions, then the basis fields of each handle. One stream per
  //! column keeps the frame loop vectorised.
  Eigen::MatrixXd fields_;
  Eigen::Matrix<double, Eigen::Dynamic, 3> frame_matrix_;  // (4h) by 3: stacked [A_k − I | t_k]ᵀ
  std::vector<int> handle_of_;
};

}  // namespace msd
