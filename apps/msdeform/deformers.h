#pragma once
// The editing methods the command line can run, by name, with their options.

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "deformation/deformer.h"
#include "deformation/shell.h"

namespace msd::cli {

struct DeformerOptions {
  std::string method = "shell";
  ShellOptions shell;
  void add_to(CLI::App& cmd);
  // The named method, configured. Throws InvalidInput for an unknown name, listing the known ones.
  std::unique_ptr<Deformer> make() const;
};

std::vector<std::string> deformer_names();

}  // namespace msd::cli
