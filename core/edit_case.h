#pragma once
//! \file An edit to run, as arrays: a shape, its region and one transform per handle, from a built-in scene
//! (core/scenes.h) or from files (a mesh with .sel / .dmat and .def). Used by the command line, the
//! comparison runner and the regression tests.

#include <memory>
#include <string>
#include <vector>

#include "msdeform/core/mesh_io.h"
#include "msdeform/core/region.h"
#include "msdeform/core/subdivision.h"
#include "msdeform/core/types.h"
#include "msdeform/core/weld.h"

namespace msd {

//! An edit: positions, faces, region and handle transforms.
struct EditCase {
  std::string name;                //!< the scene's name, or the mesh file's stem
  Positions P;                     //!< #V by 3 rest positions
  Faces F;                         //!< #F by 3 triangles
  Region region;                   //!< #V codes (empty when loaded without a region)
  std::vector<Mat4> transforms;    //!< one affine 4x4 per handle (empty when loaded without them)
  //! Built-in scenes: the Loop control mesh the surface refines (for a subdivision base); null for files.
  std::shared_ptr<const ControlMesh> control;
  std::string path;  //!< the mesh file, empty for built-in scenes
  LoadReport load_report;  //!< what loading the file dropped, triangulated or ignored (zeros for scenes)
  //! Why F is not a manifold, orientable triangle mesh with at least one face, in words with ids (see
  //! SurfaceCheck::problem, e.g. "no faces (a point cloud)"); empty when it is one. Surface methods need
  //! one (require_surface); space methods deform any input.
  std::string surface_problem;
  //! Boundary vertices at the coordinates of another boundary vertex (count_seam_vertices): a mesh split
  //! along seams, which deforms as separate pieces there unless welded (weld_case). 0 for built-in scenes.
  int seam_vertices = 0;
  //! Set by weld_case: the weld (Weld::unweld puts results back on the file's vertices) and the file's
  //! own faces, to write results with.
  std::shared_ptr<const Weld> weld;
  Faces file_F;
};

//! A built-in scene (core/scenes.h) at about `resolution` vertices as an edit case.
//! \throw InvalidInput for an unknown scene name.
EditCase scene_case(const std::string& scene, int resolution);

//! A mesh file with a .sel (or .dmat) region and a .def file. The file's vertices are kept exactly (count
//! and order) and its faces as triangles, whatever they form (load_soup): point clouds, soups and
//! non-manifold meshes load, with the reason recorded in surface_problem. Faces wound against their
//! neighbours are turned over where the surface is orientable. \throw InvalidInput naming the file, or the
//! mismatch between the handle count of the region and the number of matrices.
EditCase file_case(const std::string& mesh, const std::string& sel, const std::string& def);

//! A mesh file with an optional region and optional transforms: an empty `sel` leaves the region empty, an
//! empty `def` the transforms (for commands that need neither, e.g. a low-pass decomposition).
//! \throw InvalidInput naming the file, or the handle-count mismatch when both sel and def are given.
EditCase load_edit_case(const std::string& mesh, const std::string& sel = "", const std::string& def = "");

//! The edit with its vertices within eps (mesh units) welded (weld_vertices): a method then sees one
//! surface across seams; results go back on the file's vertices with edit.weld->unweld and are written
//! with edit.file_F, so the file's vertex count and order are kept. surface_problem and seam_vertices are
//! those of the welded mesh. \throw InvalidInput if welded vertices have different region labels (naming
//! both), or for a negative or non-finite eps.
EditCase weld_case(EditCase edit, double eps);

//! Refuses an edit that a surface method (or operation) cannot take: method is its name for the message.
//! \throw InvalidInput "<method> is a surface method and <file> is not a manifold triangle mesh:
//! <problem>. Space methods deform any input: ..." when edit.surface_problem is not empty (the last
//! sentence only for a deformation method: is_method).
void require_surface(const EditCase& edit, const std::string& method, bool is_method = true);

}  // namespace msd
