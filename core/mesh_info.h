#pragma once
//! \file Summary statistics of a mesh, a soup or a point cloud, for `msdeform info` and for checking inputs.

#include <string>

#include "msdeform/core/mesh.h"

namespace msd {

struct MeshInfo {
  int vertices = 0, faces = 0;
  int edges = 0;                     //!< distinct vertex pairs of faces
  int components = 0;                //!< pieces of faces connected through shared vertices
  int boundary_edges = 0;            //!< edges in exactly one face
  int boundary_loops = 0;            //!< connected curves of boundary edges
  int unreferenced_vertices = 0;     //!< vertices no face uses (all of a point cloud's)
  int seam_vertices = 0;             //!< boundary vertices at another's coordinates (count_seam_vertices)
  //! Boundary vertices within near_seam_distance (1e-3 of the mean edge length) of another boundary
  //! vertex, where seam_vertices is 0: a seam whose copies were written with rounding (deform --weld EPS).
  int near_seam_vertices = 0;
  double near_seam_distance = 0;
  int degenerate_faces = 0;          //!< zero-area faces (see cotan_laplacian)
  int nonmanifold_edges = 0;         //!< edges in more than two faces
  int nonmanifold_vertices = 0;      //!< vertices whose faces do not form one fan
  int nonorientable_components = 0;  //!< components that cannot be oriented consistently
  int flipped_faces = 0;             //!< faces wound against their neighbours (the loaders turn them over)
  std::string surface_problem;       //!< SurfaceCheck::problem(): empty for a manifold triangle mesh
  //! check_extent()'s refusal (sizes beyond 1e-70..1e70, or no extent): empty when the sizes are fine
  std::string size_problem;
  Vec3 bbox_min = Vec3::Zero(), bbox_max = Vec3::Zero();
  double mean_edge_length = 0;   //!< over the distinct edges
  int euler_characteristic = 0;  //!< V - E + F
};

//! Statistics of the triangles F (#F by 3, any soup, #F may be 0) over the vertices P (#V by 3), taken
//! as they are: F is not reoriented (flipped_faces counts what check_surface would turn over).
//! \throw InvalidInput for a face index outside [0, #V).
MeshInfo mesh_info(const Positions& P, const Faces& F);
MeshInfo mesh_info(const Mesh& mesh);

}  // namespace msd
