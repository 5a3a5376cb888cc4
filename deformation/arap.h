#pragma once
//! \file As-rigid-as-possible surface modelling (Sorkine & Alexa 2007; seed 9.8): alternate a local step
//! (the best rotation R_i of every vertex's cell) and a global step (the positions that fit those
//! rotations best, one sparse back-substitution), each of which lowers the energy
//!   E(x, R) = Σ_i Σ_(a,b) w_ab |(x_a − x_b) − R_i (p_a − p_b)|²
//! where the inner sum runs over the edges of the cell of vertex i (its spokes, or its spokes and rims).

#include <vector>

#include "msdeform/core/local_frame.h"
#include "msdeform/core/solver.h"
#include "msdeform/deformation/deformer.h"

namespace msd {

//! Which edges make up the rigid cell of a vertex.
enum class ArapEnergy {
  //! The edges (i, j) to the one-ring, weighted with the edge's cotangent weight (cot α + cot β)/2
  //! (Sorkine & Alexa 2007, eq. 3). Default; what the rigidity metric of analysis/metrics.h measures.
  Spokes,
  //! Every edge of the triangles incident to i (spokes and the rims opposite i), each weighted with the
  //! cotangent of its opposite angle in that triangle, cot/2 (Chao et al. 2010; libigl's
  //! ARAP_ENERGY_TYPE_SPOKES_AND_RIMS). Couples neighbouring cells more strongly.
  SpokesAndRims,
};
const char* to_string(ArapEnergy energy);

struct ArapOptions {
  ArapEnergy energy = ArapEnergy::Spokes;
  //! Iterations (one local plus one global step each) per frame at most; >= 1.
  int max_iterations = 1000;
  //! The frame stops when one iteration moves no vertex by more than tolerance × the rest shape's
  //! bounding-box diagonal (in [0, 1]). 0: run exactly max_iterations iterations. A displacement test, not a
  //! relative energy change: on the bent bar (2.5k vertices, plain local/global) the energy changed by
  //! 1.8e-9 per iteration while the shape was still 1.1e-4 diagonals from its converged state.
  double tolerance = 1e-6;
  //! Anderson acceleration of the local/global fixed point (Peng et al. 2018, "Anderson acceleration for
  //! geometry optimization and physics simulation"): the last `anderson` iterates are combined to the
  //! next one, which is kept only when it lowers the energy (else the plain iterate is used and the
  //! history restarts), so the energy still never increases. 0: plain local/global; at most 8.
  int anderson = 5;
  //! Negative (and tiny) cotangent weights make the global matrix indefinite and the energy unbounded
  //! below. Every weight is clamped from below to min_weight_ratio × the median weight magnitude (a
  //! continuous function of the weights, so a weight at 0 ± rounding moves no floor, and one that a few
  //! needles' huge cotangents do not raise), which keeps the matrix SPD on any connected mesh with a
  //! constrained vertex; in (0, 1]. Tiny weights also hold their vertices loosely, which slows the
  //! iteration down: on CGAL's camel (9.8k vertices, a third of the edges obtuse) with two handles, a
  //! floor of 1e-3 needed 1248 iterations, 0.1 needed 85, and the rigidity changed by under 2 % (under 1 %
  //! on the survey files, CGAL's cactus and libigl's knight; measured with the floor's earlier mean).
  double min_weight_ratio = 0.1;
};

//! ARAP deformation. prepare() builds the clamped cotangent weights, factors the global matrix (the
//! cotangent Laplacian −W with the fixed and handle vertices as known rows, ConstrainedQuadratic) once
//! and stores the rest edge vectors of every cell in compact arrays.
//!
//! A frame moves the constrained vertices to their targets and picks the lower-energy start of two:
//! the last frame's result (warm start, or set_initial_guess()) and a cold start, one global step with
//! rotations blended from the handles' (each handle's best rotation of its targets, normalised
//! quaternion blend with the identity by a harmonic weight per handle, computed in prepare()). The cold
//! start reproduces a rigid motion of all constrained vertices at once; after reset() it is the only
//! one. Then the frame iterates: local step (per vertex, in parallel: the cell's cross-covariance A_i,
//! its best rotation, the cell energy), global step (the right-hand side
//! b_i = Σ_j w_ij/2 (R_i + R_j)(p_i − p_j) assembled in parallel, one back-substitution for the three
//! coordinate columns), stopping test on the step, Anderson extrapolation. The returned shape is always
//! a plain global step's result, so the constraints hold exactly. Nothing is allocated inside a frame.
//!
//! The rotations are fitted by at most two Newton steps per local step on tr(Rᵀ A), warm-started from the
//! vertex's rotation of the previous local step (in the spirit of Müller et al. 2016, "A robust method
//! to extract the rotational part of deformations"), so the fits converge along with the positions. A
//! vertex where Newton does not apply (the Hessian not definite) or does not raise tr(Rᵀ A) gets the
//! exact SVD fit (core best_rotation); a fit that would still lower tr(Rᵀ A) keeps the previous
//! rotation, so the energy measured at the local steps never increases.
class ArapDeformer : public Deformer {
 public:
  //! \throw InvalidInput for max_iterations < 1, a tolerance outside [0, 1], anderson outside
  //! [0, 8], or min_weight_ratio not in (0, 1].
  explicit ArapDeformer(ArapOptions options = {});
  const std::string& name() const override { return name_; }
  //! Surface, iterative, exact constraints, per-vertex targets, initial guess, reproduces rigid motions.
  DeformerTraits traits() const override;
  const ArapOptions& options() const { return options_; }
  //! The iteration limit of the next frames (options().max_iterations), changed without preparing again:
  //! msdeform view runs a few iterations per drawn frame while a handle is dragged and many while the mouse
  //! rests. Frames stay allocation-free up to the limit given at prepare(). \throw InvalidInput for < 1.
  void set_max_iterations(int max_iterations);

  //! The energy measured at each local step of the last frame: entry k is E(x_k, R_k+1), x_0 the
  //! initial guess with the constrained vertices at their targets. One entry more than
  //! frame_report().iterations. Non-increasing (to round-off).
  const std::vector<double>& energy_history() const { return energies_; }
  //! Edges whose cotangent weight was clamped (see ArapOptions::min_weight_ratio), of all edges (Spokes)
  //! or of all triangle corners (SpokesAndRims).
  int clamped_weights() const { return clamped_weights_; }
  //! Seconds of the last frame's local steps and global steps (assembly and back-substitution).
  double local_seconds() const { return local_seconds_; }
  double global_seconds() const { return global_seconds_; }

 protected:
  void do_prepare(const Positions& P, const Faces& F, const Region& region) override;
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) override;
  void do_deform_to(const Positions& targets, Positions& out) override;
  void do_set_initial_guess(const Positions& X) override;
  void do_reset() override;

 private:
  double local_step();   // rotations and energy from x_; returns E
  void global_step();    // x_unknown_ from the rotations (not scattered into x_)
  void scatter(const Eigen::VectorXd& u);  // the free vertices of x_ from u (3 columns of #unknown)
  double anderson_step(double energy);     // u_ from the last global step (x_unknown_); returns E at u_
  void run(const Positions& targets, Positions& out);
  void cold_start(const Positions& targets);
  void fit_rotation(long i, const Mat3& A);

  std::string name_ = "arap";
  ArapOptions options_;
  int nv_ = 0;
  Positions rest_, targets_;  // the caller's frame
  LocalFrame local_;          // x_, local_targets_ and every prepared vector are in this frame
  Positions local_targets_;
  std::vector<int> constrained_, handle_of_constrained_, unknown_;
  ConstrainedQuadratic system_;

  // Spokes: compressed rows of the one-rings, w_ij, w_ij (p_i − p_j) (3 per half-edge), and per vertex
  // Σ_j w_ij (p_i − p_j) and Σ_j w_ij |p_i − p_j|².
  std::vector<int> ring_offsets_, ring_;
  std::vector<double> ring_weight_, ring_edge_, cell_sum_;
  // SpokesAndRims: per face its vertices, the clamped weights c_k of the edges opposite its corners k,
  // c_k (p_k+1 − p_k+2) (9), and per corner s_k = Σ over the corner's two edges of c (p_k − p_other) (9);
  // the (3 face + corner) indices around each vertex in compressed rows; per-face work buffers.
  std::vector<int> corner_offsets_, corners_, face_vertex_;
  std::vector<double> face_weight_, face_edge_, face_corner_, face_buffer_, face_dsq_;
  std::vector<double> cell_rest_;  // per vertex: Σ over its cell of w |p_a − p_b|²

  // Iteration state.
  RowPositions x_;                        // current positions, row-major for random access
  std::vector<Mat3> rotation_;            // R_i
  std::vector<Eigen::Vector4d> quaternion_;  // R_i as (x, y, z, w), the warm start of the fit
  std::vector<double> vertex_energy_;
  Eigen::MatrixXd rhs_known_, rhs_, x_unknown_;
  std::vector<double> energies_;
  // Anderson state (all 3·#unknown long, or that many rows): the current iterate u_, the last global
  // step's g and residual g − u, their differences over the last `anderson` iterations (ring buffer),
  // and the normal matrix of the residual differences.
  Eigen::VectorXd u_, g_previous_, f_, f_previous_, warm_;
  Eigen::MatrixXd delta_f_, delta_g_;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 8, 8> normal_;
  int history_ = 0, next_column_ = 0;
  bool has_previous_ = false;
  double diagonal_ = 1;
  Eigen::MatrixXd handle_field_;                   // #V by #handles harmonic weights
  std::vector<Eigen::Vector4d> handle_quaternion_;  // per handle, this frame (x, y, z, w)
  bool cold_ = true;
  bool guess_ = false;  // x_ holds set_initial_guess()'s X (else the last result)
  int clamped_weights_ = 0;
  double local_seconds_ = 0, global_seconds_ = 0;
};

}  // namespace msd
