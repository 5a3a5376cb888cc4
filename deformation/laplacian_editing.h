#pragma once
//! \file Laplacian surface editing (seed 9.4.2–9.4.3, eq. (9.11); Sorkine et al. 2004): the deformed
//! surface matches transformed Laplace coordinates δ'_i in the least-squares sense, with the transforms
//! either optimised implicitly as linearised similarities or propagated explicitly from the handles.

#include <string>
#include <vector>

#include "msdeform/core/edge_scale.h"
#include "msdeform/core/solver.h"
#include "msdeform/deformation/deformer.h"
#include "msdeform/deformation/local_transforms.h"

namespace msd {

struct LaplacianEditingOptions {
  //! true: implicit optimisation of a linearised similarity per vertex (Sorkine et al. 2004, (9.11)).
  //! false: the explicit variant δ'_i = M_i δ_i, M_i propagated from the handles by harmonic weights
  //! (9.4.3, blended_gradient), then the bi-Laplacian solve Δ²p' = Δδ'.
  bool implicit = true;
};

//! Laplacian editing with cotangent weights (as Botsch & Sorkine 2008 recommend) and Voronoi-area
//! weights A_i (the mixed-Voronoi mass M of cotan_laplacian). δ = Δp = M⁻¹ W p are the rest Laplace
//! coordinates (#V by 3; 0 at a vertex without area).
//!
//! Implicit (default): minimise (9.11) E(p') = Σ_i A_i ‖T_i(p') δ_i − Δp'_i‖² where
//!   T_i = [[s, −h₃, h₂], [h₃, s, −h₁], [−h₂, h₁, s]]  (plus a translation t_i)
//! is the linearised similarity that best maps the rest one-ring {i} ∪ N(i) onto the unknown one: its
//! 7 parameters (s, h, t) are the least-squares solution (AᵢᵀAᵢ)⁻¹Aᵢᵀ b_i, linear in the unknown ring
//! positions b_i, so T_i δ_i = s δ_i + h × δ_i is linear in p' and (9.11) is a quadratic p'ᵀQp' with Q
//! (3#V by 3#V, the coordinates are coupled) depending only on the rest shape. Q is factored once with the
//! fixed and handle vertices as known rows; a frame is one back-substitution (one column of 3#U values).
//! Linearised rotations: a rotation by θ is approximated by the similarity I + [h]ₓ, i.e. scaled by
//! about √(1 + θ²), so large rotations inflate the details (seed 9.4.3, 9.7).
//!
//! Every frame measures how much the edges at free vertices changed length: exp of the mean |log(ℓ'/ℓ)|.
//! Beyond ×1.25 it is a warning in the frame report: measured on the survey cactus edit (a 70° rotation),
//! the implicit variant inflates the free branch to a one-ring rigidity residual of 6.
//!
//! Explicit: minimise Σ_i A_i ‖Δp'_i − M_i δ_i‖², i.e. (W M⁻¹ W) p' = W δ' on the free rows (the shell
//! matrix Q₂, per coordinate), factored once; M_i as in GradientEditing from per-vertex harmonic weights.
//! Translation-insensitive like gradient editing.
//! (A LocalFrameDeformer: Laplace coordinates of a shape far from the origin would lose their digits to
//! cancellation, and the local similarity fits their rank in tiny units.)
class LaplacianEditing : public LocalFrameDeformer {
 public:
  explicit LaplacianEditing(LaplacianEditingOptions options = {});
  const std::string& name() const override { return name_; }
  //! Surface, linear, exact constraints, affine handles only. Implicit: does not reproduce rotations
  //! (linearised); explicit: reproduces rigid motions (weights 1 everywhere give δ' = R δ, whose exact
  //! solution is R p + t).
  DeformerTraits traits() const override;
  const LaplacianEditingOptions& options() const { return options_; }
  //! Rest Laplace coordinates δ (#V by 3), after prepare.
  const Positions& laplace_coordinates() const { return delta_; }

 protected:
  //! \throw SolverError naming the vertex when the system is singular (e.g. a free vertex whose faces all
  //! have zero area).
  void prepare_local(const Positions& P, const Faces& F, const Region& region) override;
  void deform_local(const std::vector<Mat4>& transforms, Positions& out) override;

 private:
  void prepare_implicit(const Positions& P, const Faces& F, const Region& region);
  void prepare_explicit(const Positions& P, const Faces& F, const Region& region);
  //! Adds a warning to the frame report when the edges around the free vertices changed length by more
  //! than a factor kMaxMeanScale on (geometric) average, growing or shrinking (the linearised rotations'
  //! scaling under large rotations).
  void check_scale(const Positions& out);

  std::string name_ = "laplacian";
  static constexpr double kMaxMeanScale = 1.25;
  LaplacianEditingOptions options_;
  FreeEdgeLengths free_edges_;  // edges with a free end and their rest lengths, for check_scale()
  Positions rest_, delta_;
  ConstrainedQuadratic system_;
  KnownRowSolve frame_;
  std::vector<int> constrained_, handle_of_constrained_;
  // Explicit variant.
  SparseMatrix W_;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> weights_;  // #V by h
  RowPositions target_delta_;                                                         // #V by 3, δ'
  std::vector<HandleGradient> gradients_;
};

}  // namespace msd
