#pragma once
// Each subcommand of the msdeform tool registers itself on the application here.

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace msd::cli {

//! The value of `text` when all of it is one finite decimal number, else nullopt. std::strtod alone also
//! reads infinities, NaN and C's hexadecimal numbers ("0x10" is not the 0 or 10 a user meant).
std::optional<double> decimal_number(const std::string& text);

void add_info_command(CLI::App& app);
void add_scene_command(CLI::App& app);
void add_deform_command(CLI::App& app);
void add_decompose_command(CLI::App& app);
void add_compare_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_view_command(CLI::App& app);  // needs MSD_HAVE_VIEWER to open a window

}  // namespace msd::cli
