#pragma once
//! \file What a triangle list is as a surface: non-manifold edges and vertices, orientation (repaired where
//! the surface is orientable), components and unreferenced vertices. Works on any face list (a soup, a
//! point cloud's empty one), so the loaders can keep a file's vertices exactly and say in words, with ids,
//! why a surface method cannot take it.

#include <string>
#include <vector>

#include "msdeform/core/types.h"

namespace msd {

//! An edge shared by more than two faces.
struct NonManifoldEdge {
  int a = -1, b = -1;      //!< its vertex ids, a < b
  std::vector<int> faces;  //!< the faces (rows of F) that contain it, ascending
};

//! The result of check_surface.
struct SurfaceCheck {
  int vertices = 0, faces = 0;
  int edges = 0;                                   //!< distinct vertex pairs of faces
  int boundary_edges = 0;                          //!< edges in exactly one face
  int components = 0;                              //!< pieces of faces connected through shared vertices
  int unreferenced_vertices = 0;                   //!< vertices no face uses (all of them for a point cloud)
  std::vector<NonManifoldEdge> nonmanifold_edges;  //!< ascending by (a, b)
  //! Vertices whose faces form more than one fan (e.g. two cones touching at their tips), ascending.
  std::vector<int> nonmanifold_vertices;
  //! Faces wound against the rest of their component, turned over by check_surface (in the smaller of the
  //! two ways to orient each orientable patch; ties keep the winding of the patch's first face).
  int flipped_faces = 0;
  //! One face per non-orientable patch (its lowest face id; a patch is a set of faces connected across
  //! edges shared by exactly two faces). Those patches are left as they were.
  std::vector<int> nonorientable_faces;
  //! The component (numbered 0.. in the order of their lowest face) of each such face.
  std::vector<int> nonorientable_components;
  //! Faces that repeat a vertex index, ascending (load_soup drops them before they get here).
  std::vector<int> degenerate_faces;
  //! Pairs (first, later) of faces with the same three vertices (load_soup drops them too).
  std::vector<std::pair<int, int>> duplicate_faces;

  //! The first problem that keeps the faces from being a manifold, orientable triangle mesh with at least
  //! one face, in words with ids (e.g. "edge (3, 7) is shared by 3 faces (0, 4, 9)"); empty when there is
  //! none. Multiple components, boundaries and unreferenced vertices are no problem.
  std::string problem() const;
  bool is_manifold_mesh() const { return problem().empty(); }
};

//! Checks the triangles F as a surface over the vertices of P and orients them consistently: per patch of
//! faces connected across manifold edges (a breadth-first search), faces wound against their neighbours
//! are turned over (two corners swapped) unless the patch is non-orientable.
//! \param P #V by 3 positions (only the count is used: faces may leave vertices unreferenced)
//! \param F #F by 3 vertex indices; orientation repaired in place, nothing else changes (no face is
//! removed, added or moved to another row)
//! Runs in O(#F α(#F)) plus small per-vertex sorts; 1M faces take a fraction of a second.
//! \throw InvalidInput for a vertex index outside [0, #V).
SurfaceCheck check_surface(const Positions& P, Faces& F);

}  // namespace msd
