#pragma once
//! \file Normal displacements (seed 9.3.2): each vertex p of S is stored as a base point b on B, given by
//! a face and barycentrics (α, β, γ), plus a signed height h along B's Phong-interpolated normal:
//!   p = b + h · n(b),   n(b) = (α n_a + β n_b + γ n_c) / ‖α n_a + β n_b + γ n_c‖,
//! and reconstructed on a deformed base as p' = b'(α, β, γ) + h · n'(α, β, γ). S and B may have
//! different connectivity and vertex counts.

#include <string>
#include <vector>

#include "msdeform/core/mesh.h"
#include "msdeform/core/types.h"
#include "msdeform/detail/encoding.h"

namespace msd {

//! Settings of the Newton search for base points.
//! The remedy that ends encode_warnings()'s line: a caller that knows better (the details already fold over
//! the base, where a larger detail scale makes it worse) replaces it.
constexpr const char* kNewtonFallbackRemedy = "a smoother base (a larger detail scale) usually removes them";

struct NormalDisplacementOptions {
  //! Newton steps per vertex (a step that walks to a neighbouring triangle is counted as a walk instead).
  int max_iterations = 20;
  //! Converged when the part of p − b orthogonal to n(b) is at most tolerance · (bounding-box diagonal of B).
  double tolerance = 1e-12;
  //! Walks from a triangle to its neighbour per vertex before the search gives up.
  int max_walks = 64;
  //! \throw InvalidInput naming the first option out of its range (max_iterations and max_walks >= 0, a
  //! finite tolerance > 0) as NormalDisplacementOptions::NAME.
  void validate() const;
};

//! Normal-displacement detail encoding ("normal"). encode() finds, for every vertex p of S, a point b
//! on B with p − b parallel to the Phong normal n(b): it starts at the closest point of B (Embree; where B
//! has S's connectivity (Fs = Fb), on p's own connected component of B, so a nearer second sheet or the
//! far side of a UV seam does not capture it), runs
//! Gauss–Newton on f(α, β) = (p − b(α, β)) × m(α, β) with γ = 1 − α − β and m = α n_a + β n_b + γ n_c
//! (same roots as with the normalised n of the seed, but f is then polynomial), and walks to the
//! neighbouring triangle across the edge whose barycentric coordinate turns negative. Vertex normals of B
//! are area weighted (VertexNormals). Where the search fails (iteration or walk cap, singular Jacobian,
//! a boundary in the way) the vertex falls back to its closest point on B with the Phong normal there;
//! such vertices are listed in report() and are not reproduced exactly by reconstruct(B) (the part of
//! p − b tangent to B is dropped).
//!
//! reconstruct() recomputes B' vertex normals into a member buffer and interpolates: O(#Vs + #Vb),
//! parallel, allocation-free once `out` has #Vs rows. Not safe to call concurrently on one object.
//! With placed vertices (set_placed_vertices()) it interpolates only the others, and computes only the
//! B' normals their base triangles read.
class NormalDisplacements : public DetailEncoding {
 public:
  //! What encode() found.
  struct EncodeReport {
    int converged = 0;                   //!< vertices whose Newton search met the tolerance
    int fallback = 0;                    //!< vertices that fell back to their closest point
    std::vector<int> fallback_vertices;  //!< their indices in S, ascending
    long walks = 0;                      //!< triangle-to-triangle walks over all vertices
    int max_iterations_used = 0;         //!< most Newton steps any converged vertex needed
  };

  explicit NormalDisplacements(const NormalDisplacementOptions& options = {});

  std::string name() const override { return "normal"; }

  //! S: #Vs by 3 (Fs is not used: S only contributes points); B: #Vb by 3 with faces Fb (#Fb by 3).
  //! \throw InvalidInput if Fb is empty or indexes out of range, a coordinate is non-finite, or an option
  //! is out of range (negative counts, non-positive tolerance).
  void encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) override;

  //! S' (#Vs by 3) on the deformed base B' (#Vb by 3, connectivity Fb of encode()).
  //! \throw UsageError before encode() or when B' does not have #Vb rows; InvalidInput if B' has a
  //! non-finite coordinate (with placed vertices: in a row the other vertices read).
  void reconstruct(const Positions& B_deformed, Positions& out) override;

  //! Base points b'(α, β, γ) (#Vs by 3) on a base with the encoded connectivity (B itself or a deformed B').
  //! \throw UsageError as reconstruct().
  void base_points(const Positions& B, Positions& out) const;

  bool encoded() const { return num_base_vertices_ >= 0; }
  const NormalDisplacementOptions& options() const { return options_; }
  const EncodeReport& report() const { return report_; }
  //! One sentence when some vertices fell back to their closest point (count and the first ids), placed
  //! vertices left out: their position is the caller's.
  std::vector<std::string> encode_warnings() const override;
  //! #Vs face indices into Fb: the base triangle of each vertex of S.
  const Eigen::VectorXi& base_faces() const { return face_; }
  //! #Vs by 3 barycentrics (α, β, γ) in that triangle (sum 1; each ≥ −1e-10 for converged vertices).
  const Eigen::MatrixX3d& barycentrics() const { return barycentric_; }
  //! #Vs signed heights h = (p − b) · n(b).
  const Eigen::VectorXd& heights() const { return height_; }

 private:
  NormalDisplacementOptions options_;
  Faces base_faces_;
  int num_base_vertices_ = -1;
  VertexNormals normals_;
  RowPositions normal_buffer_;  // #Vb by 3, per-frame vertex normals of B' (row-major: gathered per corner)
  // The encoding once more, sorted by base face: reconstruct() then reads B' and its normals almost
  // sequentially (the vertex order of S, e.g. of a Loop-refined mesh, scatters them).
  struct Sample {
    int corner[3], vertex;  // the base triangle's corners (no lookup in Fb per frame)
    double w[3], h;
  };
  std::vector<Sample> samples_;
  Eigen::VectorXi face_;
  Eigen::MatrixX3d barycentric_;
  Eigen::VectorXd height_;
  EncodeReport report_;
  std::vector<int> reconstructed_fallbacks_;  // report_.fallback_vertices that are not placed
  int reconstructed_vertices_ = 0;            // vertices that are not placed (a frame reconstructs them)
};

//! One-shot: the signed normal-displacement heights (#Vs) of S over the base (B, Fb), e.g. to measure
//! how much a deformation distorted the details. \throw as NormalDisplacements::encode().
Eigen::VectorXd normal_displacement_heights(const Positions& S, const Positions& B, const Faces& Fb,
                                            const NormalDisplacementOptions& options = {});

}  // namespace msd
