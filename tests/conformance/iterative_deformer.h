#pragma once
// Test fixture, not a user-facing method: a toy iterative surface method, the harmonic displacement
// field (Δd = 0 on free vertices, cotan Laplacian) solved by conjugate gradients from an initial guess.
// It proves that an iterative method plugs into the seam through this file and one catalogue row: it
// warm-starts from the last frame or set_initial_guess(), starts from rest after reset(), and reports
// its iterations, residual and convergence.

#include <Eigen/IterativeLinearSolvers>

#include "msdeform/core/laplacian.h"
#include "msdeform/deformation/deformer.h"

namespace msd::test {

struct IterativeOptions {
  int max_iterations = 2000;
  double tolerance = 1e-12;  // relative residual
};

class IterativeDeformer : public Deformer {
 public:
  explicit IterativeDeformer(IterativeOptions options = {}) : options_(options) {}
  const std::string& name() const override { return name_; }
  DeformerTraits traits() const override {
    DeformerTraits t;
    t.solve = DeformerSolve::Iterative;
    t.vertex_targets = true;
    t.initial_guess = true;
    t.reproduces_rigid_motions = false;  // harmonic displacements: translations only on a curved surface
    return t;
  }

 protected:
  void do_prepare(const Positions& P, const Faces& F, const Region& region) override {
    rest_ = P;
    constrained_ = region.constrained_vertices();
    free_ = region.free_vertices();
    handle_of_.clear();
    for (int v : constrained_) handle_of_.push_back(region.handle_of(v));
    const SparseMatrix Q = polyharmonic_matrix(cotan_laplacian(P, F), 1);  // −W, SPD on the free block
    Qff_ = submatrix(Q, free_, free_);
    Qfc_ = submatrix(Q, free_, constrained_);
    solver_.setMaxIterations(options_.max_iterations);
    solver_.setTolerance(options_.tolerance);
    solver_.compute(Qff_);
    guess_ = Eigen::MatrixXd::Zero(free_.size(), 3);
  }
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) override {
    affine_targets(rest_, constrained_, handle_of_, transforms, targets_);
    do_deform_to(targets_, out);
  }
  void do_deform_to(const Positions& targets, Positions& out) override {
    Eigen::MatrixXd dc(constrained_.size(), 3);
    for (size_t c = 0; c < constrained_.size(); ++c) dc.row(c) = targets.row(c) - rest_.row(constrained_[c]);
    const Eigen::MatrixXd rhs = -(Qfc_ * dc);
    Eigen::MatrixXd x(free_.size(), 3);
    int iterations = 0;
    double residual = 0;
    bool converged = true;
    for (int d = 0; d < 3; ++d) {
      x.col(d) = solver_.solveWithGuess(rhs.col(d), guess_.col(d));
      iterations = std::max(iterations, static_cast<int>(solver_.iterations()));
      residual = std::max(residual, solver_.error());
      converged = converged && solver_.info() == Eigen::Success;
    }
    guess_ = x;
    out = rest_;
    for (size_t c = 0; c < constrained_.size(); ++c) out.row(constrained_[c]) = targets.row(c);
    for (size_t i = 0; i < free_.size(); ++i) out.row(free_[i]) += x.row(i);
    frame_report_.iterations = iterations;
    frame_report_.residual = residual;
    frame_report_.converged = converged;
  }
  void do_set_initial_guess(const Positions& X) override {
    for (size_t i = 0; i < free_.size(); ++i) guess_.row(i) = X.row(free_[i]) - rest_.row(free_[i]);
  }
  void do_reset() override { guess_.setZero(); }

 private:
  std::string name_ = "test-iterative";
  IterativeOptions options_;
  Positions rest_, targets_;
  std::vector<int> constrained_, free_, handle_of_;
  SparseMatrix Qff_, Qfc_;
  Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper> solver_;
  Eigen::MatrixXd guess_;
};

}  // namespace msd::test
