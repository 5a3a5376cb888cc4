#pragma once
//! \file The mesh type and its conversions to and from bulk Eigen arrays.

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <vector>

#include "msdeform/core/checks.h"
#include "msdeform/core/types.h"

namespace msd {

struct MeshTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};

//! Triangle mesh with double-precision points. OpenMesh provides connectivity, circulators and
//! halfedge queries; hot numerical paths work on positions() / faces() arrays instead.
using Mesh = OpenMesh::TriMesh_ArrayKernelT<MeshTraits>;

//! #V by 3 vertex positions, in vertex-index order.
Positions positions(const Mesh& mesh);

//! Writes #V by 3 positions back into the mesh. \throw InvalidInput if the row count differs from #V.
void set_positions(Mesh& mesh, const Positions& P);

//! #F by 3 vertex indices of the faces, in face-index order.
Faces faces(const Mesh& mesh);

//! Builds a mesh from arrays. \throw InvalidInput on an index out of range, a repeated index in a face,
//! a non-finite coordinate, or a face that would make an edge non-manifold.
Mesh make_mesh(const Positions& P, const Faces& F);

//! Area-weighted unit vertex normals of (P, F) as #V by 3. Vertices without a non-degenerate incident
//! face get (0, 0, 0). For repeated evaluation on one connectivity use VertexNormals.
Positions vertex_normals(const Positions& P, const Faces& F);

//! Area-weighted vertex normals for frame loops. The constructor orders each vertex's one-ring once; a
//! compute() then sums (v_t − p) × (v_{t+1} − p) over consecutive ring neighbours (twice the area-weighted
//! face normals) without any per-face intermediate: O(#V), parallel, allocation-free once N is sized.
//! Where the CPU has AVX2, fans of equal length are summed four vertices at a time, with the same
//! operations in the same order per vertex: the normals are the same to the last bit either way.
class VertexNormals {
 public:
  VertexNormals() = default;
  VertexNormals(const Faces& F, int num_vertices);
  //! From now on the normals of only `vertices` (ascending, each below #V): compute() writes their rows
  //! and leaves the other rows of N as they are, for frame loops that read a part of the normals (the
  //! detail reconstruction around a region of interest). \throw InvalidInput on an index out of range or
  //! out of order (and the normals stay as they were).
  void restrict_to(std::vector<int> vertices);
  //! Unit normals of positions P (#V by 3) into N (#V by 3, resized only when its size is wrong).
  void compute(const Positions& P, Positions& N) const;
  //! The same into a row-major buffer, for callers that then gather normals by vertex.
  void compute(const Positions& P, RowPositions& N) const;

 private:
  // Writes vertex v's coordinate c to out[v · vertex_stride + c · coordinate_stride].
  void compute_into(const Positions& P, double* out, long vertex_stride, long coordinate_stride) const;
  // Sorts the vertices compute() writes (all, or subset) into the lanes and single_ below.
  void plan(const std::vector<int>* subset);
  enum Kind : unsigned char { kIsolated, kFan, kFacePairs };
  // Per vertex: its fan of neighbours (a closed fan repeats its first at the end) or the (j, k) pairs of
  // its faces where the one-ring is not a fan.
  std::vector<int> offsets_, ring_;
  std::vector<unsigned char> kind_;
  // The vertices compute() writes: fans summed four at a time (AVX2), group g being vertices
  // lane_vertices_[4g .. 4g + 3], all with fans of one length, whose fans lane_ring_ holds interleaved from
  // lane_offsets_[g] (position t of lane i at 4t + i); and the others one at a time (single_).
  std::vector<int> lane_vertices_, lane_ring_, lane_offsets_, single_;
};

//! The faces around each vertex: faces[offsets[v] .. offsets[v + 1]) are the rows of F containing v,
//! in ascending order.
struct VertexFaces {
  std::vector<int> offsets, faces;
};
VertexFaces vertex_faces(const Faces& F, int num_vertices);

//! Axis-aligned bounding box diagonal length of P (0 for fewer than two points).
double bounding_box_diagonal(const Positions& P);
//! Centre of P's axis-aligned bounding box (zero for no points): the origin that keeps a model far from the
//! world origin at its precision in the computations relative to it.
Vec3 bounding_box_centre(const Positions& P);

}  // namespace msd
