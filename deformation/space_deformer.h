#pragma once
//! \file Space deformations (seed 9.5–9.6) as one linear family: the displacement of any point x is
//!   d(x) = Σ_l δc_l ψ_l(x),   l = 1..m,
//! with the method's basis functions ψ_l (a lattice's tensor-product B-splines, a cage's generalised
//! barycentric coordinates, or triharmonic kernels plus a linear polynomial) and coefficients δc (m×3)
//! that depend linearly on the constraints d(p_i) = d̄_i at the fixed and handle vertices. Because the
//! map from constraints to coefficients is linear, an affine frame is a fixed linear map of the handle
//! transforms: prepare() precomputes per point and handle four numbers b_k(p) (the affine basis
//! functions of Botsch & Kobbelt 2005), and a frame is
//!   p' = p + Σ_k (T_k − I)₃ₓ₄ · b_k(p),
//! 12 multiply-adds per point and handle, no solve and no allocation. Everything here needs neither
//! faces nor a manifold: point clouds, polygon soups and multi-component meshes deform alike.

#include <memory>
#include <string>
#include <vector>

#include "msdeform/deformation/deformer.h"

namespace msd {

//! One point's basis values ψ_l(x) as (index, value) pairs: sparse (a lattice's 64) or dense (a cage's m).
struct BasisRow {
  std::vector<int> index;
  std::vector<double> value;
  void clear() {
    index.clear();
    value.clear();
  }
  void add(int l, double w) {
    index.push_back(l);
    value.push_back(w);
  }
};

//! How the free-form methods (lattice, cage) turn constraints into control displacements (seed eq. 9.13).
struct LeastNormOptions {
  //! true (default): first fit the affine map that best matches the constraints (least squares), move
  //! every control point by it, and solve (9.13) for the least-norm correction of what remains. Affine
  //! edits (a translated or rotated whole) are then reproduced exactly everywhere, and free regions far
  //! from any constraint follow the edit's affine trend. false: the seed's (9.13) alone, where control
  //! points that no constraint sees stay put (not even a translation is reproduced away from the constraints).
  bool affine_part = true;
  //! Tikhonov weight of the pseudo-inverse, relative to the mean diagonal of NᵀN (N: the #C×m basis
  //! matrix of (9.13)): (NᵀN + ε·mean·I)⁻¹Nᵀ. Directions the constraints barely see stay still instead of
  //! being blown up: the gain from a constraint to a control point is at most 1/(2√(ε·mean)). 1e-6 meets
  //! the survey benchmark's constraints to about 1e-5 of the bounding-box diagonal; smaller values meet
  //! them more closely but amplify constraints that conflict within one basis function's support (a
  //! frame warns when some point then moves more than twice as far as any target).
  double regularization = 1e-6;
  //! \throw InvalidInput, prefixed with who, unless regularization is positive and finite.
  void validate(const std::string& who) const;
};

//! Base of the space methods. Subclasses define the basis functions (fit_basis, basis) and, unless the
//! least-norm solve of (9.13) is what they want, the constraint solve (prepare_solve, solve).
//! Frames (deform) are O(#V·#handles), parallel and allocation-free; deform_to() and deform_controls()
//! evaluate the basis at every point (O(#V·basis size), cached when it fits: set_basis_cache_bytes()).
class SpaceDeformer : public Deformer {
 public:
  //! Space domain, linear, per-vertex targets; exact_constraints as the subclass says (exact_constraints()).
  DeformerTraits traits() const override;

  //! m: the number of basis functions (lattice control points, cage vertices, RBF centres + 4).
  int num_coefficients() const { return static_cast<int>(coefficients_.rows()); }
  //! The coefficients δc of the current map (m×3): zero at rest; after an affine frame, deform_to() or
  //! deform_controls(), the ones that frame used.
  const Eigen::MatrixX3d& coefficients() const { return coefficients_; }

  //! Whether the coefficients are control-point displacements (lattice, cage: true; RBF weights: false).
  virtual bool has_control_points() const { return false; }
  //! Rest positions of the control points (m×3; lattice points or cage vertices, linear precision: a
  //! point x = Σ_l c_l ψ_l(x)). \throw UsageError before prepare or for a method without control points.
  virtual Positions control_points() const;
  //! Triangles over the control points for pictures and files (a cage's faces); none for a lattice (#F×3).
  virtual Faces control_faces() const { return Faces(0, 3); }
  //! Control-point editing (seed 9.5): moves control point l by displacements(l) (m×3) and writes the
  //! deformed prepared points (#V×3) into out. Constraints are neither enforced nor measured (the frame
  //! report's constraint_error stays −1).
  //! \throw UsageError without control points, before prepare or for a wrong shape; InvalidInput for a
  //! non-finite displacement.
  void deform_controls(const Eigen::MatrixX3d& displacements, Positions& out);

  //! The memory allowed for caching the basis of the prepared points (methods with control points:
  //! prepare, deform_to, deform_controls); above it those frames re-evaluate the basis (and prepare()
  //! evaluates it twice at the constrained vertices). Set before prepare(). Default 1 GB: a lattice (64
  //! values per point, 12 bytes each) up to 1.4M points, a cage of 186 vertices (8 bytes per value) up to
  //! 720k points.
  void set_basis_cache_bytes(size_t bytes) { basis_cache_bytes_ = bytes; }

 protected:
  //! Sets up the basis for points P (#V×3) and the region: the lattice box, the cage's coordinates, the
  //! RBF centres. The arrays and region are already checked. \throw InvalidInput / SolverError.
  virtual void fit_basis(const Positions& P, const Region& region) = 0;
  //! m, once fit_basis() ran.
  virtual int basis_size() const = 0;
  //! ψ_l(x) into row (cleared first). Thread-safe: called from parallel loops with one row per thread.
  virtual void basis(const Vec3& x, BasisRow& row) const = 0;
  //! Whether every frame meets the constraints exactly (to round-off).
  virtual bool exact_constraints() const { return false; }
  //! Factors the map from constraint values to coefficients, for the constrained vertices `constrained`
  //! of P. Default: the least-norm solve of (9.13) with the options of least_norm_options().
  virtual void prepare_solve(const Positions& P, const std::vector<int>& constrained);
  //! Applies that map: values #C×k (one row per constrained vertex, in Region::constrained_vertices()
  //! order) to coefficients m×k. Linear in values.
  virtual void solve(const Eigen::MatrixXd& values, Eigen::MatrixXd& coefficients) const;
  //! What to change when a frame moves some point more than twice as far as any constraint target
  //! (the linear solve amplified conflicting constraints); appended to that frame's warning.
  virtual std::string overshoot_advice() const;
  //! What to change when a frame leaves a constrained vertex more than 5 % of the bounding-box diagonal
  //! from its target; appended to that frame's warning.
  virtual std::string missed_advice() const;
  //! ψ(p_v) of vertex v of the points being prepared (P, as given to prepare_solve), from the cache when
  //! the basis of every point fits in memory, else evaluated.
  void prepared_basis(const Positions& P, long v, BasisRow& row) const;
  //! Options of the default least-norm solve.
  virtual LeastNormOptions least_norm_options() const { return {}; }

  void do_prepare(const Positions& P, const Faces& F, const Region& region) final;
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) final;
  void do_deform_to(const Positions& targets, Positions& out) final;
  void do_reset() final;
  void do_evaluate(const Positions& points, Positions& out) const final;

 private:
  // out = rest + Σ_l coefficients_(l) ψ_l(rest) at the prepared points (cached basis when present).
  void apply_coefficients(Positions& out) const;
  // Sets the frame report's constraint_error and the largest target displacement.
  void measure_constraints(const Positions& out, const Positions* targets, const std::vector<Mat4>* transforms);
  // Warns when largest_move exceeds twice the largest target displacement.
  void check_overshoot(double largest_move);

  Positions rest_;
  double rest_diagonal_ = 0, largest_target_move_ = 0;
  Vec3 origin_ = Vec3::Zero();  // centre of the rest bounding box: the affine basis is relative to it
  std::vector<int> constrained_, handle_of_;
  int num_handles_ = 0;
  //! G (m × 4K): coefficients of handle k's affine basis: columns 4k..4k+3 are the solve of the data
  //! (x, y, z, 1) − (origin_, 0) on handle k's vertices, 0 elsewhere.
  Eigen::MatrixXd handle_coefficients_;
  //! b (#V × 4K, column-major for frames that vectorise across points): the affine basis functions at
  //! the prepared points, b = Ψ(P) G.
  Eigen::MatrixXd point_basis_;
  Eigen::MatrixX3d coefficients_;
  std::vector<double> frame_matrices_;  // K × 12: per frame, T_k − I relative to origin_, row-major 3×4
  // Least-norm solve: N (#C×m, row-major sparse) and the Cholesky factor of NᵀN + εI; affine fit.
  struct LeastNorm;
  std::shared_ptr<LeastNorm> least_norm_;
  // Cached basis of the prepared points (cache_width_ values per point; 0: not cached).
  size_t cache_width_ = 0;
  bool cache_dense_ = false;  // rows are ψ_0 .. ψ_{m−1}: indices not stored
  Eigen::VectorXi cache_index_;  // Eigen vectors: sized without being filled, then written in parallel
  Eigen::VectorXd cache_value_;
  size_t basis_cache_bytes_ = size_t(1) << 30;
};

}  // namespace msd
