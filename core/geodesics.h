#pragma once
//! \file Heat-method geodesic distances on a triangle mesh (Crane, Weischedel, Wardetzky 2013): a solver
//! class that keeps its operators and heat factorisation between queries, and a one-shot function.
//! Used by the geodesic propagation field (deformation/propagation.h).

#include <memory>
#include <string>
#include <vector>

#include "msdeform/core/types.h"

namespace msd {

//! Settings of the heat-method geodesic distance.
struct HeatGeodesicsOptions {
  //! m in the heat time step t = m·h² (h = mean edge length); Crane et al. recommend m = 1. Larger m
  //! smooths the distance (less accurate, more robust on bad triangulations). In [1e-6, 1e6]: beyond, the
  //! heat operator M − tW is dominated by one of its terms and its factorisation breaks down.
  double time_factor = 1.0;
};

//! Empty, or why `time_factor` is not in [1e-6, 1e6] (naming it and its value).
std::string check_time_factor(double time_factor);

//! Heat-method geodesic distances on a triangle mesh (Crane, Weischedel, Wardetzky 2013) with the cotan
//! operators of core/laplacian.h:
//!   1. heat flow:   (M − t·W) u = δ_sources,  M = mixed-Voronoi mass, W = cotan weights;
//!   2. direction:   X = −∇u / |∇u| per face (0 where ∇u vanishes);
//!   3. Poisson:     W φ = div X on the vertices that are not sources, φ = 0 on the sources (Dirichlet).
//! Pinning the whole source set (instead of the paper's single pinned value and shift) keeps φ exactly 0
//! on thick source regions, where X would otherwise point outwards from the region's middle.
//! Time step: t = m·h²; when the farthest reachable vertex lies more than 500·√t away along mesh edges,
//! t is doubled until it does not: u decays like exp(−d/√t) and would underflow double precision
//! (exp(−708)) beyond ~700·√t, leaving no direction to follow. With m = 1 this starts at 500 edge
//! lengths from the sources (a 1M-vertex plane is 1000 edges wide); t then grows and φ is smoother.
//! Accuracy (measured in tests/core/test_geodesics.cpp): flat 10k-vertex square, distance to a
//! vertex in the middle: max error 1.2 h, mean relative error 1.3% (beyond 5 h); distance to a strip
//! along one side: max error 0.13 h. Unit sphere, distance to a vertex: mean relative error 3.8%, 2.0%,
//! 1.1%, 0.7% and max error (away from the antipode) 0.052, 0.027, 0.016, 0.012 for 162, 642, 2.5k, 10k
//! vertices, i.e. roughly O(h). The method smooths over about √t near the sources and at the cut locus.
//! Vertices in a connected component (via edges of non-degenerate faces) with no source get +∞.
class HeatGeodesics {
 public:
  //! P: #V by 3, F: #F by 3. Builds the operators; factorisations happen in distance().
  //! \throw InvalidInput if time_factor is not in [1e-6, 1e6] or F indexes outside P.
  HeatGeodesics(const Positions& P, const Faces& F, HeatGeodesicsOptions options = {});
  ~HeatGeodesics();
  HeatGeodesics(HeatGeodesics&&) noexcept;
  HeatGeodesics& operator=(HeatGeodesics&&) noexcept;

  //! #V distances to the nearest of `sources` (vertex ids; 0 on them, +∞ where unreachable, all +∞ if
  //! sources is empty). Factors the heat operator (reused while the time step stays the same) and one
  //! Poisson system per call. \throw InvalidInput on an out-of-range source; SolverError naming the
  //! vertex if a system is singular (e.g. a vertex whose faces all have zero area).
  Eigen::VectorXd distance(const std::vector<int>& sources);

  double mean_edge_length() const;
  //! The heat time step t used by the last distance() call (0 before the first).
  double last_time_step() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

//! One-shot heat-method distance (see HeatGeodesics): #V distances from `sources` on (P, F).
Eigen::VectorXd geodesic_distance(const Positions& P, const Faces& F, const std::vector<int>& sources,
                                  HeatGeodesicsOptions options = {});

}  // namespace msd
