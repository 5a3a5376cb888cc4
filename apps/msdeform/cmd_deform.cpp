#include <chrono>
#include <cstdio>
#include <memory>

#include "apps/msdeform/commands.h"
#include "apps/msdeform/deformers.h"
#include "apps/msdeform/edit_case.h"
#include "core/errors.h"
#include "analysis/metrics.h"
#include "core/mesh_io.h"

namespace msd::cli {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
}  // namespace

void add_deform_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("deform", "Deform a mesh: prepare a method for a region, apply the handle transforms");
  auto edit = std::make_shared<EditCaseOptions>();
  auto method = std::make_shared<DeformerOptions>();
  auto output = std::make_shared<std::string>();
  edit->add_to(*cmd);
  method->add_to(*cmd);
  cmd->add_option("-o,--output", *output, "Deformed mesh to write (.off .obj .ply .stl); written atomically")->required();
  cmd->callback([=] {
    const EditCase c = edit->load();
    std::unique_ptr<Deformer> deformer = method->make();
    const Positions rest = positions(c.mesh);
    auto t0 = Clock::now();
    deformer->prepare(c.mesh, c.region);
    const double prepare_ms = ms_since(t0);
    Positions out(rest.rows(), 3);
    deformer->deform(c.transforms, out);  // first frame warms caches and buffers
    t0 = Clock::now();
    deformer->deform(c.transforms, out);
    const double frame_ms = ms_since(t0);
    if (!out.allFinite()) throw SolverError(deformer->name() + ": the result is not finite; nothing written");
    save_mesh(out, faces(c.mesh), *output);
    std::printf("%s on %s: %ld vertices (%zu free, %d handle(s))\n", deformer->name().c_str(), c.name.c_str(),
                long(rest.rows()), c.region.free_vertices().size(), c.region.num_handles());
    std::printf("  prepare %.1f ms, frame %.2f ms, handle error %.3g\n", prepare_ms, frame_ms, handle_error(rest, out, c.region, c.transforms));
    std::printf("  wrote %s\n", output->c_str());
  });
}

}  // namespace msd::cli
