#include "apps/msdeform/edit_case.h"

#include <cstdio>
#include <filesystem>

#include "msdeform/core/atomic_file.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
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
  cmd.add_flag("--force", force, "Let an output replace one of the input files (refused otherwise)");
}

bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (fs::exists(a, error) && fs::exists(b, error)) return fs::equivalent(a, b, error);
  return fs::weakly_canonical(a, error) == fs::weakly_canonical(b, error);
}

void EditCaseOptions::check_output(const std::string& output, const char* option,
                                   const std::vector<std::string>& other_inputs) const {
  check_mesh_format(output, option);
  check_writable(output, option);
  if (file_extension(output) == ".stl")
    std::fprintf(stderr, "warning: %s %s: STL keeps no vertex list, so the file loads with its vertices renumbered "
                         "(unused ones lost, coincident ones merged) and the input's .sel no longer applies; .ply, "
                         ".off and .obj keep them\n", option, output.c_str());
  if (force) return;
  std::vector<std::string> inputs = {mesh, sel, def};
  inputs.insert(inputs.end(), other_inputs.begin(), other_inputs.end());
  for (const std::string& input : inputs)
    if (!input.empty() && same_file(output, input))
      throw InvalidInput(std::string(option) + " " + output + " is one of the inputs; it would be replaced. Write "
                         "elsewhere, or give --force");
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
