#pragma once
//! \file Checks a decomposition S → B against the fold condition of seed 9.3.3: displacements of height
//! h along the normals of a base whose curvature radius is r cross each other where h > r (the offset
//! surface b + h·n turns inside out). Used to choose the detail scale of a low-pass base and by the
//! multi-scale deformer to refuse or warn before any frame.

#include <limits>

#include "msdeform/core/types.h"

namespace msd {

//! A base B with less than this fraction of S's area on the triangles with a free vertex
//! (free_area_ratio) has lost the shape, not only the details: heights over it are the shape itself (a
//! tube faired towards its axis). decompose() refuses such a base; the detail distortion metric does not
//! measure over one.
constexpr double kMinBaseAreaRatio = 0.5;

//! Details D = S − B measured against the curvature of B. S and B share connectivity F.
//!
//! Per vertex i of B: unit area-weighted normal n_i, signed height h_i = (s_i − b_i)·n_i, and for each
//! one-ring neighbour j the normal curvature along the edge, κ_ij = (n_i − n_j)·(b_j − b_i) / ‖b_j − b_i‖²
//! (exactly −1/r on a sphere of radius r with outward normals, whatever the edge; > 0 where B bends
//! towards its normal). Offsetting both ends by h_i along their normals shortens the edge's projection by
//! the factor 1 − h_i κ_ij, so the displacements cross (the details fold) where the fold ratio
//! ρ_i = max_j h_i κ_ij reaches 1.
struct DetailCheck {
  double max_height = 0;  //!< max ‖s_i − b_i‖, mesh units
  double rms_height = 0;  //!< root mean square of ‖s_i − b_i‖
  //! Smallest curvature radius of B, 1 / max_ij |κ_ij| (infinity for a flat B), mesh units.
  double min_curvature_radius = std::numeric_limits<double>::infinity();
  double max_fold_ratio = 0;  //!< max_i ρ_i; < 1: no displacement crosses its neighbour's at rest
  //! 99.9th percentile of ρ_i over the vertices: the fold ratio without the handful of vertices at mesh
  //! defects (slivers, near-duplicates) that dominate the maximum on real scans.
  double fold_ratio_p999 = 0;
  int worst_vertex = -1;      //!< the vertex of max_fold_ratio (−1 when all ρ_i ≤ 0)
  int folding_vertices = 0;   //!< vertices with ρ_i ≥ 1
  //! Height and curvature radius at worst_vertex (mesh units).
  double worst_height = 0, worst_radius = std::numeric_limits<double>::infinity();
};

//! S, B: #V by 3 with shared faces F (#F by 3). O(#F). Vertices without a non-degenerate face (no normal),
//! coinciding neighbours and mesh-boundary vertices (whose half ring measures the outline's curvature,
//! not the surface's) are skipped. \throw InvalidInput for mismatched sizes, a face
//! index out of range or a non-finite coordinate.
DetailCheck check_details(const Positions& S, const Positions& B, const Faces& F);

}  // namespace msd
