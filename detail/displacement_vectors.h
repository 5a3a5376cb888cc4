#pragma once
//! \file Displacement vectors in local frames (seed 9.3.1, eq. 9.8): S and B share connectivity, and each
//! vertex keeps h_i = p_i − b_i as coefficients in the frame (n_i, t_i1, t_i2) of the base at b_i:
//!   h_i = α_i n_i + β_i t_i1 + γ_i t_i2,   p'_i = b'_i + α_i n'_i + β_i t'_i1 + γ_i t'_i2.

#include <string>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "msdeform/core/types.h"
#include "msdeform/detail/encoding.h"

namespace msd {
namespace phong {
struct Columns;
}

//! Orthonormal per-vertex frames (n, t1, t2) of a mesh, with t2 = n × t1 (right-handed):
//! - n: the area-weighted unit vertex normal (as VertexNormals), except that faces of area below 1e-14
//!   times their squared longest edge count as zero-area, and a sum that cancels to below 1e-12 of the
//!   total weight counts as no normal: rounding noise of degenerate faces never becomes a direction.
//! - t1: the normalised projection of the vertex's *first incident edge* into the plane orthogonal to n.
//!   Incident edges are ordered by the face list: walking faces in index order, a face (i, j, k)
//!   contributes, for its corner i, the edges to j then k (for corner j: k then i; for corner k: i then j),
//!   skipping neighbours already listed. So the first incident edge of v runs to the vertex after v in
//!   the lowest-indexed face holding v. An edge whose projection is shorter than 1e-6 times its length
//!   (parallel to n, or of zero length) is skipped for the next one (seed: "first edge" heuristic).
//! - If every incident edge is skipped: t1 is the world axis least aligned with n, projected into the
//!   tangent plane (not rotation-equivariant, but defined). A vertex without normal (no incident face of
//!   positive area) gets the world frame (n, t1, t2) = (z, x, y): its detail is kept in world coordinates.
//! Frames are a function of positions only; compute() is O(#V + #F), parallel (it allocates #F by 4
//! doubles for the face normals).
class VertexFrames {
 public:
  VertexFrames() = default;
  //! Connectivity F (#F by 3) over num_vertices vertices. \throw InvalidInput on an index out of range.
  VertexFrames(const Faces& F, int num_vertices);
  //! Frames at positions P (#V by 3) into N, T1, T2 (each #V by 3, resized only when their size is wrong).
  //! \throw UsageError if P does not have #V rows.
  void compute(const Positions& P, Positions& N, Positions& T1, Positions& T2) const;
  //! The neighbours of v in the order their edges are tried for t1.
  std::vector<int> edge_order(int v) const;
  int num_vertices() const { return static_cast<int>(offsets_.size()) - 1; }

 private:
  friend class DisplacementVectors;  // reconstructs from each frame as it is computed
  //! A frame's first pass: for entries [k0, k1) of `list` (face k when null), the face's normal at
  //! positions X (length 2 · area) and its length into out[4k .. 4k + 3] (zeros for a zero-area face).
  void face_normals(const phong::Columns& X, const int* list, long k0, long k1, double* out) const;
  //! Its second pass: the frame of vertex v at X, its i-th face's normal (incident_faces_[face_offsets_[v] +
  //! i]) read at normals + 4 · slots[face_offsets_[v] + i].
  void frame(const phong::Columns& X, long v, const int* slots, const double* normals, Vec3& n, Vec3& t1,
             Vec3& t2) const;

  Faces F_;
  std::vector<int> face_offsets_{0}, incident_faces_;  // CSR: faces around each vertex
  std::vector<int> offsets_{0}, neighbours_;           // CSR: ordered, distinct neighbours of each vertex
};

//! Where the displacement vectors live.
enum class DisplacementFrame {
  Local,   //!< in the base's local frames (seed eq. 9.8): details rotate with the base
  Global,  //!< in world coordinates (h_i as is): details translate but never rotate (seed Fig. 9.8, left)
};

struct DisplacementVectorOptions {
  DisplacementFrame frame = DisplacementFrame::Local;
};

//! Displacement-vector detail encoding ("vectors"). S and B must share connectivity.
//! reconstruct() is O(#V), parallel and allocation-free once `out` is sized; not safe to call
//! concurrently on one object. With placed vertices (set_placed_vertices()) and local frames it computes
//! the frames and rows of the other vertices only.
class DisplacementVectors : public DetailEncoding {
 public:
  explicit DisplacementVectors(const DisplacementVectorOptions& options = {});

  std::string name() const override { return "vectors"; }
  bool needs_same_connectivity() const override { return true; }

  //! S and B: #V by 3 each; Fs must equal Fb (#F by 3).
  //! \throw InvalidInput if the vertex counts or face lists differ, an index is out of range or a
  //! coordinate is non-finite.
  void encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) override;

  //! S' (#V by 3) on the deformed base B' (#V by 3).
  //! \throw UsageError before encode() or when B' has the wrong number of rows; InvalidInput if the result
  //! would be non-finite (a non-finite coordinate in B'; with placed vertices, in a row the others read).
  void reconstruct(const Positions& B_deformed, Positions& out) override;

  bool encoded() const { return encoded_; }
  const DisplacementVectorOptions& options() const { return options_; }
  //! #V by 3: (α, β, γ) of (9.8) for Local, the world vector p − b for Global.
  const Eigen::MatrixX3d& coefficients() const { return coefficients_; }
  const VertexFrames& frames() const { return frames_; }

 private:
  DisplacementVectorOptions options_;
  VertexFrames frames_;
  bool encoded_ = false;
  Eigen::MatrixX3d coefficients_;
  // With placed vertices: the vertices a frame reconstructs (all when all_vertices_).
  bool all_vertices_ = true;
  std::vector<int> frame_vertices_;
  // Local frames: those vertices in blocks (kFrameBlock consecutive entries); block k reads the normals of
  // faces block_faces_[block_face_offsets_[k] ..], which a frame computes into this thread's buffer, and
  // the i-th incident face of VertexFrames (incident_faces_[i]) at slot face_slots_[i] of its block's list.
  std::vector<int> block_face_offsets_, block_faces_, face_slots_;
  tbb::enumerable_thread_specific<std::vector<double>> block_normals_;
};

}  // namespace msd
