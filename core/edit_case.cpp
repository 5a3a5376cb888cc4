#include "core/edit_case.h"

#include <filesystem>

#include "core/errors.h"
#include "core/mesh.h"
#include "core/mesh_io.h"
#include "core/scenes.h"

namespace msd {

EditCase scene_case(const std::string& scene, int resolution) {
  SceneOptions options;
  options.resolution = resolution;
  Scene s = make_scene(scene, options);
  auto control = std::make_shared<ControlMesh>(ControlMesh{std::move(s.coarse_P), std::move(s.coarse_F), std::move(s.refinement)});
  return {s.name, std::move(s.P), std::move(s.F), std::move(s.region), std::move(s.transforms), std::move(control)};
}

EditCase load_edit_case(const std::string& mesh, const std::string& sel, const std::string& def) {
  EditCase c;
  c.name = std::filesystem::path(mesh).stem().string();
  {
    const Mesh m = load_mesh(mesh);
    c.P = positions(m);
    c.F = faces(m);
  }
  const int nv = static_cast<int>(c.P.rows());
  if (!sel.empty()) c.region = file_extension(sel) == ".dmat" ? read_dmat_groups(sel, nv) : read_sel(sel, nv);
  if (!def.empty()) {
    c.transforms = read_def(def);
    if (!sel.empty() && static_cast<int>(c.transforms.size()) != c.region.num_handles())
      throw InvalidInput(def + " has " + std::to_string(c.transforms.size()) + " matrices but " + sel + " defines " +
                         std::to_string(c.region.num_handles()) + " handle(s)");
  }
  return c;
}

EditCase file_case(const std::string& mesh, const std::string& sel, const std::string& def) {
  if (sel.empty()) throw InvalidInput("file_case: " + mesh + " needs a region file (.sel or .dmat)");
  if (def.empty()) throw InvalidInput("file_case: " + mesh + " needs a transforms file (.def)");
  return load_edit_case(mesh, sel, def);
}

}  // namespace msd
