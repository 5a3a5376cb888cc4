#pragma once
//! \file Isotropic remeshing (Botsch & Kobbelt 2004, "A remeshing approach to multiresolution modeling";
//! seed 9.3.2: a remeshed base surface makes the normal-displacement search and the base deformation
//! numerically more robust). A thin wrapper over CGAL::Polygon_mesh_processing::isotropic_remeshing.

#include "msdeform/core/types.h"

namespace msd {

//! A remeshed surface: #V by 3 positions and #F by 3 faces (new connectivity, no relation to the input's
//! vertex or face numbering).
struct RemeshResult {
  Positions P;
  Faces F;
};

//! Remeshes (P #V×3, F #F×3; vertices no face uses are left out) towards edges of length target_edge_length
//! by `iterations` rounds of split (> 4/3 target), collapse (< 4/5 target), valence-improving flips and
//! tangential relaxation, each round projecting the vertices back onto the input surface (CGAL
//! isotropic_remeshing). The border is resampled, not moved: its edges are split (at their midpoints) and
//! collapsed (onto one of their vertices) towards the target like the others but never flipped or smoothed,
//! so the outline of an open mesh is a polyline through its own points, and the vertices where it turns by
//! more than 25° (a rectangle's corners) are kept. At most kMaxRemeshTriangles (20 million, about 6 GB in
//! CGAL's structures) are made: an edge length whose estimated output (area / (√3/4 · edge²)) exceeds it is
//! refused before any work, with the smallest edge length allowed. \throw InvalidInput if target_edge_length
//! is not finite and positive or too small (above), iterations < 0, F indexes out of range or repeats a
//! vertex in a face, a coordinate is not finite, or a face makes the surface non-manifold (the message names
//! the face); SolverError if CGAL reports a failure.
constexpr double kMaxRemeshTriangles = 2e7;

RemeshResult remesh_isotropic(const Positions& P, const Faces& F, double target_edge_length,
                              int iterations = 3);

//! The size check of remesh_isotropic alone (P, F finite, indices in range; a face out of range is not
//! counted), for callers that refuse before their own work. \throw InvalidInput as remesh_isotropic,
//! prefixed with `who`.
void check_remesh_size(const Positions& P, const Faces& F, double target_edge_length, const std::string& who);

}  // namespace msd
