#include "apps/msdeform/edit_case.h"

#include "msdeform/core/errors.h"
#include "msdeform/core/scenes.h"

namespace msd::cli {

void EditCaseOptions::add_to(CLI::App& cmd) {
  auto* mesh_opt = cmd.add_option(
      "mesh", mesh, "Mesh file (.off .obj .ply .stl); soups and point clouds for space methods");
  auto* sel_opt =
      cmd.add_option("--sel", sel, "Region: .sel (0 fixed, 1 free, 2+k handle k) or .dmat groups (-1 free, k handle k)");
  auto* def_opt = cmd.add_option("--def", def, "Handle transforms: .def, one 4x4 matrix per handle");
  // A scene brings its own region and transforms: files given with it would be silently ignored.
  cmd.add_option("--scene", scene, "Built-in scene instead of files (it has its own region and transforms): lift, "
                                   "bend120, twist135, bar-lift, bar-bend120, bar-twist135")
      ->excludes(mesh_opt)
      ->excludes(sel_opt)
      ->excludes(def_opt);
  cmd.add_option("--resolution", resolution, "Approximate vertex count of a built-in scene (e.g. 10k, 100k, 1M)")
      ->capture_default_str();
}

EditCase EditCaseOptions::load(bool need_transforms, bool need_region) const {
  if (!scene.empty()) return scene_case(scene, parse_resolution(resolution));
  if (mesh.empty()) throw InvalidInput("give a mesh file with --sel and --def, or a built-in --scene");
  if (sel.empty() && need_region) throw InvalidInput("a mesh file needs --sel (the region)");
  if (!sel.empty() && need_transforms) {
    if (def.empty()) throw InvalidInput("a mesh file needs --def (the handle transforms)");
    return file_case(mesh, sel, def);
  }
  return load_edit_case(mesh, sel);  // the mesh, and the region when --sel is given
}

}  // namespace msd::cli
