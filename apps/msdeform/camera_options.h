#pragma once
// Camera and colour options shared by `render`, `deform --render` and `compare`: --up, --view, --focus,
// and the colours of a region's roles.

#include <string>

#include <CLI/CLI.hpp>

#include "msdeform/analysis/render.h"
#include "msdeform/core/region.h"

namespace msd::cli {

struct CameraOptions {
  std::string up = "auto";     // auto | x | y | z | -x | -y | -z
  std::string view = "auto";   // auto | AZ,EL (degrees about up from the front, above the horizon)
  std::string focus = "all";   // all | handle

  void add_to(CLI::App& cmd);
  // Sets o.up and o.view_direction for the shape P (--up auto: edit_view_axes() with the region's fixed
  // vertices, e.g. feet or a base, else the principal axes), and the framing: the whole shape, or the
  // handles of `region` (--focus handle). \throw InvalidInput naming the option.
  void apply(const Positions& P, const Region& region, RenderOptions& o) const;
};

// Before any work: an output picture path (option, e.g. "-o") is a .png that can be written.
// \throw InvalidInput naming the option and the path.
void check_picture_output(const std::string& path, const char* option);

}  // namespace msd::cli
