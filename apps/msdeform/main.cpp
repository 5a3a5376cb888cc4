// msdeform: command-line front end of the msdeform library.
#include <iostream>

#include "apps/msdeform/commands.h"
#include "core/memory.h"
#include "core/errors.h"

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  CLI::App app{"msdeform: multi-scale, detail-preserving deformation of triangle meshes"};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Print help for all subcommands");
  msd::cli::add_info_command(app);
  msd::cli::add_scene_command(app);
  msd::cli::add_deform_command(app);
  msd::cli::add_decompose_command(app);
  msd::cli::add_compare_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const msd::Error& e) {
    std::cerr << "msdeform: error: " << e.what() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "msdeform: error: out of memory\n";
    return 1;
  }
  return 0;
}
