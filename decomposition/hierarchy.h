#pragma once
//! \file Multi-level decomposition (seed 9.3): a hierarchy S = S₀, S₁, …, S_k = B of surfaces with one
//! connectivity and decreasing geometric complexity. The detail lost from S_i to S_{i+1} is
//! D_{i+1} = S_i ⊖ S_{i+1}, and after editing the base B → B' the surface is rebuilt as
//! S' = B' ⊕ D_k ⊕ … ⊕ D_1.
//!
//! This module only holds the levels. Real detail encodings (local frames, normal displacements, …) are
//! in detail/, and reconstruction/ chains them over the levels through num_levels() / level(i) / base().
//! As a simple fallback the hierarchy offers global-coordinate differences D_i = S_{i−1} − S_i, whose sum
//! rebuilds S exactly from B but does not rotate with the edit (seed Fig. 9.8, left).

#include <vector>

#include "msdeform/core/region.h"
#include "msdeform/core/types.h"
#include "msdeform/decomposition/fairing.h"
#include "msdeform/decomposition/smoothing.h"

namespace msd {

enum class HierarchyMethod {
  //! S_i = the region of S_{i−1} faired with order orders[i−1] (non-decreasing). Fairing reads only the
  //! constrained vertices, which all levels share, so every level is the fairing of S itself; the levels
  //! differ in how smoothly the free region meets the constrained part (C⁰, C¹, C²) and S_i has the least
  //! order-k_i energy of S₀ … S_i. B = S_k is the faired region of the two-level framework. Note that a
  //! higher order is not "smoother" in every sense: it continues more derivatives of the constrained
  //! border into the region (see the bumpy-plane measurements in the fairing tests).
  Fairing,
  //! S_i = implicit smoothing of S_{i−1} with time step smoothing.time_step · growth^(i−1): a band-pass
  //! hierarchy of the whole surface, each level visibly smoother than the previous one.
  Smoothing,
};

struct HierarchyOptions {
  HierarchyMethod method = HierarchyMethod::Smoothing;
  //! Fairing: one level per entry, in non-decreasing order.
  std::vector<FairingOrder> orders = {FairingOrder::Membrane, FairingOrder::ThinPlate,
                                      FairingOrder::MinimumVariation};
  LaplacianWeights fairing_weights = LaplacianWeights::Cotan;
  //! Fairing: keep the free vertices within max(orders) rings of the mesh boundary on every level (see
  //! FairingOptions::fix_mesh_boundary; one band for all levels so they share their constrained vertices).
  bool fix_mesh_boundary = true;
  //! Smoothing: number of decomposition steps k (levels S₁ … S_k).
  int levels = 3;
  //! Smoothing: options of the first step (S₀ → S₁); step i multiplies the time step by growth^(i−1).
  //! The default time step of 4 h̄² damps the features a few edges wide first.
  SmoothingOptions smoothing = [] {
    SmoothingOptions o;
    o.time_step = 4.0;
    return o;
  }();
  double time_step_growth = 4.0;
};

//! The levels S₀ (the input) … S_k (the base), all #V by 3 on the same faces.
class DecompositionHierarchy {
 public:
  DecompositionHierarchy() = default;
  //! levels[0] is S, levels.back() is B; at least one level, all the same size.
  //! \throw InvalidInput otherwise.
  DecompositionHierarchy(std::vector<Positions> levels, Faces faces);

  //! Number of surfaces k + 1 (S₀ … S_k); 1 means B = S.
  int num_levels() const { return static_cast<int>(levels_.size()); }
  //! Level i in [0, num_levels()): 0 is the input S, num_levels() − 1 the base B.
  //! \throw UsageError for i out of range.
  const Positions& level(int i) const;
  const Positions& surface() const { return level(0); }
  const Positions& base() const { return level(num_levels() - 1); }
  const Faces& faces() const { return faces_; }
  int num_vertices() const { return levels_.empty() ? 0 : static_cast<int>(levels_[0].rows()); }

  //! Global-coordinate detail D_i = S_{i−1} − S_i (#V by 3), for i in [1, num_levels()).
  //! \throw UsageError for i out of range.
  Positions difference(int i) const;
  //! Fallback reconstruction with global-coordinate details: out = B' + D_k + … + D_1 (#V by 3), which is
  //! S for B' = B. Allocation-free once out has #V rows. \throw UsageError for a wrong size of B'.
  void reconstruct_global(const Positions& base_deformed, Positions& out) const;

 private:
  std::vector<Positions> levels_;
  Faces faces_;
};

//! Builds the hierarchy of the surface (P #V×3, F #F×3) (see HierarchyMethod). The region is used by the
//! Fairing method only (validated then; ignored by Smoothing).
//! \throw InvalidInput for an empty or decreasing `orders` list, levels < 1, a growth that is not
//! positive and finite, and everything fair_region() or implicit_smoothing() throw.
DecompositionHierarchy build_hierarchy(const Positions& P, const Faces& F, const Region& region,
                                       const HierarchyOptions& options = {});

//! Smoothing hierarchy from arrays (P #V by 3, F #F by 3), no region needed.
//! \throw UsageError if options.method is Fairing; otherwise as build_hierarchy().
DecompositionHierarchy build_hierarchy(const Positions& P, const Faces& F,
                                       const HierarchyOptions& options = {});

}  // namespace msd
