#pragma once
//! \file Generated benchmark scenes of the seed (Figs. 9.4, 9.5, 9.10, 9.16): a bumpy plane and a bumpy
//! bar, each with lift / bend / twist edits. Meshes are uniform Loop refinements of a coarse mesh, so
//! they also serve the subdivision-based multi-scale hierarchy.

#include <string>
#include <vector>

#include "msdeform/core/region.h"
#include "msdeform/core/subdivision.h"

namespace msd {

enum class SceneShape { Plane, Bar };
enum class SceneEdit { Lift, Bend, Twist };

//! Geometry of the generated surfaces (lengths in scene units; the plane is the unit square).
struct SceneOptions {
  int resolution = 10000;     //!< approximate vertex count (the nearest Loop-refinement size is used)
  double bump_height = 0.05;  //!< height of the smooth bumps
  double bump_radius = 0.045; //!< radius of each bump (bumps sit on a 0.1 lattice and do not overlap)
  double bar_radius = 0.15;   //!< radius of the bumpy bar (a tube along x of length 1)
  double fixed_end = 0.2;     //!< vertices with x below this are fixed
  double handle_start = 0.8;  //!< vertices with x above this are the handle (the free region lies between)
};

//! A deformation benchmark: the detailed surface, its region, and one transform per handle.
struct Scene {
  std::string name;
  Positions P;       //!< #V by 3 detailed surface S
  Faces F;           //!< #F by 3
  Positions smooth;  //!< #V by 3 the same surface without bumps (the analytic base surface)
  Positions smooth_normals;  //!< #V by 3 analytic unit normals of `smooth`
  Eigen::VectorXd heights;   //!< #V analytic bump heights: P = smooth + heights * smooth_normals
  Region region;             //!< fixed x < fixed_end, handle x > handle_start, free between
  std::vector<Mat4> transforms;  //!< one rigid transform for the handle
  // The coarse control mesh the surface was refined from (for subdivision-based hierarchies).
  Positions coarse_P;
  Faces coarse_F;
  LoopRefinement refinement;
  double bump_height = 0;
};

//! The generated surface (no edit yet: region set, transforms empty).
Scene make_surface(SceneShape shape, const SceneOptions& options = {});

//! The surface with an edit. amount: lift height (scene units) or bend / twist angle in degrees.
//! Bend maps the handle to where a circular arc through the free region would take it (the arc's
//! radius is free length / angle); twist rotates the handle about the surface's long axis; lift
//! translates it along z. \throw InvalidInput for a non-finite amount.
Scene make_scene(SceneShape shape, SceneEdit edit, double amount, const SceneOptions& options = {});

//! A built-in scene by name: lift, bend120, twist135 (bumpy plane) and bar-lift, bar-bend120,
//! bar-twist135 (bumpy bar). \throw InvalidInput naming the known scenes for an unknown name.
Scene make_scene(const std::string& name, const SceneOptions& options = {});
std::vector<std::string> scene_names();

//! Writes NAME.off, NAME.sel and NAME.def into folder dir (created if missing), atomically.
void write_scene(const Scene& scene, const std::string& dir);

//! Parses a resolution such as "10000", "100k" or "1M". \throw InvalidInput on anything else.
int parse_resolution(const std::string& text);

}  // namespace msd
