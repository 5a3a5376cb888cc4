#pragma once
// Each subcommand of the msdeform tool registers itself on the application here.

#include <CLI/CLI.hpp>

namespace msd::cli {

void add_info_command(CLI::App& app);
void add_scene_command(CLI::App& app);
void add_deform_command(CLI::App& app);
void add_decompose_command(CLI::App& app);
void add_compare_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_view_command(CLI::App& app);  // needs MSD_HAVE_VIEWER to open a window

}  // namespace msd::cli
