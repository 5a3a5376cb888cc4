#include <cstdio>
#include <filesystem>
#include <memory>

#include "apps/msdeform/commands.h"
#include "msdeform/core/scenes.h"

namespace msd::cli {

void add_scene_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "scene", "Write a built-in benchmark scene as NAME.off + NAME.sel + NAME.def, so other tools run the same case");
  auto name = std::make_shared<std::string>();
  auto resolution = std::make_shared<std::string>("10k");
  auto dir = std::make_shared<std::string>();
  cmd->add_option("name", *name, "lift, bend120, twist135, crease120 (bumpy plane; crease120: Fig. 9.10, a bend tighter than the bumps) or bar-lift, bar-bend120, bar-twist135")
      ->required();
  cmd->add_option("--resolution", *resolution, "Approximate vertex count (e.g. 10k, 100k, 1M)")->capture_default_str();
  cmd->add_option("-o,--output", *dir, "Folder to write into (created if missing)")->required();
  cmd->callback([=] {
    SceneOptions options;
    options.resolution = parse_resolution(*resolution);
    const Scene s = make_scene(*name, options);
    write_scene(s, *dir);
    std::printf("wrote %s.{off,sel,def}: %ld vertices, %ld faces, %zu fixed, %zu free, %zu handle\n",
                (std::filesystem::path(*dir) / s.name).string().c_str(), long(s.P.rows()), long(s.F.rows()),
                s.region.fixed_vertices().size(), s.region.free_vertices().size(),
                s.region.handle_vertices(0).size());
  });
}

}  // namespace msd::cli
