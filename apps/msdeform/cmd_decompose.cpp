#include <chrono>
#include <cstdio>
#include <memory>

#include "apps/msdeform/commands.h"
#include "apps/msdeform/edit_case.h"
#include "core/errors.h"
#include "core/mesh_io.h"
#include "decomposition/fairing.h"
#include "detail/normal_displacements.h"

namespace msd::cli {

void add_decompose_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "decompose", "Split a mesh into a faired base B and details D = S - B (the multi-scale decomposition, seed 9.3)");
  auto edit = std::make_shared<EditCaseOptions>();
  auto order = std::make_shared<int>(2);
  auto output = std::make_shared<std::string>();
  edit->add_to(*cmd);
  cmd->add_option("--fairing", *order, "Fairing order k of the free region: 1 membrane, 2 thin plate, 3 minimum variation")
      ->check(CLI::Range(1, 3))
      ->capture_default_str();
  cmd->add_option("-o,--output", *output,
                  "Base mesh to write, .ply: a per-vertex property 'detail' holds the signed normal-displacement "
                  "height of the detailed vertex (written atomically)")
      ->required();
  cmd->callback([=] {
    if (file_extension(*output) != ".ply")
      throw InvalidInput("decompose: " + *output + ": the output carries per-vertex detail heights and must be .ply");
    const EditCase c = edit->load(/*need_transforms=*/false);
    const Positions S = positions(c.mesh);
    const Faces F = faces(c.mesh);
    FairingOptions options;
    options.order = static_cast<FairingOrder>(*order);
    const auto t0 = std::chrono::steady_clock::now();
    const Positions B = fair_region(c.mesh, c.region, options);
    NormalDisplacements details;
    details.encode(S, F, B, F);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const Eigen::VectorXd h = details.heights();
    SaveOptions save;
    save.vertex_scalar = &h;
    save.scalar_name = "detail";
    save_mesh(B, F, *output, save);
    std::printf("decomposed %s: %ld vertices, fairing order %d, %.1f ms\n", c.name.c_str(), long(S.rows()), *order, ms);
    std::printf("  detail heights in [%.4g, %.4g], mean |h| %.4g\n", h.minCoeff(), h.maxCoeff(), h.cwiseAbs().mean());
    std::printf("  wrote %s\n", output->c_str());
  });
}

}  // namespace msd::cli
