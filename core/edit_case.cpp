#include "msdeform/core/edit_case.h"

#include <filesystem>

#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/surface_check.h"

namespace msd {

EditCase scene_case(const std::string& scene, int resolution) {
  SceneOptions options;
  options.resolution = resolution;
  Scene s = make_scene(scene, options);
  auto control = std::make_shared<ControlMesh>(ControlMesh{std::move(s.coarse_P), std::move(s.coarse_F), std::move(s.refinement)});
  EditCase c;
  c.name = s.name;
  c.P = std::move(s.P);
  c.F = std::move(s.F);
  c.region = std::move(s.region);
  c.transforms = std::move(s.transforms);
  c.control = std::move(control);
  return c;
}

EditCase load_edit_case(const std::string& mesh, const std::string& sel, const std::string& def) {
  EditCase c;
  c.name = std::filesystem::path(mesh).stem().string();
  c.path = mesh;
  TriangleSoup soup = load_soup(mesh);
  c.P = std::move(soup.P);
  c.F = std::move(soup.F);
  c.surface_problem = check_surface(c.P, c.F).problem();  // orients the faces where it can
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

void require_surface(const EditCase& edit, const std::string& method) {
  if (edit.surface_problem.empty()) return;
  throw InvalidInput(method + " is a surface method and " + (edit.path.empty() ? edit.name : edit.path) +
                     " is not a manifold triangle mesh: " + edit.surface_problem +
                     ". Space methods deform any input: --method lattice, cage-mvc, cage-harmonic or rbf");
}

}  // namespace msd
