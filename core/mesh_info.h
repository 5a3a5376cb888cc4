#pragma once
//! \file Summary statistics of a mesh, for `msdeform info` and for checking inputs.

#include "core/mesh.h"
#include "core/mesh_io.h"

namespace msd {

struct MeshInfo {
  int vertices = 0, faces = 0, edges = 0;
  int components = 0;            //!< connected components of faces
  int boundary_loops = 0;
  int isolated_vertices = 0;     //!< vertices without a face
  int degenerate_faces = 0;      //!< zero-area faces (see cotan_laplacian)
  int nonmanifold_vertices = 0;  //!< vertices whose faces do not form one fan
  int nonmanifold_faces = 0;     //!< faces the loader had to detach (from the LoadReport)
  Vec3 bbox_min = Vec3::Zero(), bbox_max = Vec3::Zero();
  double mean_edge_length = 0;
  int euler_characteristic = 0;  //!< V - E + F
};

//! Statistics of mesh; pass the loader's report to include what loading had to repair.
MeshInfo mesh_info(const Mesh& mesh, const LoadReport* report = nullptr);

}  // namespace msd
