#pragma once
//! \file Loading and saving meshes, soups and point clouds: OFF, OBJ, PLY, STL (chosen by the file
//! extension).

#include <string>

#include "msdeform/core/mesh.h"

namespace msd {

//! What loading did to the file's faces. The file's vertices are never changed, added or reordered.
struct LoadReport {
  //! Faces with more than 3 corners, split into triangles (in the plane of each one's normal): fans from
  //! their first corner, or where that fan has a sliver or turns a triangle over (a corner of nearly
  //! 180°, a concave polygon) the best-shaped split.
  int polygons_triangulated = 0;
  int polygons_split_otherwise = 0;  //!< of those, the ones not split into their first corner's fan
  //! Faces that repeat a vertex index other than in a row, or have fewer than 3 distinct corners (dropped).
  int degenerate_faces_skipped = 0;
  //! Faces listing a corner twice in a row (`4 a b c c`, or first and last): read without the repetition,
  //! as the polygon of the remaining corners.
  int repeated_corners_merged = 0;
  int duplicate_faces_dropped = 0;   //!< triangles with the vertex set of an earlier one (dropped)
  //! load_mesh, load_edit_case: triangles turned over to agree with their neighbours
  int faces_flipped = 0;
  //! OFF and ASCII PLY: the first line of data after the header's counts (ignored: the file holds more
  //! than its header declares), or 0.
  int first_ignored_line = 0;
  //! OFF: the first vertex or face line with numbers after its coordinates or indices (a COFF's colours,
  //! an NOFF's normals); OBJ: the first texture coordinate, normal, material, line or point statement (vt,
  //! vn, usemtl, mtllib, l, p) or vertex colour; PLY: the header line of the first property other than the
  //! coordinates and corner lists (colours, normals, face data). Read past and not kept (a written result
  //! holds positions and triangles); 0 if none.
  int first_attribute_line = 0;
};

//! What loading changed in the file's faces, in words ("1 duplicate face dropped, 3 polygons triangulated"),
//! or empty when the faces are the file's own: a written result lists the faces as loaded, so a tool says so.
std::string faces_changed_on_load(const LoadReport& report);

//! A file's vertices and triangles, whatever they form: a point cloud, a soup, a non-manifold or
//! inconsistently oriented mesh.
struct TriangleSoup {
  Positions P;  //!< #V by 3: the file's vertices, in its order
  Faces F;      //!< #F by 3 triangles in the file's face order (#F may be 0)
};

//! Loads a file as it is: its vertices exactly (count and order: selection files index them) and its
//! faces as triangles (polygons split as LoadReport::polygons_triangulated says; faces that repeat a vertex
//! index and triangles with the vertex set of an earlier one dropped, counted in the report). No face is
//! needed: an OFF with 0 faces, a PLY with only a vertex element or an OBJ with only `v` lines is a point
//! cloud. Orientation and manifoldness are not looked at (see check_surface). An STL's vertices are its
//! distinct corner positions in the order they first appear. \throw InvalidInput with file and line for: a
//! missing or unreadable file, an unknown extension, a malformed header or number, a non-finite coordinate, a
//! face index out of range, a polygon that crosses itself, no vertices at all.
TriangleSoup load_soup(const std::string& path, LoadReport* report = nullptr);

//! Loads a manifold triangle mesh: load_soup, then check_surface (core/surface_check.h). Faces wound
//! against their neighbours are turned over (counted in the report); the file's vertices keep their
//! order and count exactly.
//! \throw InvalidInput as load_soup, and for a file without faces (a point cloud).
//! \throw TopologyError naming the file and the edge, vertex or face ids for a non-manifold edge or
//! vertex or a non-orientable component (space methods take such input: load it with load_soup).
Mesh load_mesh(const std::string& path, LoadReport* report = nullptr);

//! Optional extras for save_mesh.
struct SaveOptions {
  const Eigen::VectorXd* vertex_scalar = nullptr;  //!< #V values written as a PLY vertex property
  std::string scalar_name = "quality";             //!< name of that property
};

//! Saves (P, F) to path, format by extension (.off .obj .ply .stl). Written to a temporary file and
//! renamed, so a failed save leaves any existing file untouched. Full double precision (STL: single).
//! Any face list is written as it is: a soup, or none at all (a point cloud) in .off, .obj and .ply.
//! STL keeps no vertex list: vertices no face uses are lost, and a point cloud is refused.
//! \throw InvalidInput for an unknown extension, a scalar with a non-PLY format, of the wrong size or
//! with a name PLY readers would misread (empty, with spaces or control characters, or x, y, z),
//! non-finite positions or scalars (naming the first vertex), an STL without faces, or an unwritable path.
void save_mesh(const Positions& P, const Faces& F, const std::string& path, const SaveOptions& options = {});
void save_mesh(const Mesh& mesh, const std::string& path, const SaveOptions& options = {});

//! What reading back save_mesh's STL of (P #V×3, F #F×3) gives: STL keeps no vertex list, so a reader
//! numbers the distinct corners in the order faces first use them.
struct StlReadBack {
  int vertices = 0;  //!< vertices of the file read back
  int unused = 0;    //!< vertices no face uses, lost
  int merged = 0;    //!< used vertices at the point of a lower-numbered one, joined with it
  //! The read-back numbering differs from P's (so a selection made for P no longer applies).
  bool renumbered = false;
};
//! \throw InvalidInput for an index of F outside [0, #V).
StlReadBack stl_read_back(const Positions& P, const Faces& F);

//! The values of a PLY file's per-vertex property `name` (#V, in the file's vertex order), e.g. the
//! 'detail' heights `msdeform decompose` writes or the 'detail_change' of `msdeform compare`'s meshes.
//! \throw InvalidInput for a file that is not PLY or does not read (as load_soup), or a vertex element
//! without that property (naming the properties it has).
Eigen::VectorXd load_vertex_property(const std::string& path, const std::string& name);

//! Lower-case extension of path including the dot ("" if none).
std::string file_extension(const std::string& path);

//! Checks that path has a mesh format msdeform reads and writes (.off .obj .ply .stl); `who` prefixes the
//! message. \throw InvalidInput naming the path and the extension.
void check_mesh_format(const std::string& path, const std::string& who);

}  // namespace msd
