#include "apps/msdeform/deformers.h"

#include <cmath>
#include <cstdlib>
#include <map>

#include "core/errors.h"
#include "reconstruction/multiscale.h"

namespace msd::cli {

namespace {
std::string joined(const std::vector<std::string>& names, const char* sep) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : sep) + n;
  return out;
}
}  // namespace

CLI::Validator nonnegative_length() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0') return "'" + text + "' is not a number";
        if (!std::isfinite(x) || x < 0) return "'" + text + "' must be a finite length >= 0";
        return {};
      },
      "LENGTH>=0");
}

void add_decomposition_options(CLI::App& cmd, BaseKind& base, double& detail_scale, int& fairing_order) {
  cmd.add_option("--base", base,
                 "low-pass: smooth all of S at the detail scale (keeps the shape); fairing: fair the free region "
                 "(only for free regions small next to the shape; needs a region)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, BaseKind>{{"low-pass", BaseKind::LowPass}, {"fairing", BaseKind::Fairing}},
          CLI::ignore_case))
      ->default_str("low-pass");
  cmd.add_option("--detail-scale", detail_scale,
                 "low-pass base: features shorter than this length (mesh units) are details; 0 chooses it from the "
                 "detail heights (where they stop growing with the scale; no detail layer: the base is the mesh)")
      ->check(nonnegative_length())
      ->capture_default_str();
  cmd.add_option("--fairing", fairing_order, "--base fairing: order 1 membrane, 2 thin plate, 3 minimum variation")
      ->check(CLI::Range(1, 3))
      ->capture_default_str();
}

void DeformerOptions::add_to(CLI::App& cmd) {
  cmd.add_option("--method", method, "Editing method: shell|propagate|multiscale (with --encoding), or a full name: " +
                                         joined(method_names(), "|"))
      ->capture_default_str();
  encoding_option = cmd.add_option("--encoding", encoding, "multiscale: detail encoding: " + joined(encoding_names(), "|"))
      ->capture_default_str();
  add_settings(cmd);
}

void DeformerOptions::add_settings(CLI::App& cmd) {
  auto* shell = cmd.add_option_group("shell", "shell and multiscale: the thin-shell operator (9.2)");
  shell->add_option("--ks", options.shell.ks, "stretching stiffness (membrane)")->capture_default_str();
  shell->add_option("--kb", options.shell.kb, "bending stiffness (thin plate)")->capture_default_str();
  auto* prop = cmd.add_option_group("propagate", "propagate: transformation propagation (9.1)");
  prop->add_option("--field", options.propagation.field, "blend field: euclidean, geodesic or harmonic")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, PropagationField>{{"euclidean", PropagationField::Euclidean},
                                                  {"geodesic", PropagationField::Geodesic},
                                                  {"harmonic", PropagationField::Harmonic}},
          CLI::ignore_case))
      ->default_str("harmonic");
  prop->add_option("--blend", options.propagation.blend,
                   "matrix (s T(p) + (1-s) p) or decomposed (slerp rotation, scale/shear, translation)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, PropagationBlend>{{"matrix", PropagationBlend::Matrix},
                                                  {"decomposed", PropagationBlend::Decomposed}},
          CLI::ignore_case))
      ->default_str("matrix");
  prop->add_option("--transfer", options.propagation.transfer, "transfer function of s: linear or smoothstep")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, PropagationTransfer>{{"linear", PropagationTransfer::Linear},
                                                     {"smoothstep", PropagationTransfer::SmoothStep}},
          CLI::ignore_case))
      ->default_str("linear");
  auto* ms = cmd.add_option_group("multiscale", "multiscale: decompose, deform the base, add the details back (9.3)");
  add_decomposition_options(*ms, options.base, options.low_pass.detail_scale, fairing_order);
  ms->add_option("--remesh-base", options.remesh_base_edge_length,
                 "remesh the base isotropically to this edge length before encoding (0: keep S's triangles)")
      ->check(nonnegative_length())
      ->capture_default_str();
}

std::string DeformerOptions::method_name() const {
  if (method == "multiscale") return "multiscale-" + encoding;
  if (encoding_option && encoding_option->count() > 0)
    throw InvalidInput("--encoding " + encoding + " applies to --method multiscale; --method " + method +
                       (method.rfind("multiscale-", 0) == 0 ? " names its encoding itself" : " has no detail encoding"));
  return method;
}

MethodOptions DeformerOptions::method_options() const {
  MethodOptions o = options;
  o.fairing = static_cast<FairingOrder>(fairing_order);
  return o;
}

std::unique_ptr<Deformer> DeformerOptions::make() const { return make_deformer(method_name(), method_options()); }

}  // namespace msd::cli
