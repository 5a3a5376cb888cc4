#pragma once
// Command-line options that choose and configure an editing method (see reconstruction/registry.h).

#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "reconstruction/registry.h"

namespace msd::cli {

// Checks that an option is a finite length >= 0, naming the option.
CLI::Validator nonnegative_length();

// --base, --detail-scale and --fairing: how the multi-scale base is computed (deform, compare, decompose).
void add_decomposition_options(CLI::App& cmd, BaseKind& base, double& detail_scale, int& fairing_order);

struct DeformerOptions {
  std::string method = "shell";
  std::string encoding = "normal";
  CLI::Option* encoding_option = nullptr;  // set by add_to(): whether --encoding was given
  int fairing_order = 2;
  MethodOptions options;
  // --method, --encoding and add_settings().
  void add_to(CLI::App& cmd);
  // The methods' settings alone (operator, propagation, multi-scale decomposition), for runs of several methods.
  void add_settings(CLI::App& cmd);
  // The registry name: --method, with "multiscale" completed by --encoding. Throws InvalidInput when
  // --encoding was given with another method.
  std::string method_name() const;
  // The chosen method, configured. Throws InvalidInput for an unknown name, listing the known ones.
  std::unique_ptr<Deformer> make() const;
  // The options alone, with the fairing order applied (for runs of several methods).
  MethodOptions method_options() const;
};

}  // namespace msd::cli
