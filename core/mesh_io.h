#pragma once
//! \file Loading and saving triangle meshes: OFF, OBJ, PLY, STL (chosen by the file extension).

#include <string>

#include "core/mesh.h"

namespace msd {

//! What load_mesh had to do to turn the file into a manifold triangle mesh.
struct LoadReport {
  int polygons_triangulated = 0;    //!< faces with more than 3 corners, split into fans from their first corner
  int degenerate_faces_skipped = 0; //!< faces that repeat a vertex index (dropped)
  int nonmanifold_faces = 0;        //!< faces that would make an edge or vertex non-manifold
  int duplicated_vertices = 0;      //!< copies appended after the file's vertices to add those faces
};

//! Loads a mesh. The file's vertices keep their order and indices exactly (selection files index them);
//! polygons are triangulated; faces that cannot be added to a manifold mesh get private copies of their
//! vertices appended after the file's vertices (counted in the report).
//! \throw InvalidInput with file and line for: a missing or unreadable file, an unknown extension, a
//! malformed header or number, a non-finite coordinate, a face index out of range, an empty mesh.
Mesh load_mesh(const std::string& path, LoadReport* report = nullptr);

//! Optional extras for save_mesh.
struct SaveOptions {
  const Eigen::VectorXd* vertex_scalar = nullptr;  //!< #V values written as a PLY vertex property
  std::string scalar_name = "quality";             //!< name of that property
};

//! Saves (P, F) to path, format by extension (.off .obj .ply .stl). Written to a temporary file and
//! renamed, so a failed save leaves any existing file untouched. Full double precision.
//! \throw InvalidInput for an unknown extension, a scalar with a non-PLY format or of the wrong size,
//! non-finite positions, or an unwritable path.
void save_mesh(const Positions& P, const Faces& F, const std::string& path, const SaveOptions& options = {});
void save_mesh(const Mesh& mesh, const std::string& path, const SaveOptions& options = {});

//! Lower-case extension of path including the dot ("" if none).
std::string file_extension(const std::string& path);

}  // namespace msd
