#include "apps/msdeform/edit_case.h"

#include <filesystem>

#include "core/errors.h"
#include "core/mesh_io.h"
#include "core/scenes.h"

namespace msd::cli {

void EditCaseOptions::add_to(CLI::App& cmd) {
  auto* mesh_opt = cmd.add_option("mesh", mesh, "Mesh file (.off .obj .ply .stl)");
  cmd.add_option("--sel", sel, "Region: .sel (0 fixed, 1 free, 2+k handle k) or .dmat groups (-1 free, k handle k)");
  cmd.add_option("--def", def, "Handle transforms: .def, one 4x4 matrix per handle");
  cmd.add_option("--scene", scene, "Built-in scene instead of files: lift, bend120, twist135, bar-lift, bar-bend120, bar-twist135")
      ->excludes(mesh_opt);
  cmd.add_option("--resolution", resolution, "Approximate vertex count of a built-in scene (e.g. 10k, 100k, 1M)")
      ->capture_default_str();
}

EditCase EditCaseOptions::load() const {
  EditCase c;
  if (!scene.empty()) {
    SceneOptions options;
    options.resolution = parse_resolution(resolution);
    Scene s = make_scene(scene, options);
    c.name = s.name;
    c.mesh = make_mesh(s.P, s.F);
    c.region = std::move(s.region);
    c.transforms = std::move(s.transforms);
    return c;
  }
  if (mesh.empty()) throw InvalidInput("give a mesh file with --sel and --def, or a built-in --scene");
  if (sel.empty() || def.empty()) throw InvalidInput("a mesh file needs both --sel (region) and --def (handle transforms)");
  c.name = std::filesystem::path(mesh).stem().string();
  c.mesh = load_mesh(mesh);
  const int nv = static_cast<int>(c.mesh.n_vertices());
  c.region = file_extension(sel) == ".dmat" ? read_dmat_groups(sel, nv) : read_sel(sel, nv);
  c.transforms = read_def(def);
  if (static_cast<int>(c.transforms.size()) != c.region.num_handles())
    throw InvalidInput(def + " has " + std::to_string(c.transforms.size()) + " matrices but " + sel + " defines " +
                       std::to_string(c.region.num_handles()) + " handle(s)");
  return c;
}

double handle_error(const EditCase& c, const Positions& rest, const Positions& deformed) {
  double err = 0;
  for (int v = 0; v < c.region.num_vertices(); ++v) {
    if (c.region.is_free(v)) continue;
    const int k = c.region.handle_of(v);
    const Vec3 target = k < 0 ? Vec3(rest.row(v)) : transform_point(c.transforms[k], rest.row(v));
    err = std::max(err, (Vec3(deformed.row(v)) - target).norm());
  }
  return err;
}

}  // namespace msd::cli
