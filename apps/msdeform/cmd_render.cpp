#include <cmath>
#include <cstdio>
#include <memory>

#include "apps/msdeform/camera_options.h"
#include "apps/msdeform/commands.h"
#include "apps/msdeform/deformers.h"
#include "apps/msdeform/edit_case.h"
#include "msdeform/analysis/metrics.h"
#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/decomposition/low_pass.h"
#include "msdeform/detail/normal_displacements.h"

namespace msd::cli {

void add_render_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("render", "Draw a mesh (with its region, details or self-intersections) to a PNG, "
                                           "e.g. to check a selection before deforming");
  auto edit = std::make_shared<EditCaseOptions>();
  auto camera = std::make_shared<CameraOptions>();
  auto output = std::make_shared<std::string>();
  auto color = std::make_shared<std::string>("auto");
  auto size = std::make_shared<std::vector<int>>(std::vector<int>{800, 600});
  auto detail_scale = std::make_shared<double>(0);
  edit->add_to(*cmd, /*with_transforms=*/false);
  camera->add_to(*cmd);
  auto rest = std::make_shared<std::string>();
  cmd->add_option("--color", *color,
                  "auto (region when one is given), region (fixed blue, free clay, handles red, green, ...), detail "
                  "(signed height over a low-pass base), selfint (self-intersecting triangles in red), rigidity (the "
                  "one-ring rotation residual against --rest), none, or a PLY vertex property: its name, or property:NAME "
                  "for one named like the above (e.g. property:detail from decompose, detail_change from compare's "
                  "meshes)")
      ->capture_default_str();
  cmd->add_option("--rest", *rest, "--color rigidity: the rest shape (same vertices and faces, e.g. the input of deform)");
  cmd->add_option("--detail-scale", *detail_scale, "--color detail: the low-pass detail scale (0: automatic)")
      ->check(nonnegative_length());
  cmd->add_option("--size", *size, "Width and height in pixels")->expected(2)->check(CLI::Range(16, 8192));
  cmd->add_option("-o,--output", *output, "PNG to write (atomically)")->required();
  cmd->callback([=] {
    check_picture_output(*output, "-o");
    const EditCase c = edit->load(/*need_transforms=*/false, /*need_region=*/false);
    // A mesh at one point frames nothing: a blank picture.
    check_extent(c.P, "render: " + (c.path.empty() ? c.name : c.path));
    RenderOptions o;
    o.width = (*size)[0];
    o.height = (*size)[1];
    camera->apply(c.P, c.region, o);
    const bool has_region = c.region.num_vertices() > 0;
    const std::string mode = *color == "auto" ? (has_region ? "region" : "none") : *color;
    Positions colors;
    Eigen::VectorXd heights;
    if (mode == "region") {
      if (!has_region) throw InvalidInput("--color region needs a region: --sel, or --fixed / --handle");
      colors = region_colors(c.region);
      o.vertex_colors = &colors;
      std::printf("region: %zu fixed, %zu free, %d handle(s)\n", c.region.fixed_vertices().size(),
                  c.region.free_vertices().size(), c.region.num_handles());
    } else if (mode == "detail") {
      require_surface(c, "render --color detail", /*is_method=*/false);
      LowPassOptions lp;
      lp.detail_scale = *detail_scale;
      LowPassReport report;
      const Positions B = low_pass_base(c.P, c.F, lp, &report);
      heights = normal_displacement_heights(c.P, B, c.F);
      o.vertex_scalar = &heights;
      o.scalar_label = "detail height";
      if (report.has_detail_layer())
        std::printf("details over a low-pass base at scale %.4g: heights in [%.4g, %.4g]\n", report.detail_scale,
                    heights.minCoeff() + 0.0, heights.maxCoeff() + 0.0);  // + 0.0: no "-0"
      else
        std::printf("no detail layer (%s), so the base is the mesh itself and every height is 0\n",
                    report.no_layer_explanation().c_str());
    } else if (mode == "rigidity") {
      if (rest->empty()) throw InvalidInput("--color rigidity measures against a rest shape: give --rest REST");
      const TriangleSoup r = load_soup(*rest);
      if (r.P.rows() != c.P.rows())
        throw InvalidInput("--rest " + *rest + " has " + std::to_string(r.P.rows()) + " vertices, " + c.name +
                           " has " + std::to_string(c.P.rows()));
      heights = rigidity_error(r.P, c.P, c.F).per_vertex;
      o.vertex_scalar = &heights;
      o.scalar_label = "rigidity";
      std::printf("rigidity against %s: mean %.4g, max %.4g\n", rest->c_str(), heights.mean(), heights.maxCoeff());
    } else if (mode == "selfint") {
      require_surface(c, "render --color selfint", /*is_method=*/false);
      std::vector<std::pair<int, int>> pairs;
      const int n = count_self_intersections(c.P, c.F, &pairs);
      colors = Positions::Constant(c.P.rows(), 3, 0.85).rowwise() - Eigen::RowVector3d(0, 0.1, 0.2);
      for (const auto& [f, g] : pairs)
        for (int face : {f, g})
          for (int k = 0; k < 3; ++k) colors.row(c.F(face, k)) << 0.9, 0.05, 0.05;
      o.vertex_colors = &colors;
      std::printf("self-intersecting triangle pairs: %d (drawn in red)\n", n);
    } else if (mode != "none") {  // a PLY vertex property: NAME, or property:NAME for one named like a mode
      const std::string name = mode.rfind("property:", 0) == 0 ? mode.substr(9) : mode;
      if (c.path.empty()) throw InvalidInput("--color " + mode + ": a built-in scene has no vertex properties");
      if (file_extension(c.path) != ".ply")
        throw InvalidInput("--color " + mode + ": not a colour mode (auto, region, detail, selfint, rigidity, none), "
                           "and " + c.path + " is not a PLY file, the only kind with named vertex properties");
      heights = load_vertex_property(c.path, name);
      for (Eigen::Index v = 0; v < heights.size(); ++v)
        if (!std::isfinite(heights[v]))
          throw InvalidInput("--color " + mode + ": " + c.path + ": property '" + name + "' of vertex " +
                             std::to_string(v) + " is " + format_number(heights[v]) +
                             "; colours need finite values");
      o.vertex_scalar = &heights;
      o.scalar_label = name;
      std::printf("%s: values in [%.4g, %.4g]\n", name.c_str(), heights.minCoeff(), heights.maxCoeff());
    }
    // A stray vertex far away frames the picture, and the rest of the shape is a dot in it.
    if (const std::string w = extent_outlier_warning(c.P, c.F, "render"); !w.empty())
      std::fprintf(stderr,
                   "warning: %s; the picture frames every vertex, so the shape may be too small to see\n",
                   w.c_str());
    render_png(c.P, c.F, *output, o);
    edit->write_built(c.region, c.transforms);
    std::printf("wrote %s (%dx%d, up %+.0f %+.0f %+.0f)\n", output->c_str(), o.width, o.height,
                o.up.x() + 0.0, o.up.y() + 0.0,
                o.up.z() + 0.0);  // + 0.0: no "-0"
  });
}

}  // namespace msd::cli
