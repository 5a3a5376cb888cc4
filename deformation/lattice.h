#pragma once
//! \file Lattice-based free-form deformation (seed 9.5.1, Sederberg & Parry 1986, direct manipulation
//! after Hsu et al. 1992): a uniform tensor-product cubic B-spline lattice around the shape,
//!   d(u) = Σ_ijk δc_ijk N_i(u) N_j(v) N_k(w)   (9.12),
//! driven either by its control points (deform_controls) or by handles: the control displacements then
//! solve (9.13) in the least-squares, least-norm sense (SpaceDeformer's solve, with an affine part by
//! default, LeastNormOptions).

#include "msdeform/deformation/space_deformer.h"

namespace msd {

struct LatticeOptions {
  //! Most cells along one axis: (64 + 3)³ control points already take 2.4 MB per coordinate.
  static constexpr int kMaxCells = 64;
  //! Most margin (relative to the bounding-box diagonal).
  static constexpr double kMaxMargin = 10;
  //! Cells of the lattice along x, y, z, each in 1..kMaxCells; (0, 0, 0): fitted to the input's bounding
  //! box, with `cells_longest` (1..kMaxCells) cells along its longest side and as many of the same size
  //! (at least one) along the others.
  Eigen::Vector3i cells = Eigen::Vector3i::Zero();
  int cells_longest = 8;
  //! Space left around the input's bounding box on every side, relative to its diagonal, in 0..kMaxMargin.
  double margin = 0.05;
  LeastNormOptions least_norm;
};

//! Lattice FFD ("lattice"). A lattice of n_x × n_y × n_z cells has (n_x + 3)(n_y + 3)(n_z + 3) control
//! points, placed so that the undeformed lattice is the identity (Greville points: point i of an axis at
//! lo + (i − 1)·h). Each point depends on the 4×4×4 control points of its cell. Outside the lattice a
//! point takes the displacement of the nearest lattice point (the parameters are clamped).
//! The constraints are met in the least-squares sense; the frame report gives the largest distance.
class LatticeDeformer : public SpaceDeformer {
 public:
  //! \throw InvalidInput for a negative cell count, cells_longest < 1, or a margin that is negative or not finite.
  explicit LatticeDeformer(LatticeOptions options = {});
  const std::string& name() const override { return name_; }
  bool has_control_points() const override { return true; }
  //! The control points' rest positions, index i + (n_x + 3)·(j + (n_y + 3)·k).
  Positions control_points() const override;
  //! Cells along x, y, z (after prepare: the fitted ones).
  Eigen::Vector3i cells() const { return cells_; }
  const LatticeOptions& options() const { return options_; }

 protected:
  void fit_basis(const Positions& P, const Region& region) override;
  int basis_size() const override { return (cells_ + Eigen::Vector3i::Constant(3)).prod(); }
  void basis(const Vec3& x, BasisRow& row) const override;
  LeastNormOptions least_norm_options() const override { return options_.least_norm; }
  std::string missed_advice() const override {
    return "constraints with different motions share lattice cells: use more cells "
           "(LatticeOptions::cells_longest: --lattice-cells on the command line, cells in Python), or rbf";
  }
  std::string overshoot_advice() const override {
    return "constraints that conflict within one cell's support are amplified by the least-norm solve: use "
           "more cells (cells_longest: --lattice-cells, cells in Python) so that they fall into different "
           "cells, or rbf";
  }

 private:
  LatticeOptions options_;
  std::string name_ = "lattice";
  Eigen::Vector3i cells_ = Eigen::Vector3i::Ones();
  Vec3 lo_ = Vec3::Zero(), h_ = Vec3::Ones();  // lattice corner and cell size
};

}  // namespace msd
