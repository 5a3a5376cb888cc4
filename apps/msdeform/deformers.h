#pragma once
// Command-line options that choose and configure an editing method from the catalogue
// (reconstruction/catalogue.h).

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "msdeform/core/edit_case.h"
#include "msdeform/reconstruction/catalogue.h"

namespace msd::cli {

// Checks that an option is a finite length >= 0, naming the option.
CLI::Validator nonnegative_length();

// --base, --detail-scale, --low-pass-solver, --fairing and --remesh-base: how the multi-scale base is
// computed (deform,
// compare, decompose). Call resolve_decomposition() after parsing.
struct DecompositionArgs {
  DecompositionOptions options;
  int fairing_order = 2;
  CLI::Option* base_option = nullptr;
  CLI::Option* remesh_option = nullptr;
  CLI::Option* scale_option = nullptr;
  CLI::Option* fairing_option = nullptr;
  CLI::Option* solver_option = nullptr;
  // Whether any of these options was given (they apply to multi-scale methods only).
  bool given() const;
  void add_to(CLI::App& cmd);
  // The options with the fairing order applied; --remesh-base alone selects the remeshed base. The
  // subdivision base takes the control mesh of the edit (built-in scenes carry one). Throws InvalidInput
  // for --remesh-base with another base, or a subdivision base for a mesh without a control mesh.
  DecompositionOptions resolve(const EditCase& edit) const;
};

struct DeformerOptions {
  std::string method = "shell";
  std::string encoding = "normal";
  CLI::Option* encoding_option = nullptr;  // set by add_to(): whether --encoding was given
  CLI::Option* base_method_option = nullptr;
  // Options that configure only some methods: given with another method they are refused by name
  // (they would be ignored).
  struct Scoped {
    CLI::Option* option;
    std::vector<std::string> methods;
  };
  std::vector<Scoped> scoped_options;
  CLI::Option* iterations_option = nullptr;  // --iterations (arap and primo)
  CLI::Option* tolerance_option = nullptr;   // --tolerance
  CLI::Option* geodesic_time_option = nullptr;  // --geodesic-time-factor (only with --field geodesic)
  int iterations = 0;                        // --iterations, copied into the method's settings when given
  double tolerance = 0;                      // --tolerance, likewise
  bool seed_least_norm = false;              // --seed-least-norm (lattice, cage-*)
  std::string cage_file;                     // --cage (cage-*)
  MethodSettings settings;
  DecompositionArgs decomposition;
  // --method, --encoding and add_settings().
  void add_to(CLI::App& cmd);
  // The methods' settings alone (operator, propagation, multi-scale decomposition and base method), for
  // runs of several methods.
  void add_settings(CLI::App& cmd);
  // The catalogue name: --method, with "multiscale" completed by --encoding. Throws InvalidInput when
  // --encoding, a decomposition option or --base-method was given with a method that is not multi-scale
  // (they would be ignored).
  std::string method_name() const;
  // Throws InvalidInput when an option given configures none of `methods` (catalogue names): a scoped
  // option, a decomposition option or --base-method without a multi-scale method (it would be ignored).
  // `flag` is the option that named the methods, for the message: "--method" or "--methods".
  void check_used_by(const std::vector<std::string>& methods, const std::string& flag) const;
  // The settings for an edit (the decomposition resolved for it).
  MethodSettings method_settings(const EditCase& edit) const;
  // The chosen method, configured for the edit. Throws InvalidInput for an unknown name, listing the known ones.
  std::unique_ptr<Deformer> make(const EditCase& edit) const;
};

}  // namespace msd::cli
