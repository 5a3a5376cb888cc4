#pragma once
// Test fixture, not a user-facing method: a toy space deformation, one trilinear 2×2×2 lattice around
// the shape (free-form deformation of the coarsest kind, seed 9.5). It proves that a space method plugs
// into the seam through this file and one catalogue row: it takes no faces, meets the constraints in
// the least-squares sense (reported in the frame report) and evaluates its map at any point.

#include <array>

#include "msdeform/deformation/deformer.h"

namespace msd::test {

class LatticeDeformer : public Deformer {
 public:
  const std::string& name() const override { return name_; }
  DeformerTraits traits() const override {
    DeformerTraits t;
    t.domain = DeformerDomain::Space;
    t.vertex_targets = true;
    t.exact_constraints = false;
    return t;
  }

 protected:
  // The lattice is the bounding box of P (padded by 1 %); each point has 8 trilinear weights. The 8
  // corner displacements D solve min |A D − d|² + ε|D|² for the constrained rows A of the weights.
  void do_prepare(const Positions& P, const Faces&, const Region& region) override {
    rest_ = P;
    lo_ = P.colwise().minCoeff().transpose();
    const Vec3 hi = P.colwise().maxCoeff().transpose();
    const double diagonal = (hi - lo_).norm() > 0 ? (hi - lo_).norm() : 1.0;
    size_ = ((hi - lo_) * 1.02).cwiseMax(1e-12 * diagonal);  // relative: a shape in 1e-30 units is a shape
    lo_ -= 0.01 * (hi - lo_);
    constrained_ = region.constrained_vertices();
    handle_of_.clear();
    for (int v : constrained_) handle_of_.push_back(region.handle_of(v));
    Eigen::MatrixXd A(constrained_.size(), 8);
    for (size_t c = 0; c < constrained_.size(); ++c) A.row(c) = weights(P.row(constrained_[c]));
    Eigen::Matrix<double, 8, 8> N = A.transpose() * A;
    N.diagonal().array() += 1e-12 * (N.trace() / 8 + 1);
    solve_ = N.ldlt().solve(A.transpose());  // 8 × #C
    targets_.resize(constrained_.size(), 3);
    D_.setZero();
  }
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) override {
    affine_targets(rest_, constrained_, handle_of_, transforms, targets_);
    do_deform_to(targets_, out);
  }
  void do_deform_to(const Positions& targets, Positions& out) override {
    D_.setZero();
    for (Eigen::Index c = 0; c < targets.rows(); ++c)
      for (int k = 0; k < 8; ++k) D_.row(k) += solve_(k, c) * (targets.row(c) - rest_.row(constrained_[c]));
    do_evaluate(rest_, out);
    double error = 0;
    for (Eigen::Index c = 0; c < targets.rows(); ++c)
      error = std::max(error, (out.row(constrained_[c]) - targets.row(c)).norm());
    frame_report_.constraint_error = error;
  }
  void do_reset() override { D_.setZero(); }
  void do_evaluate(const Positions& points, Positions& out) const override {
    for (Eigen::Index i = 0; i < points.rows(); ++i) {
      const Eigen::Matrix<double, 1, 8> w = weights(points.row(i));
      out.row(i) = points.row(i) + w * D_;
    }
  }

 private:
  Eigen::Matrix<double, 1, 8> weights(const Eigen::RowVector3d& p) const {
    const Vec3 t = (p.transpose() - lo_).cwiseQuotient(size_);
    Eigen::Matrix<double, 1, 8> w;
    for (int k = 0; k < 8; ++k)
      w[k] = (k & 1 ? t.x() : 1 - t.x()) * (k & 2 ? t.y() : 1 - t.y()) * (k & 4 ? t.z() : 1 - t.z());
    return w;
  }
  std::string name_ = "test-lattice";
  Positions rest_, targets_;
  Vec3 lo_, size_;
  std::vector<int> constrained_, handle_of_;
  Eigen::Matrix<double, 8, Eigen::Dynamic> solve_;
  Eigen::Matrix<double, 8, 3> D_;
};

}  // namespace msd::test
