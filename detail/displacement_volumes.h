#pragma once
//! \file Displacement volumes (seed 9.3.3; Botsch & Kobbelt 2003, "Multiresolution surface representation
//! based on displacement volumes"): each triangle (p_i, p_j, p_k) of S and its base points (b_i, b_j, b_k)
//! on B bound a prism; the prisms' signed volumes are the detail coefficients, and reconstruction finds
//! the detailed surface over a deformed base B' whose prisms have the same volumes.

#include <string>
#include <vector>

#include "msdeform/core/types.h"
#include "msdeform/detail/encoding.h"
#include "msdeform/detail/normal_displacements.h"

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
  //! Relaxation sweeps (one evaluation of every prism each) per reconstruct(); ≥ 0.
  int max_iterations = 50;
  //! Converged when every vertex's equation (below) has a residual of at most this fraction of the
  //! vertex's volume scale max(|W_i|, Ā_i h_ref) (Ā_i its dual-cell area on B, h_ref the RMS encoded
  //! height). With regularization = 0 that is the relative error of the dual-cell volume. ≥ 0.
  double volume_tolerance = 1e-6;
  //! Tikhonov weight λ (dimensionless): vertex i's equation is W_i(h') − W_i + λ Ā_i (h'_i − h_i) = 0, so
  //! the kept volume is biased by about λ |h'_i − h_i| / |h'_i| of itself. The per-vertex system is
  //! square and non-singular without it (see the class comment), so the default is 0. ≥ 0.
  double regularization = 0;
  //! Fold guard: each height stays within this fraction of vertex i's local focal distance on B' — the
  //! height along n'_i at which its normal line crosses the normal line of an S-neighbour j
  //! (‖e‖ / ((n'_i − n'_j)·ê), e = b'_j − b'_i, where the normals converge) — on both sides of B'. Past
  //! it neighbouring displacements cross and the detail surface folds over (seed 9.3.3). Where a volume
  //! would need a height past the bound (a concave bend tighter than the details are tall) the height
  //! stays at the bound and that volume is not met; Report::bounded_heights counts them. Each vertex
  //! takes the tightest bound of its closed one-ring, so that neighbours near a fold share a cap (a
  //! vertex held low beside a free one made the free one rise to make up the volume: rigidity max 27
  //! on bar-bend120 over its faired base, 7.7 with the ring minimum). 0.5 rather than 0.9: 90 → 0
  //! self-intersecting pairs there (normal displacements: 225). > 0; infinity disables the guard.
  double focal_fraction = 0.5;
  //! Trust bound, relative to each vertex's own height scale η_i = max |h_j| over the vertices within
  //! two rings of i in S (encoded heights): |h'_i − h_i| ≤ max_height_change · η_i. A vertex with no
  //! detail around it (η_i = 0: B = S there) keeps h'_i = h_i; no height grows past twice the largest
  //! near it. > 0; infinity disables it.
  double max_height_change = 1.0;
  //! Relaxation factor ω of the l1-Jacobi sweeps (h'_i −= ω F_i / (|J_ii| + Σ_j |J_ij|)). On a flat
  //! base that scaling puts the Jacobian's spectrum in [15/36, 1] for any triangulation, and ω = 1.4
  //! contracts the error by 0.41 per sweep; any ω in (0, 2) converges for a symmetric positive definite
  //! Jacobian. In (0, 2).
  double relaxation = 1.4;
  //! Start each frame from the heights of the previous reconstruct() (when they are closer to the volumes
  //! than the encoded heights are); false: always from the encoded heights.
  bool warm_start = true;
  //! Chebyshev semi-iterative acceleration of the sweeps (Wang 2015; see reconstruct() in the .cpp).
  //! Measured on the bumpy plane (10k): 14 → 10 sweeps for an affine stretch, 10 → 8 for a bend.
  bool chebyshev = true;
  //! Volume window ρ: vertex i's target is its encoded volume W_i, limited to [N_i − ρ/(1+ρ)·|N_i|,
  //! N_i + ρ·|N_i|], N_i the volume the encoded heights (plain normal displacements) give on B'. Within
  //! a factor 1 + ρ of N_i every volume is kept; past it (a base that the edit crushes or stretches, such
  //! as a linear shell under a large rotation) the cell's volume changes by that factor instead. Without
  //! this window the heights cannot reach such volumes smoothly and the solve gains the volume by
  //! wrinkling the detail surface instead (the top of a wrinkled prism is larger). > 0; infinity
  //! disables it.
  double max_volume_change = 0.5;
  //! \throw InvalidInput naming the first option out of its range (above) as DisplacementVolumeOptions::NAME.
  void validate() const;
};

//! Displacement-volume detail encoding ("volumes").
//!
//! encode() runs NormalDisplacements (S over B) for each vertex of S: base point b_i (face of B and
//! barycentrics), Phong normal n_i there and height h_i; q = b + h n is the normal-displacement
//! representation of S (q = p wherever the base-point search converged). S and B may have different
//! connectivity: base points live on B's triangles, the prisms on S's.
//!
//! Detail coefficients: one volume per vertex. The prism of triangle t = (i, j, k) of S over its base
//! points (prism_volume()) is cut along the barycentric dual cells of its corners — the kite of corner i
//! is {w_i ≥ w_j, w_i ≥ w_k} in barycentrics w, extruded through the blended prism. The Jacobian of the
//! blend, m_t · d(w) with m_t as in prism_volume() and d(w) = Σ w_l (q_l − b_l), is linear in w, so the
//! kite's volume is exact in closed form:
//!   V_t,i = m_t · (22 d_i + 7 d_j + 7 d_k) / 216,       V_t,i + V_t,j + V_t,k = V_t,
//! and W_i = Σ_{t ∋ i} V_t,i is the volume of the shell between B and S over vertex i's dual cell. The
//! cells tile the shell, so keeping every W_i keeps every volume at the resolution of one vertex.
//!
//! reconstruct(B') evaluates the base points b'_i and Phong normals n'_i on B' and solves for one height
//! h'_i per vertex (p'_i = b'_i + h'_i n'_i) with W_i(h') = W_i for every vertex: a square system. On a
//! flat base (parallel normals) its Jacobian is Σ_t A_t/108 · [22 7 7; 7 22 7; 7 7 22] assembled over
//! the triangles: symmetric positive definite, within [15/36, 1] of its l1 row sums (|J_ii| + Σ_j
//! |J_ij|) whatever the triangle shapes. It is solved by damped nonlinear l1-Jacobi sweeps
//! (DisplacementVolumeOptions::relaxation), each one pass over the prisms (kite volumes and their
//! derivatives) and one over the vertices: parallel, no matrix, no factorisation. Every height is
//! projected into its bounds (fold guard and trust bound). Anchors (set_anchor_vertices(), e.g. the
//! multi-scale deformer's fixed and handle vertices) keep their encoded heights.
//!
//! Where the edit crushes the base under the detail (a linear shell under a large rotation shrinks cells
//! of the survey's cylinder to 5% of their area and inverts some), the prisms are dominated by their
//! tops: a cell's volume then depends more on its neighbours' heights than on its own (Σ_j |J_ij| >
//! J_ii), the equations admit wrinkled solutions (a wrinkled top holds more volume), and Jacobi cycles.
//! Two guards keep each frame well posed: (1) the targets are limited to a window around the volumes of
//! plain normal displacements on B' (max_volume_change), so a smooth height field can reach them; (2) a
//! vertex's equation gets a regulariser towards its encoded height, λ_i (h'_i − h_i), exactly as strong
//! as needed for diagonal dominance, J_ii + λ_i ≥ 1.2 Σ_j |J_ij| (λ_i = 0 on healthy cells, where J_ii =
//! 22/14 Σ_j |J_ij| on a flat base); Report::regularised_heights counts where it acts. A strictly
//! diagonally dominant linearisation makes the Jacobi iteration contract.
//!
//! Warm start: a frame starts from the previous frame's heights or from the encoded ones, whichever
//! meets the volumes better (one extra sweep); B' = B resets to the encoded heights, which are exact
//! there. B' = B and rigid motions of B keep every volume, so they return S after zero sweeps.
//!
//! What made the previous version (one volume per prism, Levenberg–Marquardt on the least squares) bulge
//! and spike: wherever the volumes cannot all be met — a base that the edit crushes (linear shell under
//! a 120° bend or 135° twist), the concave side held by the fold guard — the solve makes up the missing
//! volume by wrinkling the detail surface: a prism's exact volume grows with the area of its top, so
//! heights alternating between neighbours hold more volume than a smooth field within the same bounds.
//! Per prism this met no resistance: every prism volume A_t (h_i + h_j + h_k)/3 on a flat base is blind
//! to height patterns +a, −a, 0 over the three colour classes of a 3-colourable mesh, the Tikhonov term
//! held those modes by λ² = 1e-6 only, and the trust bound (half the global maximum height H) let a
//! vertex with h ≈ 0 jump by 0.5 H. Measured on bar-bend120 / bar-twist135 over their faired bases:
//! rigidity max 35 / 56 and 1382 / 1496 self-intersecting pairs (normal displacements: 225 / 32). The
//! dual-cell volumes remove the null space, but the wrinkles came back with them on crushed cells
//! (survey cylinder: converged heights alternating 0.05 / 0.35 around h = 0.23) until the volume window,
//! the diagonal-dominance regulariser and the ring-minimum fold guard were added.
//!
//! Measured figures (bench/bench_volumes_survey, bench/bench_encodings; B' = shell of the base):
//!   edit (base)                      frame        sweeps  rigidity mean / max   pairs  (normal displ.)
//!   survey cylinder 4802 (smoothed)  15 ms        15      0.127 / 3.7           36     (0.121 / 4.1, 0)
//!   survey bar 6084 (smoothed)       25 ms        22      0.033 / 1.1            0     (0.025 / 0.31, 0)
//!   bar-bend120 16.5k (faired)       77 ms        20      0.066 / 7.7            0     (0.038 / 0.71, 225)
//!   bar-twist135 16.5k (faired)      53 ms        28      0.079 / 3.4           56     (0.049 / 0.83, 32)
//!   bend120 9.4k (faired)            14 ms        10      0.004 / 0.26           0     (0.001 / 0.04, 0)
//!   twist135 9.4k (faired)           19 ms        16      0.125 / 1.5           10     (0.111 / 1.4, 101)
//! (previous version: 107 / 117 / 1240 / 1948 / 541 / 1850 ms; rigidity max 12.6 / 8.9 / 35 / 56 / 0.56 /
//! 6.0; pairs 48 / 29 / 1382 / 1496 / 0 / 309.) Flat bumpy plane, 100k vertices, bend animated 30° → 120°
//! in 7.5° steps, warm started: 7 sweeps, 62–77 ms per frame with both cores free (123–153 ms CPU time).
//!
//! Degenerate prisms — base triangle (b_i, b_j, b_k) of area at most 1e-10 times the mean area of S's
//! triangles at encode() — have no meaningful volume: they are left out and counted in
//! report().skipped_prisms; a vertex with no other prism keeps its encoded height.
//! Not safe to call concurrently on one object; reconstruct() reuses member buffers.
class DisplacementVolumes : public DetailEncoding {
 public:
  //! What the last reconstruct() did (and, after encode(), the prisms that are skipped). Errors are
  //! per vertex, |F_i(h')| / max(|W_i|, Ā_i h_ref), over the vertices that are neither anchors nor held
  //! at a bound (F_i: the volume equation with its regularisers, against the frame's target, i.e. W_i
  //! limited by max_volume_change).
  struct Report {
    int iterations = 0;             //!< Jacobi sweeps that updated the heights
    double max_relative_error = 0;  //!< at the end
    double rms_relative_error = 0;
    double initial_max_relative_error = 0;  //!< at the start (warm or encoded heights, clipped)
    double initial_rms_relative_error = 0;
    bool warm_started = false;  //!< started from the previous frame's heights
    //! Every counted residual within volume_tolerance (the system is solved; bounded heights aside).
    bool converged = false;
    //! Converged, no height held at a bound, no target limited: every encoded volume kept (up to the
    //! regularisers, 0 on healthy cells).
    bool volumes_within_tolerance = false;
    int skipped_prisms = 0;       //!< degenerate prisms left out (see the class comment)
    int bounded_heights = 0;      //!< heights held at a bound (fold guard or trust bound) at the end
    int limited_volumes = 0;      //!< targets limited by max_volume_change this frame
    int regularised_heights = 0;  //!< heights pulled towards their encoded value at the end (see class)
    double seconds = 0;           //!< wall time of reconstruct()
  };

  explicit DisplacementVolumes(const DisplacementVolumeOptions& options = {},
                               const NormalDisplacementOptions& normal_options = {});

  std::string name() const override { return "volumes"; }
  bool iterative() const override { return true; }
  //! The next reconstruct() starts from the encoded heights (no warm start).
  void reset() override { have_previous_ = false; }
  int last_iterations() const override { return report_.iterations; }
  double last_residual() const override { return report_.max_relative_error; }
  bool last_converged() const override { return report_.converged; }

  //! S: #Vs by 3 with faces Fs (#Fs by 3); B: #Vb by 3 with faces Fb (#Fb by 3); connectivities may differ.
  //! \throw InvalidInput for a face index out of range, a non-finite coordinate, an empty Fs or Fb, an
  //! anchor out of range, an option out of range, or S's bounding-box diagonal outside [1e-50, 1e50] (its
  //! volumes and their squares would leave double's range); as NormalDisplacements::encode().
  void encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) override;

  //! S' (#Vs by 3) over the deformed base B' (#Vb by 3, connectivity Fb). Allocation-free once `out` has
  //! #Vs rows. \throw UsageError before encode() or when B' does not have #Vb rows; InvalidInput if B'
  //! has a non-finite coordinate or the result is not finite.
  void reconstruct(const Positions& B_deformed, Positions& out) override;

  bool encoded() const { return encoded_; }
  const DisplacementVolumeOptions& options() const { return options_; }
  const Report& report() const { return report_; }
  //! #Fs prism volumes V_t (0 for skipped prisms) of the encoding.
  const Eigen::VectorXd& volumes() const { return prism_volume_; }
  //! #Vs dual-cell volumes W_i of the encoding, the kept detail coefficients.
  const Eigen::VectorXd& vertex_volumes() const { return target_; }
  //! #Fs flags: 1 for prisms in the volumes, 0 for skipped (degenerate) ones.
  const std::vector<char>& active_prisms() const { return active_; }
  //! #Vs heights h' of the last reconstruct() (the encoded heights h before the first).
  const Eigen::VectorXd& heights() const { return height_; }
  //! The normal displacements that give the base points, normals and encoded heights.
  const NormalDisplacements& normal_displacements() const { return normal_; }
  std::vector<std::string> encode_warnings() const override { return normal_.encode_warnings(); }

 private:
  void base_frames(const Positions& B);  // frame_ (b and n per vertex) on base B
  void bounds();                         // lower_ and upper_ from frame_
  // One sweep at heights h: corner volumes and derivatives, then per vertex the residual and the clipped
  // Jacobi update into next (h itself if `update` is false). Returns the max and RMS relative residual
  // over counted vertices; held_ marks heights held at a bound.
  void sweep(const Eigen::VectorXd& h, Eigen::VectorXd& next, double& max_error, double& rms_error);
  // corner_volume_ (and corner_derivative_, corner_coupling_) at heights h.
  void corner_pass(const Eigen::VectorXd& h, bool derivatives);
  void gather_volumes(Eigen::VectorXd& volume) const;  // W_i from corner_volume_

  DisplacementVolumeOptions options_;
  NormalDisplacements normal_;
  bool encoded_ = false;
  Faces faces_, base_faces_;
  Positions base_;                  // B of encode(): B' = B resets the warm start
  Eigen::VectorXd encoded_height_;  // h of encode()
  Eigen::VectorXd prism_volume_;    // V_t
  Eigen::VectorXd target_;          // W_i
  Eigen::VectorXd volume_scale_;    // max(|W_i|, Ā_i h_ref); 0 for a vertex without an active prism
  Eigen::VectorXd tikhonov_;        // λ Ā_i
  Eigen::VectorXd damping_;         // Levenberg damping ε_i of vertex i's Gauss–Newton step
  Eigen::VectorXd trust_;           // max_height_change · η_i (may be infinite)
  std::vector<char> active_;        // per prism
  std::vector<char> anchored_;      // per vertex: held at its encoded height
  std::vector<char> placed_row_;    // per vertex: its row of S' written by the caller (placed_vertices())
  // CSR incidence of S: for vertex i, its corners 3t + l (vertex i is corner l of triangle t).
  std::vector<int> incidence_offsets_, incidence_corners_;
  VertexNormals base_normals_;
  bool have_previous_ = false;  // height_ holds the heights of a frame over a deformed base
  Report report_;
  // Per-frame buffers.
  Positions vertex_normals_, b_;
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>
      frame_;  // #Vs rows b'_i, n'_i (gathered per corner)
  Eigen::VectorXd height_, trial_height_, previous_height_, adaptive_, focal_up_, focal_down_, frame_target_,
      cold_volume_, lower_, upper_;
  std::vector<char> held_, regularised_;
  // Per triangle t, 9 values: kite volumes V_t,k, derivatives ∂V_t,k/∂h_k, couplings Σ_l≠k |∂V_t,k/∂h_l|.
  Eigen::VectorXd corner_;
};

}  // namespace msd
