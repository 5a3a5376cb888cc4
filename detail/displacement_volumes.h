#pragma once
//! \file Displacement volumes (seed 9.3.3; Botsch & Kobbelt 2003, "Multiresolution surface representation
//! based on displacement volumes"): each triangle (p_i, p_j, p_k) of S and its base points (b_i, b_j, b_k)
//! on B bound a prism; the prisms' signed volumes are the detail coefficients, and reconstruction finds
//! the detailed surface over a deformed base B' whose prisms have the same volumes.

#include <string>
#include <vector>

#include "core/solver.h"
#include "core/types.h"
#include "detail/encoding.h"
#include "detail/normal_displacements.h"

namespace msd {

//! Signed volume of the prism swept by linear blending between the bottom triangle (a0, a1, a2) and the
//! top triangle (c0, c1, c2): x(u, v, t) = (1 − t) a(u, v) + t c(u, v). Its side walls are the bilinear
//! patches through the edges (a_k, a_l, c_l, c_k), shared exactly by the prisms of neighbouring triangles,
//! so the prisms of a mesh tile the shell between S and its base points without gaps or overlaps, whatever
//! the vertex order (unlike a split into three tetrahedra, whose diagonal choice breaks that symmetry).
//! Closed form:
//!   V = m · (d0 + d1 + d2) / 6,   d_k = c_k − a_k,
//!   m = (2 e1×e2 + e1×f2 + f1×e2 + 2 f1×f2) / 6,   e_l = a_l − a0,  f_l = c_l − c0  (l = 1, 2).
//! Positive when the top lies on the side of the bottom's normal (a1 − a0) × (a2 − a0); A·h for a right
//! prism of base area A and height h, A·h/3 for a tetrahedron (c0 = c1 = c2). Always finite for finite input.
double prism_volume(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& c0, const Vec3& c1,
                    const Vec3& c2);

//! Settings of the displacement-volume reconstruction.
struct DisplacementVolumeOptions {
  //! Levenberg–Marquardt steps (each a numeric refactorisation) per reconstruct().
  int max_iterations = 30;
  //! Stop as soon as every prism's volume error is at most this fraction of the prism's volume scale
  //! (see DisplacementVolumes::Report::max_relative_error).
  double volume_tolerance = 1e-8;
  //! Also stop (converged, "stationary") once an accepted step lowers the least-squares cost by less than
  //! this fraction: there are about twice as many prisms as heights, so the volumes generally cannot all
  //! be met exactly and the solve ends at the least-squares optimum.
  double stationary_tolerance = 1e-6;
  //! Tikhonov weight λ, relative to the mean base-triangle area Ā of the prisms: residual λ·Ā·(h'_i − h_i)
  //! per vertex (an area times a length, like the volume residuals). It fixes the heights' null space (on
  //! a 3-colourable mesh, height patterns +a, −a, 0 over the three colour classes leave every prism
  //! volume unchanged to first order) and keeps heights whose volumes cannot be reached near their
  //! encoded value. ≥ 0.
  double regularization = 1e-3;
  //! Fold guard: while iterating, each height stays within this fraction of vertex i's local focal
  //! distance on B' — the height along n'_i at which its normal line crosses the normal line of an
  //! S-neighbour j (‖e‖ / ((n'_i − n'_j)·ê), e = b'_j − b'_i, where the normals converge) — on both sides
  //! of B'. Beyond it neighbouring displacements cross and the detail surface folds over (seed 9.3.3:
  //! displacement volumes avoid these local self-intersections). Where a volume would need a height past
  //! the bound (a bend tighter than the details are tall) the height stays at the bound and the volume is
  //! not met; Report::bounded_heights counts them. > 0; infinity disables the guard.
  double focal_fraction = 0.9;
  //! Trust bound: each height stays within max_height_change · H of its encoded value, H the largest
  //! |height| of the encoding. Where the volumes cannot be met (shearing twists, tight bends), least
  //! squares otherwise trades many small prism errors for a few heights many times the detail's size
  //! (measured on the bumpy plane's twist135: bump tops at 7× their height). > 0; infinity disables it.
  double max_height_change = 0.5;
  //! Smoothness of the height change δ = h' − h: adds (σĀ)²/2 · Σ_triangles Σ_edges ½ (δ_i − δ_j)² to
  //! the least-squares cost (Ā the mean base-triangle area, so the term scales like the volume
  //! residuals). Where volumes cannot all be met (twists), it damps neighbours pushed up and down
  //! (measured on twist135: self-intersecting pairs 309 → 108 with σ = 0.3), but it also pulls against
  //! legitimate uneven changes (an affine stretch, whose exact answer scales every height by 1/det), so
  //! it is off by default. ≥ 0.
  double smoothness = 0;
  //! Initial Levenberg–Marquardt damping μ (system (H + μ diag H) δ = −g); divided by 10 after an accepted
  //! step, multiplied by 10 after a rejected one. ≥ 0.
  double damping = 1e-6;
};

//! Displacement-volume detail encoding ("volumes").
//!
//! encode() runs NormalDisplacements (S over B) for each vertex of S: base point b_i (face of B and
//! barycentrics), Phong normal n_i there and height h_i. The detail coefficient of triangle t = (i, j, k)
//! of S is V_t = prism_volume(b_i, b_j, b_k, q_i, q_j, q_k) with q = b + h n, the normal-displacement
//! representation of S (q = p for every vertex whose base-point search converged). S and B may have
//! different connectivity: base points live on B's triangles, the prisms on S's.
//!
//! reconstruct(B') evaluates the base points b'_i and Phong normals n'_i on B' (as NormalDisplacements
//! does) and solves for new heights h' with p'_i = b'_i + h'_i n'_i. Regularisation, in two parts:
//! (1) this parameterisation removes the tangential freedom of the vertices (one unknown per vertex, not
//! three); (2) a Tikhonov term λ·Ā·(h'_i − h_i) (see DisplacementVolumeOptions::regularization). The
//! nonlinear least-squares problem
//!   min_h'  Σ_t (V_t(h') − V_t)²  +  (λ Ā)² Σ_i (h'_i − h_i)²
//! (each V_t is a cubic polynomial in the heights of its three vertices) is solved by Levenberg–Marquardt
//! from h' = h, the normal-displacement result: sparse normal equations (JᵀJ + (λĀ)² I + μ diag) δ = −g,
//! whose pattern is S's vertex adjacency, factored once symbolically in encode() and refactored numerically
//! (SparseSPDSolver::refactor) per step. B' = B and rigid motions of B keep every volume, so they return
//! the normal-displacement result after zero steps. Otherwise the heights are kept inside the fold guard
//! (DisplacementVolumeOptions::focal_fraction) by projection: the start h is clipped to the bounds, a
//! height at a bound whose gradient pushes outwards is held fixed for the step (projected Newton), and
//! every trial is clipped. Without the guard, volumes that cannot be reached under a tight concave bend
//! send the solve to far branches of the cubic volume polynomials (heights tens of times the detail's).
//!
//! The solve ends at the least-squares optimum, not at zero residuals: a mesh has about two triangles
//! per vertex, and under bending the two triangles of a quad change volume differently at first order in
//! the edge length, which one height per vertex cannot absorb. The per-prism error at the optimum
//! shrinks with the edge length, and the volume around each vertex (the sum over its triangles) is kept
//! far more closely; report() has the per-prism figures.
//!
//! Degenerate prisms — base triangle (b_i, b_j, b_k) of area at most 1e-10 times the mean area of S's
//! triangles at encode() — have no meaningful volume: they are left out of the residuals and counted in
//! report().skipped_prisms. The volume formula itself has no division, so results stay finite.
//! Not safe to call concurrently on one object; reconstruct() reuses member buffers.
class DisplacementVolumes : public DetailEncoding {
 public:
  //! What the last reconstruct() did (and, after encode(), the prisms that are skipped).
  struct Report {
    int iterations = 0;             //!< accepted Levenberg–Marquardt steps
    int factorizations = 0;         //!< numeric refactorisations (accepted and rejected steps)
    double max_relative_error = 0;  //!< max over prisms of |V_t(h') − V_t| / max(|V_t|, A_t h_ref)
    double rms_relative_error = 0;  //!< root mean square of the same
    //! The same two measures for the start h' = h (plain normal displacements on B').
    double initial_max_relative_error = 0;
    double initial_rms_relative_error = 0;
    //! Stopped by a tolerance: every volume within volume_tolerance, or a stationary point reached.
    bool converged = false;
    bool volumes_within_tolerance = false;  //!< max_relative_error ≤ volume_tolerance
    int skipped_prisms = 0;                 //!< degenerate prisms left out (see the class comment)
    int bounded_heights = 0;  //!< heights held at the fold guard's bound at the end (focal_fraction)
    double seconds = 0;       //!< wall time of reconstruct()
  };

  explicit DisplacementVolumes(const DisplacementVolumeOptions& options = {},
                               const NormalDisplacementOptions& normal_options = {});

  std::string name() const override { return "volumes"; }

  //! S: #Vs by 3 with faces Fs (#Fs by 3); B: #Vb by 3 with faces Fb (#Fb by 3); connectivities may differ.
  //! \throw InvalidInput for a face index out of range, a non-finite coordinate, an empty Fs or Fb, or an
  //! option out of range; as NormalDisplacements::encode(); SolverError if the normal equations cannot be
  //! factored.
  void encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) override;

  //! S' (#Vs by 3) over the deformed base B' (#Vb by 3, connectivity Fb). Allocation-free after the first
  //! call apart from the sparse solver (SparseSPDSolver::refactor copies the matrix it factors).
  //! \throw UsageError before encode() or when B' does not have #Vb rows; InvalidInput if B' has a
  //! non-finite coordinate; SolverError if a refactorisation fails.
  void reconstruct(const Positions& B_deformed, Positions& out) override;

  bool encoded() const { return encoded_; }
  const DisplacementVolumeOptions& options() const { return options_; }
  const Report& report() const { return report_; }
  //! #Fs prism volumes V_t (0 for skipped prisms).
  const Eigen::VectorXd& volumes() const { return volume_; }
  //! #Fs flags: 1 for prisms in the residuals, 0 for skipped (degenerate) ones.
  const std::vector<char>& active_prisms() const { return active_; }
  //! #Vs heights h' of the last reconstruct() (the encoded heights h before the first).
  const Eigen::VectorXd& heights() const { return height_; }
  //! The normal displacements that give the base points, normals and start heights.
  const NormalDisplacements& normal_displacements() const { return normal_; }

 private:
  // Residuals r_t = V_t(h) − V_t and their gradients (#Fs by 3, per corner) for heights h; returns ½Σ r².
  double evaluate(const Eigen::VectorXd& h, Eigen::VectorXd& r, Eigen::MatrixX3d& J) const;
  // Max and RMS relative volume error of residuals r.
  void relative_errors(const Eigen::VectorXd& r, double& max_error, double& rms_error) const;
  // Fills the lower triangle of H = JᵀJ (values only; pattern fixed in encode) and the gradient Jᵀr.
  void assemble(const Eigen::MatrixX3d& J, const Eigen::VectorXd& r);
  void base_frames(const Positions& B);  // b_ and n_ on base B
  void focal_bounds();                   // lower_ and upper_ from b_ and n_

  DisplacementVolumeOptions options_;
  NormalDisplacements normal_;
  bool encoded_ = false;
  Faces faces_, base_faces_;  // Fs and Fb
  int num_base_vertices_ = 0;
  Eigen::VectorXd encoded_height_;  // h of encode(): start and Tikhonov target
  Eigen::VectorXd volume_;          // V_t
  Eigen::VectorXd volume_scale_;    // max(|V_t|, A_t h_ref), 0 for skipped prisms
  std::vector<char> active_;
  double tikhonov_ = 0;        // (λ Ā)²
  double diagonal_floor_ = 0;  // keeps H positive definite for vertices outside every prism
  // CSR incidence of S: for vertex j, the faces around it and, per face, the value index in H_ of each
  // corner's entry (i, j) (−1 where i < j: only the lower triangle is stored).
  std::vector<int> incidence_offsets_, incidence_faces_, incidence_slots_;
  std::vector<int> diagonal_slot_;  // value index of H(j, j)
  SparseMatrix H_;
  Eigen::VectorXd hessian_diagonal_;  // diag(JᵀJ) + (λĀ)², before damping
  SparseSPDSolver solver_;
  VertexNormals base_normals_;
  Report report_;
  // Per-frame buffers.
  Positions vertex_normals_, b_, n_;
  Eigen::VectorXd height_, trial_height_, r_, trial_r_, lower_, upper_;
  std::vector<char> held_;      // heights held at their bound for the current step
  std::vector<char> anchored_;
  double height_scale_ = 0;
  double smoothness_ = 0;  // (σĀ)²  // largest |encoded height|, the unit of max_height_change  // anchor vertices (set_anchor_vertices): heights held at their encoded value
  Eigen::MatrixX3d J_, trial_J_;
  Eigen::MatrixXd gradient_, step_;
};

}  // namespace msd
