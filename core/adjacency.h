#pragma once
//! \file Vertex adjacency of a triangle array: the one builder every module uses for one-rings, the mesh
//! boundary and connected components (no OpenMesh needed below the editing seam).

#include <vector>

#include "msdeform/core/types.h"

namespace msd {

//! One-ring neighbours in compressed rows: the neighbours of v are indices[offsets[v] .. offsets[v + 1]),
//! ascending and without repeats. Built from the edges of F (a soup or a non-manifold mesh is fine);
//! repeated indices inside a face add no self-loop.
struct VertexAdjacency {
  std::vector<int> offsets, indices;
  int num_vertices() const { return static_cast<int>(offsets.size()) - 1; }
  int degree(int v) const { return offsets[v + 1] - offsets[v]; }
  const int* begin(int v) const { return indices.data() + offsets[v]; }
  const int* end(int v) const { return indices.data() + offsets[v + 1]; }
};

//! The adjacency of F (#F by 3, indices in [0, num_vertices); not checked here, see check_mesh_arrays).
VertexAdjacency vertex_adjacency(const Faces& F, int num_vertices);

//! Vertices on a boundary edge (an edge used by exactly one face), ascending.
std::vector<int> boundary_vertices(const Faces& F, int num_vertices);

//! The seed vertices and every vertex within `rings` edges of one (rings = 0: the seeds), ascending.
//! Seeds must be in [0, num_vertices).
std::vector<int> grow_rings(const Faces& F, int num_vertices, std::vector<int> seeds, int rings);

//! Vertices within `rings` rings of the mesh boundary, ascending: the boundary vertices for rings = 1,
//! plus their neighbours for 2, and so on; empty for rings <= 0.
std::vector<int> boundary_band(const Faces& F, int num_vertices, int rings);

//! Connected components through shared vertices: the component of each of the num_vertices vertices,
//! numbered 0, 1, … in the order of their first face in F; −1 for a vertex no face uses. The number of
//! components is the largest entry + 1.
std::vector<int> vertex_components(const Faces& F, int num_vertices);

}  // namespace msd
