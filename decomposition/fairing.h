#pragma once
//! \file Fairing of the region to be edited (Botsch & Kobbelt 2004; seed 9.3 decomposition S → B):
//! the base surface b equals the input p on fixed and handle vertices and satisfies Δᵏ b = 0 on the free
//! vertices, k = 1, 2, 3 (membrane, thin plate, minimum variation). The smooth base B of the multi-scale
//! framework (seed Fig. 9.7) is the faired region; the details D = S ⊖ B are what fairing removed.

#include <vector>

#include "msdeform/core/laplacian.h"
#include "msdeform/core/region.h"
#include "msdeform/core/solver.h"

namespace msd {

//! k of Δᵏ b = 0: which energy the faired region minimises, and how smoothly it meets the constrained
//! vertices (C⁰, C¹, C² across the region boundary). The result depends only on the k rings of
//! constrained vertices around the free region; vertices further away have no influence.
enum class FairingOrder {
  Membrane = 1,          //!< Δb = 0: minimal area (discrete harmonic)
  ThinPlate = 2,         //!< Δ²b = 0: minimal bending, as in (9.5) with ks = 0
  MinimumVariation = 3,  //!< Δ³b = 0: minimal variation of curvature
};

struct FairingOptions {
  FairingOrder order = FairingOrder::ThinPlate;
  LaplacianWeights weights = LaplacianWeights::Cotan;
  //! Keep the free vertices within k rings of the mesh boundary (vertices on an edge with one face, and
  //! k − 1 rings inside) where they are, i.e. treat them as constrained, as pmp-library's fair() does. At
  //! a boundary vertex the discrete Δp carries the curvature of the outline, not of the surface: fairing
  //! those rows literally pulls the outline inward (k = 1 minimises area), and for k >= 2 one fixed ring
  //! is not enough to determine Δᵏ near it. Measured on the 10k bumpy plane, whose free strip touches the
  //! outline along y = 0 and y = 1: the largest in-plane move of a free vertex is 0.22 / 0.08 / 0.05
  //! (k = 1 / 2 / 3, plane width 1) with fix_mesh_boundary = false, and 0.008 / 0.009 / 0.035 (about one
  //! grid spacing for k <= 2) with it. The price: details within k rings of the outline stay in the
  //! base. Set false for Δᵏb = 0 literally on every free vertex.
  bool fix_mesh_boundary = true;
};

const char* to_string(FairingOrder order);

//! Fairing prepared once for a mesh and region: prepare() assembles Q_k on the rest geometry and
//! factors it restricted to the free vertices (ConstrainedQuadratic); fair() then re-fairs any new
//! positions of the constrained vertices with one back-substitution (O(#V) work besides it, internal
//! workspace reused; `out` resized only when its shape differs). The operator stays that of prepare()
//! (the fairing is linear in the constrained positions). Not thread-safe: fair() uses the workspace.
class RegionFairing {
 public:
  RegionFairing() = default;
  //! Same as prepare().
  RegionFairing(const Positions& P, const Faces& F, const Region& region, const FairingOptions& options = {});

  //! P (#V by 3), F (#F by 3): the surface S whose geometry defines Δ; region: free vertices are faired, fixed and handle
  //! vertices are kept (Region codes; handles are not distinguished here).
  //! \throw InvalidInput for a region of the wrong size, an empty handle, no constrained vertex, a
  //! non-finite position, an invalid order, or a free vertex without incident area; TopologyError for a
  //! free component that touches no constrained vertex (Region::validate); SolverError naming the vertex
  //! where the system is singular.
  void prepare(const Positions& P, const Faces& F, const Region& region, const FairingOptions& options = {});
  bool prepared() const { return prepared_; }

  //! Faired positions for P (#V by 3): only the rows of constrained vertices are read; writes #V by 3
  //! into out (resized only when its shape differs). out may alias P.
  //! \throw UsageError before prepare() or for a wrong row count; InvalidInput for a non-finite
  //! constrained position; SolverError if the result is not finite.
  void fair(const Positions& P, Positions& out) const;
  Positions fair(const Positions& P) const;

  //! Same, with the constrained positions given directly: #C by 3, one row per vertex of
  //! constrained_vertices() in that order.
  void fair_constrained(const Positions& constrained, Positions& out) const;

  //! The rest positions passed to prepare(), faired (b of the decomposition S → B).
  Positions base() const { return fair(rest_); }

  const FairingOptions& options() const { return options_; }
  int num_vertices() const { return static_cast<int>(rest_.rows()); }
  //! Fixed and handle vertices, plus the free ones in the boundary band if options().fix_mesh_boundary;
  //! ascending (the `known` rows of the system).
  const std::vector<int>& constrained_vertices() const { return system_.known(); }
  //! The faired vertices, ascending (the unknowns): the region's free vertices, without those in the
  //! boundary band if options().fix_mesh_boundary.
  const std::vector<int>& free_vertices() const { return system_.unknown(); }
  //! Q_k of the rest geometry (#V by #V), see polyharmonic_matrix().
  const SparseMatrix& matrix() const { return Q_; }

 private:
  void solve_known(Positions& out) const;

  FairingOptions options_;
  Positions rest_;
  SparseMatrix Q_;
  ConstrainedQuadratic system_;
  bool prepared_ = false;
  mutable Eigen::MatrixXd known_, x_;  // per-call workspace
};

//! One-shot fairing of the free vertices of `region` on (P, F) (see RegionFairing): #V by 3 positions,
//! equal to the mesh positions on fixed and handle vertices (and near the mesh boundary, see
//! FairingOptions::fix_mesh_boundary), Δᵏ b = 0 on the other free ones.
//! \throw as RegionFairing::prepare().
Positions fair_region(const Positions& P, const Faces& F, const Region& region, const FairingOptions& options = {});

}  // namespace msd
