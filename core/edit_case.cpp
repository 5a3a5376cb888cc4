#include "msdeform/core/edit_case.h"

#include <filesystem>

#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
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
  TriangleSoup soup = load_soup(mesh, &c.load_report);
  c.P = std::move(soup.P);
  c.F = std::move(soup.F);
  const SurfaceCheck surface = check_surface(c.P, c.F);  // orients the faces where it can
  c.surface_problem = surface.problem();
  c.load_report.faces_flipped = surface.flipped_faces;
  c.seam_vertices = count_seam_vertices(c.P, c.F);
  const int nv = static_cast<int>(c.P.rows());
  if (!sel.empty()) {
    c.region = file_extension(sel) == ".dmat" ? read_dmat_groups(sel, nv) : read_sel(sel, nv);
    try {  // a gap in the handle codes, before the handles are counted against the .def
      c.region.validate(nv);
    } catch (const InvalidInput& e) {
      throw InvalidInput(sel + ": " + e.what());
    }
  }
  if (!def.empty()) {
    if (!sel.empty() && c.region.num_handles() == 0)
      throw InvalidInput(sel + " defines no handle (every vertex fixed or free): there is nothing for " +
                         def + " to move");
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

EditCase weld_case(EditCase c, double eps) {
  auto weld = std::make_shared<Weld>(weld_vertices(c.P, c.F, eps));
  if (c.region.num_vertices() > 0) {
    std::vector<int> codes(static_cast<size_t>(weld->P.rows()), -1), first(codes.size(), -1);
    for (int v = 0; v < c.region.num_vertices(); ++v) {
      const int w = weld->welded_of[v];
      if (codes[w] < 0) {
        codes[w] = c.region.code(v);
        first[w] = v;
      } else if (codes[w] != c.region.code(v)) {
        throw InvalidInput("weld: vertices " + std::to_string(first[w]) + " and " + std::to_string(v) +
                           " are welded (a chain of vertices each within " + format_number(eps) +
                           " of the next joins them) but have region labels " +
                           std::to_string(codes[w]) + " and " + std::to_string(c.region.code(v)));
      }
    }
    c.region = Region::from_codes(std::move(codes));
  }
  c.file_F = std::move(c.F);
  c.P = weld->P;
  c.F = weld->F;
  c.surface_problem = check_surface(c.P, c.F).problem();
  if (!c.surface_problem.empty() && weld->merged > 0)  // the weld's doing, not the file's
    c.surface_problem = "welding within " + format_number(eps) + " merged " + std::to_string(weld->welded_of.size()) +
                        " vertices into " + std::to_string(weld->P.rows()) + ", which left " + c.surface_problem +
                        " (use a smaller --weld)";
  c.seam_vertices = count_seam_vertices(c.P, c.F);
  c.weld = std::move(weld);
  return c;
}

void require_surface(const EditCase& edit, const std::string& method, bool is_method) {
  if (edit.surface_problem.empty()) return;
  throw InvalidInput(method + (is_method ? " is a surface method and " : " needs a surface, and ") +
                     (edit.path.empty() ? edit.name : edit.path) + " is not a manifold triangle mesh: " +
                     edit.surface_problem +
                     (is_method ? ". Space methods deform any input: --method lattice, cage-mvc, cage-harmonic or rbf"
                                : ""));
}

}  // namespace msd
