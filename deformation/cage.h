#pragma once
//! \file Cage-based free-form deformation (seed 9.5.2): the points are written in generalised barycentric
//! coordinates of a coarse closed triangle mesh, the cage, p = Σ_l c_l φ_l(p) (9.14), and moving the cage
//! vertices by δc moves every point by d(p) = Σ_l δc_l φ_l(p). Two coordinate kinds: mean value
//! coordinates (Ju, Schaefer & Warren 2005), closed-form and defined everywhere in space, and harmonic
//! coordinates (Joshi et al. 2007, Blender's Mesh Deform), solved on a grid over the cage. Without a user
//! cage, an offset 26-DOP around the points is generated. Handle constraints go through the least-norm
//! solve of (9.13) with φ_l(p_i) in place of N_l(u_i) (SpaceDeformer).

#include <memory>
#include <string>
#include <vector>

#include "msdeform/core/types.h"
#include "msdeform/deformation/space_deformer.h"

namespace msd {

enum class CageCoordinates {
  MeanValue,  //!< mean value coordinates: exact, smooth, defined inside and outside; may be negative inside
              //!< a non-convex cage
  Harmonic,   //!< harmonic coordinates on a grid: non-negative inside, interior-respecting; harmonic only up
              //!< to the grid resolution
};

struct CageOptions {
  CageCoordinates coordinates = CageCoordinates::MeanValue;
  //! A user cage: a closed, edge-manifold, consistently oriented triangle mesh (cage_P #C×3, cage_F #T×3)
  //! that should enclose the points; an inward-oriented cage is flipped. Empty: an offset 26-DOP is
  //! generated.
  Positions cage_P;
  Faces cage_F;
  //! Generated cage: offset of its planes from the points, relative to their bounding-box diagonal (> 0).
  double margin = 0.05;
  //! Generated cage: midpoint (1→4) subdivisions of the 26-DOP's triangles (more control vertices), 0..4.
  int subdivisions = 1;
  //! Harmonic coordinates: grid cells along the cage's longest bounding-box side (4..kMaxHarmonicResolution).
  //! Memory is about (nodes inside or near the cage) × #cage vertices × 8 bytes, plus the grid Laplacian's
  //! factor: 128 takes about 40 s and 4 GB with a 186-vertex cage; 256 failed to factor in 2 GB.
  int harmonic_resolution = 64;
  static constexpr int kMaxHarmonicResolution = 128;
  LeastNormOptions least_norm;
};

// ---------------------------------------------------------------------------------------------------
// Mean value coordinates

//! Per-thread scratch space of MeanValueCage::coordinates() (reused: no allocation once sized).
struct MeanValueWorkspace {
  std::vector<double> r;      // #C×3 vectors c_l − x
  std::vector<double> d;      // #C distances |c_l − x|
  std::vector<double> u;      // #C×3 unit vectors (c_l − x) / d_l
  std::vector<double> g;      // #E per edge θ/(|r_a×r_b|): angle over the doubled area it subtends
  std::vector<double> theta;  // #E angle subtended at x
};

//! A closed triangle cage prepared for mean value coordinates (Ju, Schaefer & Warren 2005): edges and
//! per-face frames are precomputed so that one evaluation costs O(#C + #E + #T).
//!
//! Per face T and point x the coordinates come from the mean vector m_T = ∫ u dS over T's spherical
//! projection, written as m_T = ½ Σ_k θ_k n_k (θ_k the angle edge k subtends at x, n_k the normal of the
//! plane through x and edge k), split into the part along T's unit normal N, m⊥, and the part in T's
//! plane, m∥. With η the signed distance of x to T's plane, λ the barycentric coordinates of x's
//! projection and ∇λ their gradients, T's weights are
//!   w_j = −(m⊥/η) λ_j + ∇λ_j · m∥,
//! which reproduce m_T exactly (Σ_j w_j (c_j − x) = m_T) for any η. An error in m⊥ therefore changes only
//! the normal component, and linear precision, Σ_T m_T = 0, survives points near faces, edges and face
//! planes. m∥ carries an explicit factor η (no cancellation), and where x is close to T's plane outside T
//! (a thin spherical triangle, the paper's "ignore t" case) m⊥ = O(η²) is computed from angle differences
//! that do not cancel. On a vertex, edge or face (within 1e-13 of the cage diagonal) the coordinates are
//! the vertex, the linear interpolation on the edge, or the barycentric coordinates on the face.
//! Far outside (distance D) the coordinates are ill-conditioned: Σ_l w_l falls like D⁻⁴ while each weight
//! falls like D⁻³, so the per-face round-off grows about like (D/diag)⁴·1e-13 in linear precision (Ju et
//! al.'s formula in double: 100 times that). A least-norm correction onto Σ w = 1, Σ w c = x (its size is
//! that residual: ≤ 1e-12 within a diagonal of the cage) keeps both properties at round-off everywhere.
class MeanValueCage {
 public:
  MeanValueCage() = default;
  //! cage_P #C×3, cage_F #T×3 (closed and consistently oriented; not checked here, see check_cage()).
  //! \throw InvalidInput for an index out of range, a non-finite vertex or a degenerate (zero-area) face.
  MeanValueCage(const Positions& cage_P, const Faces& cage_F);

  int num_vertices() const { return static_cast<int>(P_.rows()); }
  int num_faces() const { return static_cast<int>(faces_.size()); }
  int num_edges() const { return static_cast<int>(edges_.size()); }
  const Positions& positions() const { return P_; }

  //! The #C coordinates φ_l(x) into w (normalised: Σ w = 1). Finite for every finite x, inside or outside.
  //! Thread-safe with one workspace per thread.
  void coordinates(const Vec3& x, MeanValueWorkspace& ws, double* w) const;
  //! The generalised winding number of the cage around x (1 inside, 0 outside an outward closed cage), from
  //! the faces' solid angles.
  double winding_number(const Vec3& x) const;

 private:
  struct Face {
    int v[3];   // vertex ids
    int e[3];   // edge k (opposite v[k], from v[k+1] to v[k+2]) as an index into edges_
    Vec3 n;     // unit normal
    Vec3 q[3];  // E_k × n, E_k = c_{k+2} − c_{k+1}: a_k = r_{k+1} · q_k is twice the signed area at x
    double gram[3][3];  // E_j · E_k
    double edge_len[3];
    double area2;  // twice the area
  };
  Positions P_;
  std::vector<Face> faces_;
  std::vector<std::pair<int, int>> edges_;  // undirected, a < b
  std::vector<double> edge_len_;
  double tol_ = 0;  // snapping distance: 1e-13 × the cage's bounding-box diagonal
  // The linear-precision correction: vertices centred and scaled, (Σ_l [1 ĉ_l][1 ĉ_l]ᵀ)⁻¹.
  Vec3 centre_ = Vec3::Zero();
  double scale_ = 1;
  Positions unit_;
  Eigen::Matrix4d gram_inv_ = Eigen::Matrix4d::Zero();
};

//! One-off mean value coordinates of x with respect to the closed cage (cage_P #C×3, cage_F #T×3) into w
//! (#C values). Prefer MeanValueCage for many points. \throw as MeanValueCage's constructor.
void mean_value_coordinates(const Positions& cage_P, const Faces& cage_F, const Vec3& x, double* w);

// ---------------------------------------------------------------------------------------------------
// Harmonic coordinates

//! Harmonic coordinates (Joshi et al. 2007) of a closed cage on a regular grid: the cage's bounding box plus
//! a cell, `resolution` cells along its longest side. Nodes within half a cell diagonal of the cage surface
//! are near-boundary; a 6-connected flood fill from a grid corner through the other nodes marks the outside,
//! what it does not reach is inside. Near-boundary and outside nodes take mean value coordinates (so the
//! Dirichlet data have partition of unity and linear precision), inside nodes solve the 7-point Laplace
//! equation, one factorisation for all #C right-hand sides. Because that Laplacian is exact for linear
//! functions, partition of unity and linear precision hold at every node and, through trilinear
//! interpolation, at every point of the grid. The coordinates are harmonic only up to the grid resolution;
//! near the surface they follow the MVC data. Points outside the grid are clamped to it.
class HarmonicCoordinates {
 public:
  //! cage_P #C×3, cage_F #T×3: closed and consistently oriented (see check_cage()). \throw InvalidInput for
  //! a resolution outside 4..CageOptions::kMaxHarmonicResolution or a bad cage array; SolverError if the grid system cannot be factored.
  HarmonicCoordinates(const Positions& cage_P, const Faces& cage_F, int resolution);
  ~HarmonicCoordinates();

  int num_vertices() const;
  //! The #C coordinates at x into w (trilinear interpolation of the node values). Thread-safe.
  void coordinates(const Vec3& x, double* w) const;

  //! Grid facts: nodes per axis, cell size, node counts by class, seconds spent solving.
  Eigen::Vector3i grid_size() const;
  double cell_size() const;
  int num_inside_nodes() const;
  int num_boundary_nodes() const;
  double solve_seconds() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---------------------------------------------------------------------------------------------------
// Cages

//! An offset k-DOP cage around the points P (#V×3, at least one point, finite): the 26 directions d_i of
//! the 3×3×3 grid (normalised), support h_i = max_p d_i·p, half-spaces d_i·x ≤ h_i + margin·diag (diag:
//! the bounding-box diagonal of P). The convex polytope is clipped from the grown bounding box, its
//! polygons fan-triangulated, then `subdivisions` midpoint subdivisions add control vertices (the cage
//! keeps its shape). Output: cage_P #C×3, cage_F #T×3, closed, manifold, outward-oriented, every point of P
//! strictly inside. \throw InvalidInput for empty or non-finite P, all points equal, margin not in
//! (0, 10] or subdivisions not in 0..4; SolverError if the result is not a closed manifold (a bug).
void offset_kdop_cage(const Positions& P, double margin, int subdivisions, Positions& cage_P, Faces& cage_F);

//! Checks a user cage (cage_P #C×3, cage_F #T×3): finite, indices in range, every vertex in a face, no
//! zero-area face, every edge in exactly two faces with opposite directions (closed, manifold, consistently
//! oriented), non-zero volume. Returns the faces oriented outward (flipped when the volume was negative;
//! *flipped says so). \throw InvalidInput naming the vertex, face or edge, with `who` as prefix.
Faces check_cage(const Positions& cage_P, const Faces& cage_F, const char* who, bool* flipped = nullptr);

// ---------------------------------------------------------------------------------------------------
// The deformer

//! Cage-based free-form deformation (seed 9.5.2) on the SpaceDeformer seam: the basis functions are the
//! cage coordinates φ_l (dense: all #C cage vertices), the coefficients the cage-vertex displacements δc.
//! Handle constraints are met in the least-squares sense by the least-norm solve of (9.13) (with the
//! affine part of LeastNormOptions, affine edits are reproduced exactly); deform_controls() edits the cage
//! directly. Prepare costs O(#V·#T) (coordinates at every point, in parallel) plus, for harmonic
//! coordinates, one grid solve.
class CageDeformer : public SpaceDeformer {
 public:
  //! \throw InvalidInput for options out of range (margin, subdivisions, resolution, a cage array with a
  //! wrong shape).
  explicit CageDeformer(CageOptions options = {});
  ~CageDeformer() override;
  //! "cage-mvc" or "cage-harmonic".
  const std::string& name() const override { return name_; }
  const CageOptions& options() const { return options_; }

  bool has_control_points() const override { return true; }
  //! The cage vertices (#C×3). \throw UsageError before prepare.
  Positions control_points() const override;
  //! The cage in use after prepare (generated or the user's, outward-oriented): #C×3 and #T×3.
  const Positions& cage_positions() const { return cage_P_; }
  const Faces& cage_faces() const { return cage_F_; }
  Faces control_faces() const override { return cage_F_; }

 protected:
  void fit_basis(const Positions& P, const Region& region) override;
  int basis_size() const override { return static_cast<int>(cage_P_.rows()); }
  void basis(const Vec3& x, BasisRow& row) const override;
  bool exact_constraints() const override { return false; }
  LeastNormOptions least_norm_options() const override { return options_.least_norm; }
  //! The cage's remedies: a larger regularisation, a finer cage (more vertices near the constraints), or
  //! editing the cage vertices directly.
  std::string overshoot_advice() const override;
  std::string missed_advice() const override {
    return "the cage's vertices are too far from the constrained parts to move them apart: give a cage drawn "
           "around them (--cage), or use rbf";
  }

 private:
  std::string name_;
  CageOptions options_;
  Positions cage_P_;
  Faces cage_F_;
  // The cage's bounding-box centre: mvc_ and harmonic_ take points relative to it.
  Vec3 cage_origin_ = Vec3::Zero();
  MeanValueCage mvc_;
  std::unique_ptr<HarmonicCoordinates> harmonic_;
};

}  // namespace msd
