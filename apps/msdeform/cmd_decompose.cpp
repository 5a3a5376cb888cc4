#include <chrono>
#include <cstdio>
#include <memory>

#include "apps/msdeform/commands.h"
#include "apps/msdeform/deformers.h"
#include "apps/msdeform/edit_case.h"
#include "core/errors.h"
#include "core/mesh_io.h"
#include "decomposition/fairing.h"
#include "decomposition/low_pass.h"
#include "detail/normal_displacements.h"
#include "reconstruction/multiscale.h"

namespace msd::cli {

namespace {
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
  auto base = std::make_shared<BaseKind>(BaseKind::LowPass);
  auto low_pass = std::make_shared<LowPassOptions>();
  auto order = std::make_shared<int>(2);
  auto output = std::make_shared<std::string>();
  edit->add_to(*cmd);
  add_decomposition_options(*cmd, *base, low_pass->detail_scale, *order);
  cmd->add_option("-o,--output", *output,
                  "Base mesh to write, .ply: a per-vertex property 'detail' holds the signed normal-displacement "
                  "height of the detailed vertex (written atomically)")
      ->required();
  cmd->callback([=] {
    if (file_extension(*output) != ".ply")
      throw InvalidInput("decompose: " + *output + ": the output carries per-vertex detail heights and must be .ply");
    const bool fairing = *base == BaseKind::Fairing;
    const EditCase c = edit->load(/*need_transforms=*/false, /*need_region=*/fairing);
    const Positions& S = c.P;
    const Faces& F = c.F;
    const auto t0 = std::chrono::steady_clock::now();
    Positions B;
    LowPassReport report;
    if (fairing) {
      FairingOptions options;
      options.order = static_cast<FairingOrder>(*order);
      B = fair_region(S, F, c.region, options);
    } else {
      B = low_pass_base(S, F, *low_pass, &report);
    }
    const DetailCheck check = fairing ? check_details(S, B, F) : report.check;
    NormalDisplacements details;
    details.encode(S, F, B, F);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const Eigen::VectorXd h = details.heights();
    SaveOptions save;
    save.vertex_scalar = &h;
    save.scalar_name = "detail";
    save_mesh(B, F, *output, save);
    std::printf("decomposed %s: %ld vertices, %.1f ms\n", c.name.c_str(), long(S.rows()), ms);
    if (fairing) {
      std::printf("  base: fairing of order %d of the free region\n", *order);
    } else {
      if (report.detail_scale > 0)
        std::printf("  base: low-pass at detail scale %.10g (%s; mean edge length %.4g)\n", report.detail_scale,
                    report.automatic ? "chosen automatically" : "given", report.mean_edge_length);
      else
        std::printf("  base: the mesh itself: the detail heights grow with every scale tried, so there is no separate "
                    "detail layer (--detail-scale sets one)\n");
      for (const auto& k : report.candidates) {
        std::printf("    tried %-10.4g", k.detail_scale);
        print_check("", k.check);
      }
    }
    print_check("  ", check);
    std::printf("  normal-displacement heights in [%.4g, %.4g], mean |h| %.4g, %d vertices without a base point\n",
                h.minCoeff(), h.maxCoeff(), h.cwiseAbs().mean(), details.report().fallback);
    if (check.max_fold_ratio >= 1)
      std::fprintf(stderr, "warning: %d vertices have details taller than the base's curvature radius (they fold)\n",
                   check.folding_vertices);
    std::printf("  wrote %s\n", output->c_str());
  });
}

}  // namespace msd::cli
