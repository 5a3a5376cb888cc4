#include <cstdlib>
#include <memory>

#include "apps/msdeform/camera_options.h"
#include "apps/msdeform/commands.h"
#include "apps/msdeform/deformers.h"
#include "apps/msdeform/edit_case.h"
#include "msdeform/analysis/render.h"
#include "msdeform/core/errors.h"
#ifdef MSD_HAVE_VIEWER
#include "apps/view/viewer.h"
#endif

namespace msd::cli {

void add_view_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "view", "Edit interactively: paint the fixed part and handles, drag a handle with the gizmo and watch the method "
              "follow (a GLFW + OpenGL 3.3 window; --script and --screenshot run it without a person)");
  auto edit = std::make_shared<EditCaseOptions>();
  auto method = std::make_shared<DeformerOptions>();
  method->method = "arap";
  auto camera = std::make_shared<CameraOptions>();
  edit->add_to(*cmd);
  method->add_to(*cmd);
  camera->add_to(*cmd);
  auto script = std::make_shared<std::string>();
  auto screenshot = std::make_shared<std::string>();
  auto size = std::make_shared<std::vector<int>>(std::vector<int>{1280, 800});
  auto per_frame = std::make_shared<int>(5);
  auto quiet = std::make_shared<bool>(false);
  cmd->add_option("--script", *script,
                  "Commands to run, one per drawn frame (method, handle, translate, rotate, gizmo, paint, lasso, orbit, "
                  "zoom, color, shading, converge, screenshot, save-mesh, save-sel, save-def, reset; see the README)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--screenshot", *screenshot, "After the script: write the 3D view to this PNG and exit");
  cmd->add_option("--size", *size, "Window width and height in pixels")->expected(2)->check(CLI::Range(400, 8192));
  cmd->add_option("--iterations-per-frame", *per_frame,
                  "arap, primo: iterations per drawn frame while a handle is dragged; while the mouse rests they go "
                  "on in longer runs (up to --iterations) until they converge")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", *quiet, "No line per script command");
  cmd->callback([=] {
#ifdef MSD_HAVE_VIEWER
    if (!screenshot->empty()) check_picture_output(*screenshot, "--screenshot");
    if ((*size)[0] < 700) throw InvalidInput("--size: the window needs a width of 700 pixels or more (the panel takes 380)");
    for (const auto& [path, option] : {std::pair{edit->region.write_sel, "--write-sel"}, {edit->region.write_def, "--write-def"}})
      if (!path.empty() && !script->empty() && same_file(path, *script))
        throw InvalidInput(std::string(option) + " " + path + " is the --script; it would be replaced");
    view::ViewerOptions o;
    // A --def is read (with its --sel) when given; without one the handles start at rest.
    const bool def_given = !edit->def.empty();
    o.edit = edit->load(/*need_transforms=*/def_given, /*need_region=*/def_given);
    o.method = method->method_name();
    o.settings = method->method_settings(o.edit);
    // Painting a region prepares the method again on the same mesh: the multi-scale base is computed once.
    o.settings.decomposition.low_pass_cache = std::make_shared<LowPassCache>();
    method->make(o.edit);  // an unknown method or invalid settings are refused before the window opens
    if (o.method == "arap" || o.method == "primo") {
      const double tolerance = o.method == "arap" ? o.settings.arap.tolerance : o.settings.primo.tolerance;
      if (tolerance == 0)
        throw InvalidInput("--tolerance 0 asks for a fixed number of iterations, but the viewer iterates until the "
                           "method converges: give a positive tolerance");
    }
    o.iterations_per_frame = *per_frame;
    RenderOptions r;
    camera->apply(o.edit.P, o.edit.region, r);
    o.up = r.up;
    o.view_direction = r.view_direction;
    o.width = (*size)[0];
    o.height = (*size)[1];
    o.script = *script;
    o.screenshot = *screenshot;
    o.quiet = *quiet;
    o.inputs = {edit->mesh, edit->sel, edit->def, *script};
    for (const std::string& f : edit->region.input_files()) o.inputs.push_back(f);
    if (const int status = view::run_viewer(o); status != 0) std::exit(status);
    edit->write_built(o.edit.region, o.edit.transforms);  // the region and transforms given, not those painted
#else
    throw UsageError("this msdeform was built without the viewer: install libglfw3-dev and libimgui-dev "
                     "(scripts/setup.sh does) and build again");
#endif
  });
}

}  // namespace msd::cli
