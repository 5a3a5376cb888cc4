#pragma once
//! \file Deformation transfer as a detail encoding (seed 9.3.3; Botsch, Sumner, Pauly & Gross 2006,
//! "Deformation transfer for detail-preserving surface editing", after Sumner & Popović 2004): the
//! deformation B → B' is measured per base triangle as a 3×3 deformation gradient, applied to the
//! corresponding triangles of S, and S' is the surface whose gradients best match (one Poisson solve).

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "msdeform/core/solver.h"
#include "msdeform/core/types.h"
#include "msdeform/detail/encoding.h"
#include "msdeform/detail/normal_displacements.h"

namespace msd {

//! Deformation-transfer detail encoding ("transfer").
//!
//! Deformation gradients (Sumner & Popović 2004, eqs. 1–4): a base triangle (b1, b2, b3) gets the frame
//! V = [b2 − b1, b3 − b1, n / √‖n‖] with n = (b2 − b1) × (b3 − b1) (the fourth, normal-offset vertex
//! b4 = b1 + n / √‖n‖ scales like an edge), and the gradient of B → B' on it is G = V' V⁻¹. V⁻¹ is
//! computed once in encode(). A base triangle that cotan_laplacian() would leave out (degenerate) or clamp
//! (a needle: some |cot| > LaplaceOperator::kMaxCotangent; the rule is triangle_cotangents()) has no frame:
//! its V⁻¹ would amplify the rounding of B' by up to its cotangent, far from the origin into garbage. It
//! borrows the gradient of the nearest usable base triangle (breadth first over shared vertices); see
//! report(). Both tests are ratios, so the choice does not depend on the scale of B.
//!
//! Triangle correspondence S → B: with identical connectivity (#Vs = #Vb and Fs = Fb) triangle t of S
//! takes the gradient of triangle t of B. Otherwise the centroid of each triangle of S is projected
//! onto B along B's Phong normals (the base-point search of NormalDisplacements) and the triangle takes
//! the gradient of the base triangle holding that foot point.
//!
//! Reconstruction (seed Fig. 9.10 form; Botsch et al. 2006 eq. 5): minimise over the positions x of S'
//!   Σ_t A_t ‖∇x|_t − G_t ∇s|_t‖²
//! with A_t, ∇ the areas and piecewise-linear gradient of S. Its normal equations are the Poisson system
//! (−W) x = −D (G ∇S) in msdeform's convention (W = cotan weights of S, D = divergence, D·∇ = W), per
//! triangle Q_t x = G_t Q_t S with Q_t = −W_t. The right-hand side is linear in the G_t: row i is
//! Σ G_t (Q_t S)_k over the corners k of the triangles t at vertex i, with (Q_t S)_k = Σ_m w_km (s_k − s_m)
//! precomputed from edge vectors (independent of where S sits). encode() folds V⁻¹ in: G_t (Q_t S)_k =
//! V'_t u_k with u_k = V_t⁻¹ (Q_t S)_k, and V' u = u0 (b' − a') + u1 (c' − a') + u2 n'/√‖n'‖ is linear in B'
//! but for the scaled normal: a frame computes one scaled normal per base triangle and sums fixed weights
//! of B' and of those normals per row (O(#V), allocation-free). Triangles of S follow cotan_laplacian()'s rule: degenerate ones are left out, and a needle's
//! weight is bounded so that its largest |cot| is kMaxCotangent (all three cotangents scaled together, which
//! keeps Q_t positive semi-definite; clamping them one by one would not). Matrix and right-hand side use the
//! same Q_t, so G = identity gives back S to rounding. The matrix depends on S only: it is factored once
//! in encode() (ConstrainedQuadratic) and each frame back-substitutes three columns, solving for x − c
//! with c the first Dirichlet value so the rounding scales with the mesh, not with its distance from the
//! origin. Translating or scaling S, B and B' together translates or scales S' (to rounding).
//!
//! Dirichlet constraints: the anchor vertices (set_anchor_vertices, e.g. the multi-scale deformer's fixed
//! and handle vertices). Those the caller places (set_placed_vertices: the multi-scale deformer puts them
//! at T_k p before reconstruct()) keep the rows it wrote, so the solve ends at the positions returned
//! there (a placed vertex that is not an anchor is held there too); the others are placed at their
//! normal-displacement reconstruction b'_i + h_i n'_i on B' (= B' exactly where S = B). A connected
//! component of S without an anchor — e.g. all of S when no anchors are given — has its lowest-indexed
//! vertex pinned the same way, so the system is positive definite (report().pinned_vertices). The reconstructed values come from normal_displacements(), encoded to
//! reconstruct only those constrained vertices (its placed vertices are the others), with B' normals only
//! where they read them.
//!
//! Result check: before returning, reconstruct() verifies that every vertex of S' is finite and within
//! 2 × (diagonal of B' ∪ Dirichlet values + diagonal of S ∪ B) of the bounding box of B' ∪ Dirichlet
//! values; otherwise it throws SolverError naming the worst vertex.
//! reconstruct() is O(#Vs + #Vb + #Fs + #Fb) plus the back-substitution, parallel, allocation-free once
//! `out` has #Vs rows. Not safe to call concurrently on one object.
class DeformationTransfer : public DetailEncoding {
 public:
  struct Report {
    bool identical_connectivity = false;  //!< triangle t of S ↔ triangle t of B
    //! Base triangles without a frame (they borrow a neighbour's gradient): degenerate ones, and needles
    //! (not degenerate, some |cot| > LaplaceOperator::kMaxCotangent), by cotan_laplacian()'s rule.
    int degenerate_base_faces = 0;
    int needle_base_faces = 0;
    //! Triangles of S left out of the Poisson system, and S's cotangents beyond kMaxCotangent (whose
    //! triangles' weights were bounded): the same counts as cotan_laplacian(S, Fs).
    int degenerate_faces = 0;
    int clamped_cotangents = 0;
    std::vector<int> pinned_vertices;  //!< vertices pinned because their component had no anchor
    int unreachable_faces = 0;         //!< S triangles left with G = identity (no usable base triangle)
    double factor_seconds = 0;         //!< wall time of encode() (base points, correspondence, factor)
    double seconds = 0;                //!< wall time of the last reconstruct()
  };

  explicit DeformationTransfer(const NormalDisplacementOptions& normal_options = {});

  std::string name() const override { return "transfer"; }

  //! S: #Vs by 3 with faces Fs (#Fs by 3); B: #Vb by 3 with faces Fb (#Fb by 3); connectivities may differ.
  //! \throw InvalidInput for a face or anchor index out of range, a non-finite coordinate or an empty face
  //! list; as NormalDisplacements::encode(); SolverError if the Poisson system cannot be factored.
  void encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) override;

  //! S' (#Vs by 3) for the deformed base B' (#Vb by 3, connectivity Fb), in the units of B'.
  //! \throw UsageError before encode() or when B' does not have #Vb rows; InvalidInput if B' has a
  //! non-finite coordinate, or as NormalDisplacements::reconstruct() if a Dirichlet value overflows;
  //! SolverError (index() = the vertex) if a vertex of S' is not finite or lies beyond the bound above (out
  //! then holds no usable result).
  void reconstruct(const Positions& B_deformed, Positions& out) override;

  bool encoded() const { return encoded_; }
  const Report& report() const { return report_; }
  //! #Fs: the base triangle whose gradient each triangle of S takes.
  const Eigen::VectorXi& source_faces() const { return source_face_; }
  //! The vertices held fixed in the solve (anchors, then pinned vertices), in solve order.
  const std::vector<int>& constrained_vertices() const { return system_.known(); }
  //! The normal displacements of S on B that give the Dirichlet values the caller does not place: they
  //! reconstruct only those constrained vertices (their placed_vertices() are the others).
  const NormalDisplacements& normal_displacements() const { return normal_; }
  //! Newton fallbacks among the constrained vertices the caller does not place (the only base points that
  //! reach S').
  std::vector<std::string> encode_warnings() const override { return normal_.encode_warnings(); }

 private:
  // Measures every row of S' (out; known_values_ + centre: its Dirichlet values, to rounding) against the
  // result bound and throws SolverError naming the worst vertex beyond it or not finite. reconstruct()
  // calls it only when a row failed the bound's quick test as it was written.
  void check_result(const Positions& B_deformed, const Eigen::RowVector3d& centre,
                    const Positions& out) const;

  NormalDisplacements normal_;
  bool encoded_ = false;
  int num_base_vertices_ = 0;
  long num_vertices_ = 0;  // of S
  // Per base face: the face whose frame it uses (itself unless degenerate or a needle).
  Eigen::VectorXi frame_face_;
  Eigen::VectorXi source_face_;      // per S face, already resolved through frame_face_ (−1: identity)
  // Frame slots: slot_corners_[k] are the corners of the base face whose scaled normal ñ' = n'/√‖n'‖ (the
  // third column of its frame V') a frame writes to slot_normal_ row k (the faces the unknown vertices'
  // triangles read, in the order the right-hand side first reads them).
  std::vector<std::array<int, 3>> slot_corners_;
  // The right-hand side of row r of the reduced system (unknown vertex r), f_r = Σ_c V'_s u_c over the
  // corners c of S at that vertex (u_c = V_s⁻¹ q_{t,k} of the source face s of the corner's triangle t),
  // expanded: V' u = u0 (b' − a') + u1 (c' − a') + u2 ñ' is linear in B' but for ñ', so
  //   f_r = Σ_j base_weight (b'_j − b'_ref) + Σ_k normal_weight ñ'_k + q_r,
  // CSR by row with the weights merged per base vertex j and per slot k. The weights of a row sum to zero,
  // so subtracting its first base vertex b'_ref changes nothing but the rounding: each term is an edge
  // vector, as in V' u. q_r sums the corners whose triangle has no base frame (G = I): rare, kept apart.
  std::vector<int> base_offsets_, base_vertex_, normal_offsets_, normal_slot_;
  std::vector<double> base_weight_, normal_weight_;
  std::vector<std::pair<int, Vec3>> identity_rows_;  // (r, q_r) where q_r ≠ 0
  // Row r of the reduced system is row solve_row_[r] of its solver's order (SparseSPDSolver::ordering()).
  std::vector<int> solve_row_;
  // Q(unknown, known) by row r (CSR): coupling_known_ indexes system_.known().
  std::vector<int> coupling_offsets_, coupling_known_;
  std::vector<double> coupling_weight_;
  ConstrainedQuadratic system_;
  double rest_extent_ = 0;  // diagonal of the bounding box of S ∪ B (the result check's detail allowance)
  Report report_;
  // Per-frame buffers.
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> slot_normal_;  // ñ' per frame slot
  Eigen::MatrixXd known_values_;  // rows of system_.known()
  // The right-hand sides, then the solution, of the reduced system in its solver's order (4 per row).
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> ordered_;
};

}  // namespace msd
