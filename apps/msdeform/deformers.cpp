#include "apps/msdeform/deformers.h"

#include "core/errors.h"

namespace msd::cli {

std::vector<std::string> deformer_names() { return {"shell"}; }

void DeformerOptions::add_to(CLI::App& cmd) {
  std::string names;
  for (const auto& n : deformer_names()) names += (names.empty() ? "" : "|") + n;
  cmd.add_option("--method", method, "Editing method: " + names)->capture_default_str();
  cmd.add_option("--ks", shell.ks, "shell: stretching stiffness (membrane)")->capture_default_str();
  cmd.add_option("--kb", shell.kb, "shell: bending stiffness (thin plate)")->capture_default_str();
}

std::unique_ptr<Deformer> DeformerOptions::make() const {
  if (method == "shell") return std::make_unique<ShellDeformer>(shell);
  std::string names;
  for (const auto& n : deformer_names()) names += (names.empty() ? "" : ", ") + n;
  throw InvalidInput("unknown method '" + method + "' (known: " + names + ")");
}

}  // namespace msd::cli
