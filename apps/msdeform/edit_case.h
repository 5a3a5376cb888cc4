#pragma once
// Command-line options that choose an edit: mesh files or a built-in scene (loaded by core/edit_case.h).

#include <string>

#include <CLI/CLI.hpp>

#include "msdeform/core/edit_case.h"

namespace msd::cli {

struct EditCaseOptions {
  std::string mesh, sel, def, scene, resolution = "10k";
  void add_to(CLI::App& cmd);
  // Loads the files or builds the scene. Throws InvalidInput naming the file or the mismatch. Without
  // need_transforms, --def may be omitted (transforms stay empty); without need_region, --sel too (the
  // region stays empty).
  EditCase load(bool need_transforms = true, bool need_region = true) const;
};

}  // namespace msd::cli
