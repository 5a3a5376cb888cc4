#pragma once
//! \file The Laplace operator used by fairing and smoothing, in symmetric form Δ = M⁻¹ W (seed chapter 3
//! and appendix), with a choice of weights.

#include <vector>

#include "core/types.h"

namespace msd {

//! Edge weights of the discrete Laplacian.
enum class LaplacianWeights {
  Cotan,  //!< cotangent weights and mixed-Voronoi areas (core/laplacian.h): geometry-aware, linear precision
  Uniform,  //!< graph (umbrella) weights: 1 per edge, mass = degree · h̄²/4 (see LaplaceOperator)
};

//! Δ = M⁻¹ W as a symmetric negative semi-definite W and a diagonal mass M.
struct LaplaceOperator {
  //! #V by #V symmetric, negative semi-definite, constants in the kernel.
  SparseMatrix W;
  //! #V diagonal of M. Cotan: mixed-Voronoi vertex areas. Uniform: degree · h̄²/4 with h̄ the mean edge
  //! length, which makes M⁻¹W approximate the same Δ (units 1/length²) as the cotan operator on regular
  //! meshes, so time steps mean the same for both weights. 0 for a vertex without any usable face.
  Eigen::VectorXd mass;
};

//! The Laplace operator of (P #V×3, F #F×3) with the given weights. Indices are not checked here;
//! callers validate their input first (see check_mesh_arrays).
LaplaceOperator laplace_operator(const Positions& P, const Faces& F, LaplacianWeights weights);

//! Mean length of the three edges of every face of (P, F) (interior edges count twice); 0 without faces.
double mean_edge_length(const Positions& P, const Faces& F);

//! Throws InvalidInput, prefixed with `who`, if F has an index outside [0, #P) or P a non-finite
//! coordinate, naming the face or vertex.
void check_mesh_arrays(const Positions& P, const Faces& F, const char* who);

//! Vertices on a boundary edge (an edge used by exactly one face), ascending.
std::vector<int> boundary_vertices(const Faces& F, int num_vertices);

const char* to_string(LaplacianWeights weights);

}  // namespace msd
