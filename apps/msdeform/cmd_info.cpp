#include <cstdio>
#include <memory>

#include "apps/msdeform/commands.h"
#include "msdeform/core/mesh_info.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/scenes.h"

namespace msd::cli {

namespace {
void print_info(const std::string& what, const MeshInfo& i, const LoadReport* report) {
  std::printf("%s\n", what.c_str());
  std::printf("  vertices              %d\n", i.vertices);
  std::printf("  faces                 %d%s\n", i.faces, i.faces == 0 ? " (a point cloud)" : "");
  std::printf("  edges                 %d\n", i.edges);
  std::printf("  components            %d\n", i.components);
  std::printf("  boundary edges        %d in %d loop(s)\n", i.boundary_edges, i.boundary_loops);
  std::printf("  euler characteristic  %d\n", i.euler_characteristic);
  std::printf("  unreferenced vertices %d\n", i.unreferenced_vertices);
  std::printf("  seam vertices         %d%s\n", i.seam_vertices,
              i.seam_vertices > 0 ? " (boundary vertices at another's coordinates: deform --weld 0 joins them)" : "");
  if (i.near_seam_vertices > 0)
    std::printf("  near-seam vertices    %d (boundary vertices within %.3g of another, 1e-3 of the mean edge: a seam "
                "written with rounding? deform --weld %.3g joins them)\n",
                i.near_seam_vertices, i.near_seam_distance, i.near_seam_distance);
  std::printf("  degenerate faces      %d (zero area)\n", i.degenerate_faces);
  std::printf("  non-manifold edges    %d\n", i.nonmanifold_edges);
  std::printf("  non-manifold vertices %d\n", i.nonmanifold_vertices);
  std::printf("  non-orientable parts  %d\n", i.nonorientable_components);
  std::printf("  flipped faces         %d (wound against their neighbours; turned over when loaded)\n",
              i.flipped_faces);
  if (report) {
    std::printf("  polygons triangulated %d", report->polygons_triangulated);
    if (report->polygons_split_otherwise > 0)
      std::printf(
          " (%d not into their first corner's fan, which had a sliver or a turned-over triangle: "
          "into the best-shaped triangles)",
          report->polygons_split_otherwise);
    std::printf("\n");
    std::printf("  repeated-index faces  %d (dropped)\n", report->degenerate_faces_skipped);
    if (report->repeated_corners_merged > 0)
      std::printf(
          "  repeated corners      %d (faces listing a corner twice in a row: read without the repetition)\n",
          report->repeated_corners_merged);
    std::printf("  duplicate faces       %d (dropped)\n", report->duplicate_faces_dropped);
    if (report->first_attribute_line > 0)
      std::printf(
          "  ignored attributes    from line %d (colours, normals, texture coordinates, materials or other "
          "data: read past, not kept)\n",
          report->first_attribute_line);
    if (report->first_ignored_line > 0)
      std::printf("  ignored data          from line %d (more than the header's counts)\n", report->first_ignored_line);
  }
  std::printf("  bounding box          [%.6g %.6g %.6g] .. [%.6g %.6g %.6g]\n", i.bbox_min.x(), i.bbox_min.y(),
              i.bbox_min.z(), i.bbox_max.x(), i.bbox_max.y(), i.bbox_max.z());
  std::printf("  mean edge length      %.6g\n", i.mean_edge_length);
  if (!i.size_problem.empty()) {  // "sizes: coordinates too large: ..."
    std::printf("  sizes                %s\n", i.size_problem.substr(i.size_problem.find(':') + 1).c_str());
    std::printf("  surface               not for any method at these sizes (above)\n");
  } else if (i.surface_problem.empty())
    std::printf("  surface               manifold and oriented: for surface and space methods\n");
  else
    std::printf("  surface               %s: for space methods only (lattice, cage-mvc, cage-harmonic, rbf)\n",
                i.surface_problem.c_str());
}
}  // namespace

void add_info_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "info", "Print statistics of a mesh file (or soup, or point cloud) or a built-in scene");
  auto mesh_path = std::make_shared<std::string>();
  auto scene = std::make_shared<std::string>();
  auto resolution = std::make_shared<std::string>("10k");
  auto* mesh_opt =
      cmd->add_option("mesh", *mesh_path, "Mesh, soup or point cloud file (.off .obj .ply .stl)");
  cmd->add_option("--scene", *scene, "Built-in scene instead of a file (lift, bend120, twist135, bar-...)")
      ->excludes(mesh_opt);
  cmd->add_option("--resolution", *resolution, "Approximate vertex count of the scene (e.g. 10k, 1M)")->capture_default_str();
  cmd->callback([=] {
    if (!scene->empty()) {
      SceneOptions options;
      options.resolution = parse_resolution(*resolution);
      const Scene s = make_scene(*scene, options);
      print_info("scene " + s.name, mesh_info(s.P, s.F), nullptr);
      std::printf("  fixed / free / handle %zu / %zu / %zu vertices\n", s.region.fixed_vertices().size(),
                  s.region.free_vertices().size(), s.region.handle_vertices(0).size());
      std::printf("  subdivision levels    %d (coarse mesh %ld vertices)\n", s.refinement.levels, long(s.coarse_P.rows()));
      return;
    }
    if (mesh_path->empty()) throw CLI::RequiredError("mesh or --scene");
    LoadReport report;
    const TriangleSoup soup = load_soup(*mesh_path, &report);
    print_info(*mesh_path, mesh_info(soup.P, soup.F), &report);
  });
}

}  // namespace msd::cli
