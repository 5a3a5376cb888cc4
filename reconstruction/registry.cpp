#include "reconstruction/registry.h"

#include "core/errors.h"
#include "reconstruction/multiscale.h"

namespace msd {

std::vector<std::string> method_names() {
  std::vector<std::string> names = {"shell", "propagate"};
  for (const auto& e : encoding_names()) names.push_back("multiscale-" + e);
  return names;
}

std::unique_ptr<Deformer> make_deformer(const std::string& name, const MethodOptions& options) {
  if (name == "shell") return std::make_unique<ShellDeformer>(options.shell);
  if (name == "propagate") return std::make_unique<TransformationPropagation>(options.propagation);
  const std::string prefix = "multiscale-";
  if (name.rfind(prefix, 0) == 0) {
    MultiscaleOptions o;
    o.encoding = name.substr(prefix.size());
    o.shell = options.shell;
    o.base = options.base;
    o.low_pass = options.low_pass;
    o.fairing = options.fairing;
    o.remesh_base_edge_length = options.remesh_base_edge_length;
    return std::make_unique<MultiscaleDeformer>(o);
  }
  std::string known;
  for (const auto& n : method_names()) known += (known.empty() ? "" : ", ") + n;
  throw InvalidInput("unknown method '" + name + "' (known: " + known + ")");
}

}  // namespace msd
