#include "apps/msdeform/edit_case.h"

#include <cstdio>
#include <tuple>

#include "msdeform/core/atomic_file.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/scenes.h"

namespace msd::cli {

void EditCaseOptions::add_to(CLI::App& cmd, bool with_transforms) {
  auto* mesh_opt = cmd.add_option(
      "mesh", mesh, "Mesh file (.off .obj .ply .stl); soups and point clouds for space methods");
  auto* sel_opt =
      cmd.add_option("--sel", sel, "Region: .sel (0 fixed, 1 free, 2+k handle k) or .dmat groups (-1 free, k handle k)");
  // A scene brings its own region and transforms: files given with it would be silently ignored.
  auto* scene_opt =
      cmd.add_option("--scene", scene, "Built-in scene instead of files (it has its own region and transforms): lift, "
                                       "bend120, twist135, bar-lift, bar-bend120, bar-twist135, crease120 (Fig. 9.10)")
          ->excludes(mesh_opt)
          ->excludes(sel_opt);
  if (with_transforms)
    scene_opt->excludes(cmd.add_option("--def", def, "Handle transforms: .def, one 4x4 matrix per handle"));
  cmd.add_option("--resolution", resolution, "Approximate vertex count of a built-in scene (e.g. 10k, 100k, 1M)")
      ->capture_default_str();
  cmd.add_flag("--force", force, "Let an output replace one of the input files (refused otherwise)");
  region.add_to(cmd, with_transforms);
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
  for (const std::string& f : region.input_files()) inputs.push_back(f);
  inputs.insert(inputs.end(), other_inputs.begin(), other_inputs.end());
  for (const std::string& input : inputs)
    if (!input.empty() && same_file(output, input))
      throw InvalidInput(std::string(option) + " " + output + " is one of the inputs; it would be replaced. Write "
                         "elsewhere, or give --force");
}

EditCase EditCaseOptions::load(bool need_transforms, bool need_region) const {
  std::vector<std::string> inputs = {mesh, sel, def};
  for (const std::string& f : region.input_files()) inputs.push_back(f);
  for (const auto& [path, option, ext] : {std::tuple{region.write_sel, "--write-sel", ".sel"},
                                          {region.write_def, "--write-def", ".def"}}) {
    if (path.empty()) continue;
    if (file_extension(path) != ext)
      throw InvalidInput(std::string(option) + " " + path + ": the file is written in the " + ext + " format; name it " +
                         "NAME" + ext);
    check_writable(path, option);
    for (const std::string& input : inputs)
      if (!force && !input.empty() && same_file(path, input))
        throw InvalidInput(std::string(option) + " " + path + " is one of the inputs; it would be replaced. Write "
                           "elsewhere, or give --force");
  }
  const bool built_region = region.builds_region(), built_transforms = region.builds_transforms();
  EditCase c;
  if (!scene.empty()) {
    if (built_region || built_transforms)
      throw InvalidInput("--scene brings its own region and transforms; --fixed, --handle, --translate, --rotate and "
                         "--scale apply to a mesh file");
    c = scene_case(scene, parse_resolution(resolution));
  } else {
    if (mesh.empty()) throw InvalidInput("give a mesh file with a region (--sel, or --fixed / --handle), or a built-in --scene");
    if (!sel.empty() && built_region) throw InvalidInput("give the region by --sel or by --fixed / --handle, not both");
    if (!def.empty() && built_transforms)
      throw InvalidInput("give the transforms by --def or by --translate / --rotate / --scale, not both");
    if (sel.empty() && !built_region && need_region)
      throw InvalidInput("a mesh file needs a region: --sel FILE, or --fixed / --handle selections");
    const bool transforms_from_file = need_transforms && (!sel.empty() || built_region) && !built_transforms;
    if (transforms_from_file && def.empty())
      throw InvalidInput("a mesh file needs handle transforms: --def FILE, or --translate / --rotate / --scale");
    if (file_extension(mesh) == ".stl" && !sel.empty())
      std::fprintf(stderr,
                   "warning: %s: STL keeps no vertex list, so its vertices are numbered by first appearance "
                   "(coincident corners merged); a .sel made for another file of this mesh selects other "
                   "vertices here (.ply, .off and .obj keep the file's numbering)\n",
                   mesh.c_str());
    c = load_edit_case(mesh, sel, transforms_from_file ? def : std::string());
    note_faces_changed(c, mesh);
    if (built_region) c.region = region.build_region(c.P, c.F);
    if (transforms_from_file && built_region && static_cast<int>(c.transforms.size()) != c.region.num_handles())
      throw InvalidInput(def + " has " + std::to_string(c.transforms.size()) + " matrices but --handle selected " +
                         std::to_string(c.region.num_handles()) + " handle(s)");
    if (built_transforms) {
      if (c.region.num_vertices() == 0) throw InvalidInput("--translate, --rotate and --scale need a region with handles");
      c.transforms = region.build_transforms(c.P, c.region);
    }
  }
  if (!region.write_sel.empty() && c.region.num_vertices() == 0)
    throw InvalidInput("--write-sel: there is no region to write");
  if (!region.write_def.empty() && c.transforms.empty())
    throw InvalidInput("--write-def: there are no transforms to write");
  return c;
}

void EditCaseOptions::write_built(const Region& built_region, const std::vector<Mat4>& transforms) const {
  if (!region.write_sel.empty()) write_sel(built_region, region.write_sel);
  if (!region.write_def.empty()) write_def(transforms, region.write_def);
}

void note_faces_changed(const EditCase& c, const std::string& mesh) {
  if (const std::string changed = faces_changed_on_load(c.load_report); !changed.empty())
    std::fprintf(stderr, "note: %s: %s; the meshes written list the faces as loaded\n", mesh.c_str(),
                 changed.c_str());
}

}  // namespace msd::cli
