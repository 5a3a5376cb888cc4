#pragma once
// An edit to run: a mesh, its region and one transform per handle, from files or a built-in scene.

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/mesh.h"
#include "core/region.h"

namespace msd::cli {

struct EditCase {
  std::string name;
  Mesh mesh;
  Region region;
  std::vector<Mat4> transforms;
};

// The options that choose an edit case, shared by the subcommands that run edits.
struct EditCaseOptions {
  std::string mesh, sel, def, scene, resolution = "10k";
  void add_to(CLI::App& cmd);
  // Loads the files or builds the scene. Throws InvalidInput naming the file or the mismatch.
  EditCase load() const;
};

// Max over handle vertices of |p' - T p| and over fixed vertices of |p' - p|.
double handle_error(const EditCase& c, const Positions& rest, const Positions& deformed);

}  // namespace msd::cli
