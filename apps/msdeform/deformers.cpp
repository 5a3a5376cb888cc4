#include "apps/msdeform/deformers.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>

#include "apps/msdeform/commands.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"

namespace msd::cli {

namespace {
std::string joined(const std::vector<std::string>& names, const char* sep) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : sep) + n;
  return out;
}
// A default value for help text: 1e-06, 1000.
std::string compact(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}
}  // namespace

CLI::Validator nonnegative_length() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const std::optional<double> x = decimal_number(text);
        return x && *x >= 0 ? std::string() : "'" + text + "' must be a finite length >= 0";
      },
      "LENGTH>=0");
}

void DecompositionArgs::add_to(CLI::App& cmd) {
  base_option =
      cmd.add_option("--base", options.kind,
                     "low-pass: smooth all of S at the detail scale (keeps the shape); fairing: fair the free region "
                     "(only for free regions small next to the shape; needs a region); remeshed: the low-pass base "
                     "remeshed isotropically (--remesh-base); subdivision: the Loop surface of the control mesh "
                     "(built-in scenes)")
          ->transform(CLI::CheckedTransformer(
              std::map<std::string, DecompositionKind>{{"low-pass", DecompositionKind::LowPass},
                                                       {"fairing", DecompositionKind::Fairing},
                                                       {"remeshed", DecompositionKind::Remeshed},
                                                       {"subdivision", DecompositionKind::Subdivision}},
              CLI::ignore_case))
          ->default_str("low-pass");
  scale_option = cmd.add_option("--detail-scale", options.low_pass.detail_scale,
                 "low-pass base: features shorter than this length (mesh units) are details; 0 chooses it from the "
                 "detail heights (where they stop growing with the scale; no detail layer: the base is the mesh)")
      ->check(nonnegative_length())
      ->capture_default_str();
  solver_option =
      cmd.add_option(
             "--low-pass-solver", options.low_pass.solver,
             "how the low-pass base's system is solved: conjugate-gradients (preconditioned, condition "
             "number <= 2; half the memory of a factorisation, and right where it fails: a closed piece far "
             "smaller than the detail scale, a vertex of thousands of neighbours; the factorisation where "
             "they "
             "do not apply, e.g. a vertex without area) or factorisation")
          ->transform(CLI::CheckedTransformer(
              std::map<std::string, LowPassSolver>{{"conjugate-gradients", LowPassSolver::ConjugateGradients},
                                                   {"factorisation", LowPassSolver::Factorisation}},
              CLI::ignore_case))
          ->default_str("conjugate-gradients");
  fairing_option = cmd.add_option("--fairing", fairing_order, "--base fairing: order 1 membrane, 2 thin plate, 3 minimum variation")
      ->check(CLI::Range(1, 3))
      ->capture_default_str();
  remesh_option = cmd.add_option("--remesh-base", options.remesh_edge_length,
                                 "remeshed base: edge length (mesh units; 0 = the mean edge length); alone it selects "
                                 "--base remeshed")
                      ->check(nonnegative_length())
                      ->capture_default_str();
}

bool DecompositionArgs::given() const {
  for (const CLI::Option* o : {base_option, remesh_option, scale_option, fairing_option, solver_option})
    if (o && o->count() > 0) return true;
  return false;
}

DecompositionOptions DecompositionArgs::resolve(const EditCase& edit) const {
  DecompositionOptions o = options;
  o.fairing = static_cast<FairingOrder>(fairing_order);
  if (remesh_option && remesh_option->count() > 0) {
    if (base_option && base_option->count() > 0 && o.kind != DecompositionKind::Remeshed)
      throw InvalidInput(std::string("--remesh-base applies to --base remeshed, not --base ") + to_string(o.kind));
    o.kind = DecompositionKind::Remeshed;
  }
  // Options of another base would be ignored.
  if (fairing_option && fairing_option->count() > 0 && o.kind != DecompositionKind::Fairing)
    throw InvalidInput(std::string("--fairing applies to --base fairing, not --base ") + to_string(o.kind));
  if (scale_option && scale_option->count() > 0 && !reads_detail_scale(o.kind))
    throw InvalidInput(std::string("--detail-scale applies to --base low-pass or remeshed, not --base ") +
                       to_string(o.kind));
  if (solver_option && solver_option->count() > 0 && !reads_detail_scale(o.kind))
    throw InvalidInput(std::string("--low-pass-solver applies to --base low-pass or remeshed, not --base ") +
                       to_string(o.kind));
  if (o.kind == DecompositionKind::Subdivision) {
    if (!edit.control)
      throw InvalidInput("--base subdivision needs a mesh with Loop subdivision connectivity and its control mesh; "
                         "the built-in scenes (--scene) carry one, " + edit.name + " does not: use --base low-pass");
    o.control = edit.control;
  }
  return o;
}

void DeformerOptions::add_to(CLI::App& cmd) {
  cmd.add_option("--method", method, "Editing method: shell|propagate|multiscale (with --encoding), or a full name: " +
                                         joined(builtin_methods().names(), "|"))
      ->capture_default_str();
  encoding_option = cmd.add_option("--encoding", encoding, "multiscale: detail encoding: " + joined(encoding_names(), "|"))
      ->check(CLI::IsMember(encoding_names()))
      ->capture_default_str();
  add_settings(cmd);
}

void DeformerOptions::add_settings(CLI::App& cmd) {
  // Each method's own options are scoped to it: check_used_by() refuses one that no chosen method reads.
  scoped_options.clear();
  auto* shell = cmd.add_option_group("shell", "shell and multiscale: the thin-shell operator (9.2)");
  scoped_options.push_back(
      {shell->add_option("--ks", settings.shell.ks, "stretching stiffness (membrane)")->capture_default_str(), {"shell"}});
  scoped_options.push_back(
      {shell->add_option("--kb", settings.shell.kb, "bending stiffness (thin plate)")->capture_default_str(), {"shell"}});
  auto* prop = cmd.add_option_group("propagate", "propagate: transformation propagation (9.1)");
  const auto propagate = [&](CLI::Option* o) { scoped_options.push_back({o, {"propagate"}}); };
  propagate(prop->add_option("--field", settings.propagation.field, "blend field: euclidean, geodesic or harmonic")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, PropagationField>{{"euclidean", PropagationField::Euclidean},
                                                  {"geodesic", PropagationField::Geodesic},
                                                  {"harmonic", PropagationField::Harmonic}},
          CLI::ignore_case))
      ->default_str("harmonic"));
  propagate(geodesic_time_option = prop->add_option("--geodesic-time-factor", settings.propagation.geodesic.time_factor,
                   "field geodesic: heat-method time step t = m h^2 (h the mean edge length)")
      ->check(CLI::Range(1e-6, 1e6))
      ->capture_default_str());
  propagate(prop->add_option("--blend", settings.propagation.blend,
                   "matrix (s T(p) + (1-s) p) or decomposed (slerp rotation, scale/shear, translation)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, PropagationBlend>{{"matrix", PropagationBlend::Matrix},
                                                  {"decomposed", PropagationBlend::Decomposed}},
          CLI::ignore_case))
      ->default_str("matrix"));
  propagate(prop->add_option("--transfer", settings.propagation.transfer, "transfer function of s: linear or smoothstep")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, PropagationTransfer>{{"linear", PropagationTransfer::Linear},
                                                     {"smoothstep", PropagationTransfer::SmoothStep}},
          CLI::ignore_case))
      ->default_str("linear"));
  auto* laplacian = cmd.add_option_group("laplacian", "laplacian: Laplacian editing (9.4.2)");
  scoped_options.push_back(
      {laplacian->add_flag("--laplacian-explicit{false}", settings.laplacian.implicit,
                           "explicit variant: δ'_i = M_i δ_i with M_i propagated from the handles (9.4.3) instead of "
                           "the implicit linearised similarities (9.11)"),
       {"laplacian"}});
  // One pair of options for both iterative methods: bound to DeformerOptions and copied into the chosen
  // method's settings by method_settings() (their defaults differ per method).
  auto* iterative = cmd.add_option_group("iterative methods",
                                        "arap, primo: iterations per frame and stopping test; "
                                        "multiscale-volumes: --iterations");
  iterations_option = iterative->add_option("--iterations", iterations,
                                            "iterations per frame at most (default: arap " +
                                                std::to_string(ArapOptions{}.max_iterations) + ", primo " +
                                                std::to_string(PrimoOptions{}.max_iterations) +
                                                ", multiscale-volumes " +
                                                std::to_string(DisplacementVolumeOptions{}.max_iterations) +
                                                " relaxation sweeps)")
                          ->check(CLI::Range(1, 1000000));
  tolerance_option = iterative->add_option("--tolerance", tolerance,
                                           "stop when one iteration moves no vertex (arap) or no prism corner (primo) "
                                           "by more than this fraction of the bounding-box diagonal; 0: exactly "
                                           "--iterations (default: arap " + compact(ArapOptions{}.tolerance) +
                                               ", primo " + compact(PrimoOptions{}.tolerance) + ")")
                         ->check(CLI::Range(0.0, 1.0));  // a fraction (NonNegativeNumber printed DBL_MAX)
  scoped_options.push_back({iterations_option, {"arap", "primo", "multiscale-volumes"}});
  scoped_options.push_back({tolerance_option, {"arap", "primo"}});
  auto* arap = cmd.add_option_group("arap", "arap: as-rigid-as-possible (9.8)");
  scoped_options.push_back({arap->add_option("--anderson", settings.arap.anderson,
                                             "Anderson acceleration window (Peng et al. 2018), 0: plain local/global")
                                ->check(CLI::Range(0, 8))
                                ->capture_default_str(),
                            {"arap"}});
  scoped_options.push_back({arap->add_option("--arap-energy", settings.arap.energy, "rigid cells: spokes or spokes-and-rims")
                                ->transform(CLI::CheckedTransformer(
                                    std::map<std::string, ArapEnergy>{{"spokes", ArapEnergy::Spokes},
                                                                      {"spokes-and-rims", ArapEnergy::SpokesAndRims}},
                                    CLI::ignore_case))
                                ->default_str("spokes"),
                            {"arap"}});
  auto* primo = cmd.add_option_group("primo", "primo: coupled rigid prisms, Botsch et al. 2006 (9.8)");
  scoped_options.push_back({primo->add_option("--prism-thickness", settings.primo.thickness,
                                              "prism height relative to the mean edge length (> 0); thicker prisms "
                                              "resist bending more")
                                ->check(CLI::Range(1e-6, 1e6))
                                ->capture_default_str(),
                            {"primo"}});
  auto* space = cmd.add_option_group("space", "lattice, cage-mvc, cage-harmonic, rbf: space deformations (9.5, 9.6)");
  const std::vector<std::string> free_form = {"lattice", "cage-mvc", "cage-harmonic"};
  scoped_options.push_back({space->add_flag("--seed-least-norm", seed_least_norm,
                                            "lattice, cage: the seed's least-norm solve (9.13) alone; by default the "
                                            "constraints' best affine map is fitted first and (9.13) corrects the rest, "
                                            "so affine edits are reproduced everywhere"),
                            free_form});
  scoped_options.push_back({space->add_option("--lattice-cells", settings.lattice.cells_longest,
                                              "lattice: cells along the longest side of the box (the others get cells "
                                              "of the same size)")
                                ->check(CLI::Range(1, LatticeOptions::kMaxCells))
                                ->capture_default_str(),
                            {"lattice"}});
  scoped_options.push_back({space->add_option("--lattice-margin", settings.lattice.margin,
                                              "lattice: space around the input's box on each side, relative to its diagonal")
                                ->check(CLI::Range(0.0, LatticeOptions::kMaxMargin))
                                ->capture_default_str(),
                            {"lattice"}});
  const std::vector<std::string> cages = {"cage-mvc", "cage-harmonic"};
  scoped_options.push_back({space->add_option("--cage", cage_file,
                                              "cage-*: a closed, consistently oriented triangle mesh enclosing the "
                                              "input (.off .obj .ply .stl); default: an offset 26-DOP of the input")
                                ->check(CLI::ExistingFile),
                            cages});
  scoped_options.push_back({space->add_option("--cage-margin", settings.cage.margin,
                                              "cage-*, generated cage: its offset from the input, relative to the "
                                              "bounding-box diagonal")
                                ->check(CLI::Range(1e-6, 10.0))
                                ->capture_default_str(),
                            cages});
  scoped_options.push_back({space->add_option("--cage-subdivisions", settings.cage.subdivisions,
                                              "cage-*, generated cage: midpoint subdivisions of the 26-DOP (each "
                                              "quadruples its triangles: more control vertices)")
                                ->check(CLI::Range(0, 4))
                                ->capture_default_str(),
                            cages});
  scoped_options.push_back({space->add_option("--harmonic-resolution", settings.cage.harmonic_resolution,
                                              "cage-harmonic: grid cells along the cage's longest side (128: about "
                                              "40 s and 4 GB with a 186-vertex cage)")
                                ->check(CLI::Range(4, CageOptions::kMaxHarmonicResolution))
                                ->capture_default_str(),
                            {"cage-harmonic"}});
  scoped_options.push_back({space->add_option("--max-centres", settings.rbf.max_centres,
                                              "rbf: most centres; more constrained vertices are subsampled by "
                                              "farthest-point sampling (O(n^3) factorisation)")
                                ->check(CLI::Range(1, RbfOptions::kMaxCentres))
                                ->capture_default_str(),
                            {"rbf"}});
  auto* ms = cmd.add_option_group("multiscale", "multiscale: decompose, deform the base, add the details back (9.3)");
  decomposition.add_to(*ms);
  std::vector<std::string> single_scale;
  for (const auto& n : builtin_methods().names())
    if (!is_multiscale(n)) single_scale.push_back(n);
  base_method_option = ms->add_option("--base-method", settings.base_method, "the method that deforms the base: " + joined(single_scale, "|"))
      ->check(CLI::IsMember(single_scale))
      ->capture_default_str();
}

void DeformerOptions::check_used_by(const std::vector<std::string>& methods, const std::string& flag) const {
  const bool multiscale = std::any_of(methods.begin(), methods.end(), is_multiscale);
  const bool one = methods.size() == 1;
  if (!multiscale && (decomposition.given() || (base_method_option && base_method_option->count() > 0)))
    throw InvalidInput(
        "--base, --detail-scale, --low-pass-solver, --fairing, --remesh-base and --base-method apply to "
        "--method "
        "multiscale; " +
        (one ? flag + " " + methods[0] + " has no"
             : "none of " + flag + " " + joined(methods, ", ") + " has a") +
        " base to decompose");
  const auto used = [&](const std::string& m) {
    return std::find(methods.begin(), methods.end(), m) != methods.end() ||
           (multiscale && settings.base_method == m);
  };
  for (const Scoped& scoped : scoped_options) {
    if (scoped.option->count() == 0 || std::any_of(scoped.methods.begin(), scoped.methods.end(), used))
      continue;
    throw InvalidInput(scoped.option->get_name() + " applies to --method " + joined(scoped.methods, ", ") +
                       " (or multiscale with such a --base-method), not " +
                       (one ? flag + " " + methods[0] : "to any of " + flag + " " + joined(methods, ", ")));
  }
}

std::string DeformerOptions::method_name() const {
  const std::string full = method == "multiscale" ? "multiscale-" + encoding : method;
  check_used_by({full}, "--method");
  if (method == "multiscale") return full;
  if (encoding_option && encoding_option->count() > 0)
    throw InvalidInput(
        "--encoding " + encoding + " applies to --method multiscale; --method " + method +
        (is_multiscale(method) ? " names its encoding itself" : " has no detail encoding"));
  return method;
}

MethodSettings DeformerOptions::method_settings(const EditCase& edit) const {
  MethodSettings s = settings;
  if (iterations_option && iterations_option->count() > 0)
    s.arap.max_iterations = s.primo.max_iterations = s.encoding.volumes.max_iterations = iterations;
  if (tolerance_option && tolerance_option->count() > 0) s.arap.tolerance = s.primo.tolerance = tolerance;
  s.lattice.least_norm.affine_part = s.cage.least_norm.affine_part = !seed_least_norm;
  if (!cage_file.empty()) {
    for (const Scoped& scoped : scoped_options)
      if (scoped.option->count() > 0 &&
          (scoped.option->get_name() == "--cage-margin" || scoped.option->get_name() == "--cage-subdivisions"))
        throw InvalidInput(scoped.option->get_name() + " shapes the generated cage; with --cage the given cage is used as it is");
    Mesh cage;
    try {
      cage = load_mesh(cage_file);
    } catch (const Error& e) {
      throw InvalidInput(std::string("--cage: the cage must be a closed, manifold, consistently oriented triangle "
                                     "mesh: ") + e.what());
    }
    s.cage.cage_P = positions(cage);
    s.cage.cage_F = faces(cage);
  }
  s.decomposition = decomposition.resolve(edit);
  if (geodesic_time_option && geodesic_time_option->count() > 0 &&
      s.propagation.field != PropagationField::Geodesic)
    throw InvalidInput("--geodesic-time-factor applies to --field geodesic (the heat method's time step)");
  return s;
}

std::unique_ptr<Deformer> DeformerOptions::make(const EditCase& edit) const {
  return builtin_methods().make(method_name(), method_settings(edit));
}

}  // namespace msd::cli
