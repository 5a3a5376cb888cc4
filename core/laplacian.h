#pragma once
//! \file Discrete differential operators on triangle meshes (seed chapter 3 and appendix).

#include <string>
#include <vector>

#include "msdeform/core/types.h"

namespace msd {

//! Edge weights of the discrete Laplacian.
enum class LaplacianWeights {
  Cotan,    //!< cotangent weights and mixed-Voronoi areas: geometry-aware, linear precision
  Uniform,  //!< graph (umbrella) weights: 1 per edge, mass = degree · h̄²/4 (see laplace_operator)
};
const char* to_string(LaplacianWeights weights);

//! The Laplace operator in symmetric form, Δf = M⁻¹ W f: the one operator type of msdeform (shell,
//! fairing, smoothing, low-pass, propagation and the metrics all use it).
struct LaplaceOperator {
  //! #V by #V symmetric, negative semi-definite, constants in the kernel. Cotan:
  //! W_ij = (cot α_ij + cot β_ij) / 2 for each edge, W_ii = -Σ_j W_ij.
  SparseMatrix W;
  //! #V diagonal of M. Cotan: mixed-Voronoi vertex areas (Meyer et al. 2003), summing to the surface area.
  //! Uniform: degree · h̄²/4 (h̄ the mean edge length), so M⁻¹W approximates the same Δ (1/length²) on
  //! regular meshes. 0 for a vertex without a usable face.
  Eigen::VectorXd mass;
  int degenerate_faces = 0;    //!< cotan: faces of (near) zero area, left out of W and the mass
  //! Needle angles, |cot| > kMaxCotangent. Their triangle's three cotangents are scaled together so the
  //! largest is ±kMaxCotangent: the triangle's weights stay positive semi-definite (clamping one by one
  //! turns a needle's (K', K', −K') into the indefinite (K, K, −K)).
  int clamped_cotangents = 0;
  static constexpr double kMaxCotangent = 1e5;
};

//! The face rule of cotan_laplacian(), for code that assembles its own cotangent-weighted operators
//! (deformation transfer) and must treat degenerate and needle triangles the same way.
struct TriangleCotangents {
  double area2 = 0;           //!< twice the area, ‖(p1 − p0) × (p2 − p0)‖
  double cot[3] = {0, 0, 0};  //!< cotangent of the angle at corner k (opposite the edge k+1, k+2), unclamped
  //! The cotangents cotan_laplacian() weighs with: cot, scaled together so the largest is at most
  //! ±LaplaceOperator::kMaxCotangent (clamping one by one would make a needle's weights indefinite).
  double weight[3] = {0, 0, 0};
  //! Twice the area at most 2 · kDegenerateAreaRatio · (longest edge)², or within the rounding of the
  //! corners' coordinates (4 ε · their largest magnitude · longest edge: the same triangle moved far from
  //! the origin stays degenerate), or not a number: cotan_laplacian() leaves the face out (cot stays 0).
  bool degenerate = false;
  //! Corners with |cot| > LaplaceOperator::kMaxCotangent (cotan_laplacian() scales the triangle's cotangents
  //! down together): a needle.
  int needle_corners = 0;
  static constexpr double kDegenerateAreaRatio = 1e-14;
};

//! Classifies the triangle (p0, p1, p2) exactly as cotan_laplacian() does; scale-invariant (ratio tests).
TriangleCotangents triangle_cotangents(const Vec3& p0, const Vec3& p1, const Vec3& p2);

//! TriangleCotangents::degenerate's rule on a triangle's measures, in any one unit: twice its area, its
//! squared longest edge and the largest magnitude of its corners' coordinates (for callers that measure
//! in a scaled frame, like the fold check).
bool degenerate_area(double area2, double longest2, double largest_coordinate);

//! Cotan weights and mixed-Voronoi mass of (P #V×3, F #F×3). A face whose area is below 1e-14 times its
//! squared longest edge, or within the rounding of its coordinates (TriangleCotangents::degenerate), counts
//! as degenerate and contributes nothing; cotangents are clamped, so the result is always finite.
LaplaceOperator cotan_laplacian(const Positions& P, const Faces& F);

//! The Laplace operator of (P #V×3, F #F×3) with the given weights. Indices are not checked here;
//! callers validate their input first (see check_mesh_arrays).
LaplaceOperator laplace_operator(const Positions& P, const Faces& F, LaplacianWeights weights);

//! The symmetric polyharmonic matrix of order k = 1, 2, 3 (#V by #V) of op, Δ = M⁻¹W:
//!   Q₁ = −W,   Q₂ = W M⁻¹ W,   Q₃ = −W M⁻¹ W M⁻¹ W,
//! i.e. Q_k = (−1)ᵏ M Δᵏ, positive semi-definite: xᵀQ₁x is the membrane, xᵀQ₂x the thin-plate and xᵀQ₃x
//! the minimum-variation energy (seed 9.2, (9.5)–(9.7); Botsch & Kobbelt 2004). The shell operator
//! ks·Q₁ + kb·Q₂ and the fairing of order k both come from here. Vertices with zero mass get M⁻¹ = 0
//! (their rows then only keep Q₁'s part). \throw InvalidInput for k outside 1..3.
SparseMatrix polyharmonic_matrix(const LaplaceOperator& op, int k);

//! W diag(w) W (#V by #V) for a symmetric W (#V by #V, both triangles stored) and weights w (#V): the
//! thin-plate matrix Q₂ = W M⁻¹ W with w = M⁻¹, or the low-pass base's bending term. Its pattern is W's
//! 2-ring. Computed on both cores, with the values of Eigen's W * (w.asDiagonal() * W) bit for bit.
//! \throw InvalidInput when it would have more than 2^31 − 1 nonzeros, or more than the machine's memory
//! holds with a factorisation at 48 bytes per nonzero (measured), naming the vertex of most neighbours: it
//! couples every two neighbours of a vertex, so a vertex of valence 46340 alone gives 2^31, and one of
//! 23000 alone fills 24 GB.
SparseMatrix weighted_square(const SparseMatrix& W, const Eigen::VectorXd& w);

//! Refuses a product that couples every two neighbours of a vertex (W M⁻¹ W, a least-squares RᵀR over
//! one-rings) where one vertex alone would give it more than 2^31 − 1 nonzeros, the most a sparse matrix
//! holds, or more than fit the machine's memory with a factorisation (48 bytes per nonzero, measured):
//! (unknowns_per_vertex · (valence + 1))² of them. W: #V by #V with one column per vertex, its pattern the
//! one-rings. \throw InvalidInput naming `product` and the vertex of most neighbours (a fan-triangulated
//! disk or cone: remesh it).
void check_neighbour_coupling(const SparseMatrix& W, int unknowns_per_vertex, const std::string& product);

//! Mean length of the three edges of every face of (P, F) (interior edges count twice); 0 without faces.
double mean_edge_length(const Positions& P, const Faces& F);

//! Uniform (graph) Laplacian in symmetric form: W_ij = 1 per edge, W_ii = -degree. Δ_uniform = D⁻¹ W.
SparseMatrix uniform_laplacian(const Faces& F, int num_vertices);

//! Σ_f (p0 − o) · ((p1 − o) × (p2 − o)) / 6 over the faces of (P, F), o the bounding box's centre: the
//! enclosed volume of a closed, consistently oriented mesh (divergence theorem; positive for outward
//! faces), the same wherever the mesh sits. Indices are not checked here.
double signed_volume(const Positions& P, const Faces& F);

//! #F triangle areas.
Eigen::VectorXd face_areas(const Positions& P, const Faces& F);

class Region;
//! Area of (deformed, F) over the area of (rest, F) on the triangles with a free vertex of region (all of
//! them when none is free; 1 when they have no area). rest, deformed: #V by 3. Indices are not checked here.
double free_area_ratio(const Positions& rest, const Positions& deformed, const Faces& F, const Region& region);

//! Per-face gradient of piecewise-linear functions: 3#F by #V; rows 3f..3f+2 give the gradient on face f.
//! Degenerate faces get zero rows.
SparseMatrix gradient_operator(const Positions& P, const Faces& F);

//! Integrated divergence of per-face vector fields: #V by 3#F, D = -Gᵀ A (A = face areas, 3 per face),
//! so that D·G equals the cotan weight matrix W.
SparseMatrix divergence_operator(const Positions& P, const Faces& F);

//! Sub-matrix A(rows, cols) for index lists (each ascending or not; entries keep their list order).
SparseMatrix submatrix(const SparseMatrix& A, const std::vector<int>& rows, const std::vector<int>& cols);

}  // namespace msd
