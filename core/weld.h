#pragma once
//! \file Seams: meshes split along coincident boundary vertices (converted game and glTF assets) deform
//! as separate pieces. Counting them, and welding vertices within a distance so that a method sees one
//! surface while the file keeps its vertices.

#include <string>
#include <vector>

#include "msdeform/core/types.h"

namespace msd {

//! The vertices of open seams: boundary vertices (on an edge of exactly one face) within eps (mesh units; 0:
//! at the same coordinates) of another boundary vertex, on a boundary edge that lies on another boundary
//! edge (both ends within eps). Boundary vertices that meet another only at a point (holes touching at a
//! vertex) are not counted: welding them would make the vertex non-manifold. O(#V + #F) expected.
//! \throw InvalidInput for a negative or non-finite eps, or a face index outside [0, #V).
int count_seam_vertices(const Positions& P, const Faces& F, double eps = 0);

//! A mesh with its seam vertices within a distance merged, and the way back.
struct Weld {
  //! #V: each original vertex's vertex in the welded mesh. Vertices chained within eps are one group; a
  //! group's welded vertex sits at its lowest-numbered member, and groups are numbered in that order.
  std::vector<int> welded_of;
  Positions P;     //!< #W by 3 welded positions
  Faces F;         //!< the faces re-indexed (none loses a corner: an edge's ends are never merged)
  int merged = 0;  //!< #V − #W
  //! Positions of the welded mesh (#W by 3) back on the original vertices (#V by 3): every member of a
  //! group gets its group's position. \throw InvalidInput for a row count other than #W.
  Positions unweld(const Positions& welded) const;
  //! The file's vertex of welded vertex w: its group's lowest-numbered member. \throw InvalidInput for w
  //! outside [0, #W).
  int file_vertex(int w) const;
  //! A message of a method that ran on the welded mesh, with the vertices it names ("vertex 12",
  //! "vertices 3, 5, 8") renumbered to the file's (file_vertex), so the user finds them in the file.
  std::string in_file_numbering(const std::string& message) const;
};

//! Merges the vertices of open seams (count_seam_vertices) within eps of each other (eps in mesh units; 0:
//! identical coordinates only). Other vertices within eps stay apart, as interior twins (CGAL's cow has
//! one pair) and holes touching at a point: merging them would pinch the surface into a non-manifold
//! vertex. \throw InvalidInput for a negative or non-finite eps, a face index outside [0, #V), or an eps
//! that would merge the two ends of an edge (chaining along the boundary, it collapsed whole loops).
Weld weld_vertices(const Positions& P, const Faces& F, double eps);

}  // namespace msd
