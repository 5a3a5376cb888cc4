#pragma once
//! \file Triharmonic radial basis functions (seed 9.6; Botsch & Kobbelt 2005): the displacement
//!   d(x) = Σ_j w_j ‖c_j − x‖³ + π(x),   π linear,
//! interpolates the constraints at the centres c_j and minimises the triharmonic fairness energy of the
//! seed among all such maps (Duchon 1977). The centres are the constrained (fixed and handle) vertices,
//! subsampled by farthest-point sampling beyond RbfOptions::max_centres. The dense symmetric system
//! (9.15) with its polynomial block is factored once; affine handle frames then use the precomputed
//! affine basis functions of SpaceDeformer (one 3×4 by 4 product per point and handle, no solve).

#include "msdeform/deformation/space_deformer.h"

namespace msd {

struct RbfOptions {
  //! Most centres: with more constrained vertices, farthest-point sampling picks this many (one seed on
  //! each handle and on the fixed part, then always the vertex farthest from the chosen ones). The
  //! others are then met only approximately (the frame report's constraint_error). Cost: the factorisation
  //! is O(n³) (about 0.1 s for 1000 centres, tens of seconds for 10 000 on two cores), the basis O(#V·n).
  int max_centres = 2000;
  //! Upper bound of max_centres: 20 000 centres take 3.2 GB for the dense factor.
  static constexpr int kMaxCentres = 20000;
};

//! Triharmonic RBF space deformation ("rbf"). The polynomial part spans the directions of the centres'
//! principal axes that they actually extend along, so coplanar or collinear centres keep a solvable
//! system. Centres closer than 1e-9 of the bounding box diagonal to a chosen one are merged.
class RbfDeformer : public SpaceDeformer {
 public:
  //! \throw InvalidInput if max_centres is not in 1..RbfOptions::kMaxCentres.
  explicit RbfDeformer(RbfOptions options = {});
  const std::string& name() const override { return name_; }
  const RbfOptions& options() const { return options_; }
  //! The centres (n×3) and, for each, its index in Region::constrained_vertices(); after prepare.
  const Positions& centres() const { return centres_; }
  const std::vector<int>& centre_constraints() const { return centre_rows_; }

 protected:
  void fit_basis(const Positions& P, const Region& region) override;
  int basis_size() const override { return static_cast<int>(centres_.rows()) + 1 + static_cast<int>(axes_.cols()); }
  void basis(const Vec3& x, BasisRow& row) const override;
  //! Declared inexact: RBF meets a constrained vertex exactly only when it is a centre (all of them up to
  //! max_centres); the frame report's constraint_error gives the distance either way.
  bool exact_constraints() const override { return false; }
  void prepare_solve(const Positions& P, const std::vector<int>& constrained) override;
  void solve(const Eigen::MatrixXd& values, Eigen::MatrixXd& coefficients) const override;
  std::string missed_advice() const override {
    return "the constrained vertices that are not centres are off: raise --max-centres (constrained vertices at "
           "one position with different targets cannot both be met)";
  }
  std::string overshoot_advice() const override {
    return "constraints close together with different motions make the triharmonic map overshoot between and "
           "beyond them: move them apart, or use a surface method";
  }

 private:
  RbfOptions options_;
  std::string name_ = "rbf";
  Positions centres_;            // scaled: (c − origin) / scale
  std::vector<int> centre_rows_;  // constrained-list row of each centre
  std::vector<int> centre_vertices_;  // and its vertex
  Vec3 origin_ = Vec3::Zero();
  double scale_ = 1;
  Eigen::Matrix<double, 3, Eigen::Dynamic> axes_;  // polynomial directions (principal axes the centres span)
  struct Factor;
  std::shared_ptr<Factor> factor_;
};

}  // namespace msd
