#pragma once
//! \file PriMo (Botsch, Pauly, Gross & Kobbelt 2006, "PriMo: Coupled Prisms for Intuitive Surface
//! Modeling"; seed 9.7 and 9.8): the nonlinear reference of the comparison. Every face is extruded into a
//! prism that moves rigidly; neighbouring prisms are coupled by the squared distance of their two copies
//! of the shared side face.

#include <string>
#include <vector>

#include "msdeform/core/solver.h"
#include "msdeform/deformation/deformer.h"

namespace msd {

struct PrimoOptions {
  //! Prism thickness h relative to the mean edge length of the rest mesh: a prism spans p ± (h/2)·n over
  //! its three vertices (n the area-weighted vertex normals). Thicker prisms resist bending more; h → 0
  //! leaves only the membrane (no-gap) coupling. Must be > 0. Measured on CGAL's cactus edit (620
  //! vertices; CGAL's SRE-ARAP: rigidity mean 0.0243, 0 self-intersecting pairs): thickness 0.5 gives
  //! rigidity 0.0288 with 89 self-intersecting face pairs, 1 gives 0.0197 with 43, 1.5 gives 0.0198 with
  //! 0, 2 gives 0.0202 with 0, 4 gives 0.0228 with 0. Thin prisms let the thin arms kink at the handle.
  double thickness = 2.0;
  //! Iteration cap per frame (>= 1).
  int max_iterations = 500;
  //! A frame stops once an iteration moves no prism corner (a prism's copy of one of its face's
  //! vertices) by more than tolerance × the rest mesh's bounding-box diagonal (in [0, 1]), or when no damped
  //! step lowers the energy any more. 0 runs exactly max_iterations iterations. A displacement test
  //! like ARAP's: the relative energy change is round-off near a rigid motion, where E → 0.
  double tolerance = 1e-6;
};

//! PriMo with a local/global optimisation. Unknowns: one rigid motion per prism, x = R_f (q − c_f) + g_f
//! (c_f the rest centroid of face f, g_f its new position). Energy (Botsch et al. 2006, eq. 1–2):
//!   E = Σ_{edges e = f|j} w_e ∫∫_{[0,1]²} |x_f(e, u, v) − x_j(e, u, v)|² du dv,   w_e = |e|² / (A_f + A_j),
//! where x_f(e, ·) is prism f's copy of the bilinear side face over e. The integrand is biquadratic, so a
//! 2×2 Gauss rule is exact: E = Σ_e (w_e / 4) Σ_{m=1..4} |x_f(q_m) − x_j(q_m)|² with q_m the four Gauss
//! points of the rest side face (both prisms share it at rest, so E(rest) = 0).
//! Faces whose three vertices are all fixed or handle vertices are prisms with a fixed rigid motion (the
//! best rigid fit of their rest triangle to its targets); constraints act through these whole faces.
//! Optimisation, instead of the paper's hierarchical shape matching: a damped Newton method on the free
//! prisms' motions, 6 unknowns per face (an infinitesimal rotation ω, applied as exp([ω]×)·R, and a
//! translation δ). Each iteration assembles the exact Hessian (Gauss–Newton's JᵀJ plus the second-order
//! rotation term d·∇²d, which makes the last iterations quadratic where Gauss–Newton crawled: the
//! bar's 135° twist took > 500 iterations with Gauss–Newton, 117 with it); where that matrix is not
//! positive definite it is shifted by μ·diag(JᵀJ) (μ from 1e-3, ×10 per failed factorisation) and, past
//! μ = 1, replaced by Gauss–Newton. The 6#F_free-square matrix keeps its sparsity pattern, so a
//! factorisation is numeric only (the ordering is computed once). A backtracking line search (halving,
//! first trial turning no prism by more than 0.5 rad) accepts a step only if E does not increase, so E
//! never increases.
//! Continuation: when the constrained prisms turn by more than 30° in one frame (a first frame from rest),
//! their motion is applied in stages of at most 30°, each intermediate one solved to a step of 1e-4
//! diagonals (at most max_iterations / (2 · stages) iterations); solved in one go from rest, the 135°
//! twist ends in a folded local minimum. Warm start: the next
//! frame starts from the last one's prisms. The vertices are the mean of the incident prisms' copies of
//! them; constrained vertices are placed exactly.
//! (A LocalFrameDeformer: the damping, energy floor and stage tolerances are absolute numbers.)
class PrimoDeformer : public LocalFrameDeformer {
 public:
  //! \throw InvalidInput for a thickness that is not finite and > 0, max_iterations < 1 or a tolerance
  //! that is negative or not finite.
  explicit PrimoDeformer(PrimoOptions options = {});
  const std::string& name() const override { return name_; }
  //! Surface, iterative, exact constraints, reproduces rigid motions, takes an initial guess (each prism
  //! fitted to the guess's faces), no per-vertex targets.
  DeformerTraits traits() const override;
  const PrimoOptions& options() const { return options_; }
  //! The iteration limit of the next frames (options().max_iterations), changed without preparing again:
  //! msdeform view runs a few iterations per drawn frame while a handle is dragged and many while the mouse
  //! rests. Frames stay allocation-free up to the limit given at prepare(). \throw InvalidInput for < 1.
  void set_max_iterations(int max_iterations);

  //! The energy E after each iteration of the last continuation stage of the last frame (the one with the
  //! target constraints), preceded by the energy it started from; empty before the first frame. Measured
  //! in the shape's normalised frame (centred, bounding-box diagonal 1), like the whole solve, so the
  //! method does not depend on where the shape sits or the units it is modelled in.
  const std::vector<double>& energy_history() const { return energies_; }
  //! Prism thickness in mesh units (thickness × mean edge length), after prepare().
  double prism_height() const { return height_ * local_frame().scale; }

 protected:
  //! \throw TopologyError when no face has all three vertices constrained, or a group of free faces is
  //! not coupled through edges to a constrained face (its rigid motion would be undetermined).
  void prepare_local(const Positions& P, const Faces& F, const Region& region) override;
  void deform_local(const std::vector<Mat4>& transforms, Positions& out) override;
  void set_initial_guess_local(const Positions& X) override;
  void do_reset() override;

 private:
  struct Edge {
    int a, b;      // vertices of the shared edge
    int f, j;      // the two faces
    double w;      // w_e / 4 (the Gauss weight folded in)
  };
  Vec3 gauss_point(const Edge& e, int m) const;
  double energy();
  void prepare_newton();
  // One damped Gauss-Newton step; false when no damping lowers E (E and the state are then kept).
  // step_length: the largest move of a free prism's vertex copies in the accepted step (0 if none).
  bool newton_step(double energy_now, double& energy_after, double& step_length);
  void apply_step(double alpha);  // free prisms: saved motion + alpha × step_; fills move_
  void fit_constrained(const Positions& targets);
  void rest_state();

  std::string name_ = "primo";
  PrimoOptions options_;
  Positions rest_, normals_;
  Faces faces_;
  double height_ = 0;
  double energy_floor_ = 0;
  double diagonal_length_ = 1;  // bounding-box diagonal of the rest mesh
  std::vector<Edge> edges_;
  std::vector<int> face_edge_offsets_, face_edges_;      // CSR: edges of each face
  std::vector<int> vertex_face_offsets_, vertex_faces_;  // CSR: faces of each vertex
  std::vector<int> constrained_faces_, constrained_, constrained_index_, handle_of_;
  std::vector<char> face_is_constrained_;
  std::vector<Vec3> centroids_;
  // State: rotation and position per prism; warm-started between frames.
  std::vector<Mat3> rotation_;
  std::vector<Vec3> position_;
  // Gauss-Newton on the free prisms' rigid motions: 6 unknowns (ω, δ) per free face.
  std::vector<int> free_faces_, free_index_;  // free face list; face → its index in it (−1: constrained)
  SparseMatrix hessian_;                      // lower triangle, fixed pattern
  std::vector<int> diag_entry_, edge_entry_;  // first entry id of each free face's / free edge's block
  std::vector<int> entry_position_;           // entry id → index into hessian_.valuePtr()
  std::vector<double> diagonal_;              // undamped diagonal of the last assembly
  std::vector<Mat3> rotation_block_, second_order_;  // per free face: JᵀJ's ω block, and d·∇²d's
  std::vector<double> move_;                  // per free face: squared largest corner move of the last step
  Eigen::MatrixXd gradient_, step_;
  SparseSPDSolver newton_solver_;
  std::vector<Mat3> saved_rotation_;
  std::vector<Vec3> saved_position_;
  double damping_ = 1e-4;
  // Frame workspace.
  Positions targets_;
  std::vector<Mat3> target_rotation_, start_rotation_;  // constrained faces: target and frame-start motions
  std::vector<Vec3> target_position_, start_position_;
  std::vector<double> chunk_energy_, energies_;
};

}  // namespace msd
