#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "apps/msdeform/commands.h"
#include "apps/msdeform/deformers.h"
#include "apps/msdeform/edit_case.h"
#include "apps/msdeform/progress.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/detail/normal_displacements.h"
#include "msdeform/reconstruction/decompose.h"

namespace msd::cli {

namespace {
// Which solver gave the low-pass base, and why conjugate gradients gave way where they did.
std::string solver_line(const LowPassReport& r) {
  if (r.iterations > 0)
    return "solved by conjugate gradients, " + std::to_string(r.iterations) + " iterations";
  if (r.solver_fallback.empty()) return "solved by factorisation";
  return "solved by factorisation: conjugate gradients gave way, " + r.solver_fallback;
}

void print_check(const char* indent, const DetailCheck& c) {
  std::printf("%sdetail heights |S - B|: max %.4g, rms %.4g; base's smallest curvature radius %.4g; fold ratio "
              "p99.9 %.3g, max %.3g",
              indent, c.max_height, c.rms_height, c.min_curvature_radius, c.fold_ratio_p999, c.max_fold_ratio);
  if (c.worst_vertex >= 0) std::printf(" (vertex %d)", c.worst_vertex);
  std::printf("\n");
}
}  // namespace

void add_decompose_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "decompose", "Split a mesh into a smooth base B and details D = S - B (the multi-scale decomposition, seed 9.3)");
  auto edit = std::make_shared<EditCaseOptions>();
  auto decomposition = std::make_shared<DecompositionArgs>();
  auto output = std::make_shared<std::string>();
  edit->add_to(*cmd, /*with_transforms=*/false);
  decomposition->add_to(*cmd);
  cmd->add_option("-o,--output", *output,
                  "Base mesh to write, .ply: a per-vertex property 'detail' holds the signed normal-displacement "
                  "height of the detailed vertex (written atomically); a remeshed base has its own triangles and no "
                  "'detail' property")
      ->required();
  auto quiet = std::make_shared<bool>(false);
  cmd->add_flag("-q,--quiet", *quiet, "No progress lines on stderr (the automatic detail scale's candidates)");
  cmd->callback([=] {
    if (file_extension(*output) != ".ply")
      throw InvalidInput("decompose: " + *output + ": the output carries per-vertex detail heights and must be .ply");
    edit->check_output(*output, "-o");
    const bool fairing = decomposition->options.kind == DecompositionKind::Fairing;
    EditCase c = edit->load(/*need_transforms=*/false, /*need_region=*/fairing);
    require_surface(c, "decompose", /*is_method=*/false);
    if (c.region.num_vertices() == 0) c.region = Region(static_cast<int>(c.P.rows()));  // all free
    const Positions& S = c.P;
    const Faces& F = c.F;
    const auto t0 = std::chrono::steady_clock::now();
    const DecompositionOptions options = decomposition->resolve(c);
    ProgressPrinter printer(*quiet);
    const Decomposition d = decompose(S, F, c.region, options, [&](const std::string& line) { printer(line); });
    printer.flush();
    const DecompositionReport& report = d.report;
    const bool same_connectivity = d.base_faces.rows() == F.rows() && d.base_faces == F;
    NormalDisplacements details;
    details.encode(S, F, d.base, d.base_faces);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    // A vertex no face uses has no detail (the base keeps it): its closest point on B lies on some other part.
    Eigen::VectorXd h = details.heights();
    std::vector<char> used(static_cast<size_t>(S.rows()), 0);
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int k = 0; k < 3; ++k) used[F(f, k)] = 1;
    const long unused = std::count(used.begin(), used.end(), 0);
    for (Eigen::Index v = 0; v < h.size(); ++v) h[v] = used[v] ? h[v] + 0.0 : 0.0;  // + 0.0: no "-0" in the file
    SaveOptions save;
    if (same_connectivity) {
      save.vertex_scalar = &h;
      save.scalar_name = "detail";
    }
    save_mesh(d.base, d.base_faces, *output, save);
    edit->write_built(c.region, c.transforms);
    std::printf("decomposed %s: %ld vertices, %.1f ms\n", c.name.c_str(), long(S.rows()), ms);
    switch (report.kind) {
      case DecompositionKind::Fairing:
        std::printf("  base: fairing of order %d of the free region\n", decomposition->fairing_order);
        break;
      case DecompositionKind::Subdivision:
        std::printf("  base: Loop subdivision of the control mesh (%d vertices)\n", report.control_vertices);
        break;
      default:
        if (report.low_pass.has_detail_layer())
          std::printf("  base: low-pass at detail scale %.10g (%s; mean edge length %.4g; %s)\n",
                      report.low_pass.detail_scale,
                      report.low_pass.automatic ? "chosen automatically" : "given",
                      report.low_pass.mean_edge_length, solver_line(report.low_pass).c_str());
        else
          std::printf("  base: the mesh itself, no separate detail layer: %s%s%s%s\n",
                      report.low_pass.no_layer_reason.c_str(), report.low_pass.all_boundary ? "" : " (",
                      report.low_pass.no_layer_remedy(), report.low_pass.all_boundary ? "" : ")");
        for (const auto& k : report.low_pass.candidates) {
          std::printf("    tried %-10.4g", k.detail_scale);
          print_check("", k.check);
        }
        if (report.kind == DecompositionKind::Remeshed)
          std::printf("  remeshed to edge length %.4g: %d vertices (the output has the base's triangles, without "
                      "per-vertex heights)\n", report.remesh_edge_length, report.remeshed_vertices);
    }
    if (report.kind != DecompositionKind::Remeshed)  // |S − B| per vertex needs B to have S's vertices
      print_check("  ", report.check);
    std::printf("  normal-displacement heights in [%.4g, %.4g], mean |h| %.4g, %d vertices without a base point",
                h.minCoeff(), h.maxCoeff(), h.cwiseAbs().mean(), details.report().fallback);
    if (unused > 0) std::printf(" (%ld vertices no face uses: height 0)", unused);
    std::printf("\n");
    if (!report.warning.empty()) std::fprintf(stderr, "warning: %s\n", report.warning.c_str());
    if (details.report().fallback > 0)
      std::fprintf(
          stderr,
          "warning: %d vertices found no base point along the base's normals (Newton did not converge): "
          "their heights%s are those of their closest points on B; a smoother base%s usually removes "
          "them\n",
          details.report().fallback, same_connectivity ? " (the 'detail' property)" : "",
          report.kind == DecompositionKind::LowPass ? " (a larger --detail-scale)" : "");
    std::printf("  wrote %s\n", output->c_str());
  });
}

}  // namespace msd::cli
