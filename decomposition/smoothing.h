#pragma once
//! \file Global implicit smoothing (Desbrun et al. 1999; seed chapter 4), a decomposition S → B of the
//! whole surface: backward-Euler steps of the diffusion ∂p/∂t = Δp,
//!   (M − t·W) p_{n+1} = M p_n,
//! with Δ = M⁻¹W (symmetric W, diagonal mass M). The matrix is symmetric positive definite for t > 0, so
//! any time step is stable; features smaller than about √t are damped most.

#include "msdeform/core/laplacian.h"
#include "msdeform/core/types.h"

namespace msd {

//! How SmoothingOptions::time_step is scaled into the time t of (M − t·W), which has units length².
enum class SmoothingTimeUnit {
  MeanEdgeLengthSquared,  //!< t = time_step · h̄², h̄ = mean edge length of the input (resolution-relative)
  BoundingBoxDiagonalSquared,  //!< t = time_step · d², d = bounding-box diagonal (size-relative)
  Absolute,                    //!< t = time_step
};

//! What to restore after the last step (smoothing shrinks: diffusion is mean-curvature flow).
enum class SmoothingRescale {
  None,    //!< keep the smoothed positions
  Area,    //!< scale about the centroid so the total surface area equals the input's
  Volume,  //!< scale about the centroid so the enclosed volume equals the input's (closed meshes only)
};

struct SmoothingOptions {
  //! Size of each step in `unit`s. With MeanEdgeLengthSquared, 1 damps features of about one edge length;
  //! the damping of a feature of size ℓ grows like t/ℓ².
  double time_step = 1.0;
  SmoothingTimeUnit unit = SmoothingTimeUnit::MeanEdgeLengthSquared;
  //! Number of implicit steps (0 returns the input).
  int iterations = 1;
  LaplacianWeights weights = LaplacianWeights::Cotan;
  //! false (default): W and M of the input are used for every step, so the matrix is factored once and
  //! the mass-weighted centroid Σ mᵢpᵢ / Σ mᵢ (input masses) is preserved exactly by each step, as 1ᵀW = 0.
  //! true: W and M are recomputed from the current positions and refactored every step (Desbrun's
  //! original non-linear flow; smooths faster, costs one factorisation per step).
  bool update_operator = false;
  //! Keep boundary vertices (on an edge with one face) where they are. Stops the outline of an open surface
  //! from shrinking inward; closed meshes have none. Contradicts rescaling on an open mesh.
  bool fix_boundary = true;
  SmoothingRescale rescale = SmoothingRescale::None;
};

//! P: #V by 3 positions; F: #F by 3 faces. Returns the #V by 3 smoothed positions after
//! options.iterations steps. The rescale centroid is the mass-weighted centroid with the input masses.
//! \throw InvalidInput for an index out of range, a non-finite position, a time step that is not positive
//! and finite, negative iterations, a vertex that is not fixed and has no incident area (isolated or only
//! degenerate faces), Volume rescaling of a mesh with boundary, or rescaling with fix_boundary on a mesh
//! with boundary; SolverError naming the vertex if a step's system cannot be factored.
Positions implicit_smoothing(const Positions& P, const Faces& F, const SmoothingOptions& options = {});

//! t of (M − t·W) for `options` on the mesh (P, F), in length² (see SmoothingTimeUnit).
double smoothing_time(const Positions& P, const Faces& F, const SmoothingOptions& options);

}  // namespace msd
