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
                  "arap, primo: iterations per drawn frame (they go on while the mouse rests until converged)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", *quiet, "No line per script command");
  cmd->callback([=] {
#ifdef MSD_HAVE_VIEWER
    if (!screenshot->empty()) check_picture_output(*screenshot, "--screenshot");
    view::ViewerOptions o;
    o.edit = edit->load(/*need_transforms=*/false, /*need_region=*/false);
    o.method = method->method_name();
    o.settings = method->method_settings(o.edit);
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
    if (const int status = view::run_viewer(o); status != 0) std::exit(status);
#else
    throw UsageError("this msdeform was built without the viewer: install libglfw3-dev and libimgui-dev "
                     "(scripts/setup.sh does) and build again");
#endif
  });
}

}  // namespace msd::cli
