// msdeform.Deformer: any method of the catalogue (reconstruction/catalogue.h) by name, configured by
// keyword options that map onto msd::MethodSettings (as apps/msdeform/deformers.cpp maps the command
// line's), and driven with numpy arrays.

#include <pybind11/functional.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <climits>
#include <cmath>
#include <functional>
#include <memory>
#include <stdexcept>
#include <utility>

#include "common.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/reconstruction/catalogue.h"

namespace msdpy {
namespace {

// propagate's transfer function given as a Python callable. Holds the GIL around each call (prepare calls it
// from the solver's threads) and where the last copy lets the callable go; options returns the callable
// itself. A result that is no number is a TypeError naming the option rather than pybind11's cast error.
struct PythonTransfer {
  std::shared_ptr<py::object> callable;
  explicit PythonTransfer(py::handle f)
      : callable(new py::object(py::reinterpret_borrow<py::object>(f)), [](py::object* o) {
          py::gil_scoped_acquire gil;
          delete o;
        }) {}
  double operator()(double x) const {
    py::gil_scoped_acquire gil;
    py::object y = (*callable)(x);
    try {
      return y.cast<double>();
    } catch (const py::cast_error&) {
      throw py::type_error("option transfer: the callable must return a number, t(" + std::to_string(x) +
                           ") did not");
    }
  }
};

using msd::is_multiscale;
using msd::MethodSettings;

std::string joined(const std::vector<std::string>& items, const char* sep = ", ") {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : sep) + s;
  return out;
}

std::string type_name(py::handle obj) { return Py_TYPE(obj.ptr())->tp_name; }

bool is_numpy_bool(py::handle v) {
  return std::string(Py_TYPE(v.ptr())->tp_name) == "numpy.bool_";
}

// ---------------------------------------------------------------------------------------------------
// Option values: strict types (a bool is not a number, a float is not an int), clear TypeErrors.

double real_value(py::handle v, const std::string& name) {
  if (py::isinstance<py::bool_>(v) || is_numpy_bool(v) || py::isinstance<py::str>(v) || v.is_none())
    throw py::type_error("option " + name + " must be a number, got " + type_name(v));
  try {
    return v.cast<double>();
  } catch (const py::cast_error&) {
    throw py::type_error("option " + name + " must be a number, got " + type_name(v));
  }
}

int int_value(py::handle v, const std::string& name) {
  if (py::isinstance<py::bool_>(v) || is_numpy_bool(v) || !PyIndex_Check(v.ptr()))
    throw py::type_error("option " + name + " must be an int, got " + type_name(v));
  const py::int_ index(py::reinterpret_steal<py::object>(PyNumber_Index(v.ptr())));
  int overflow = 0;
  const long long x = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
  if (overflow != 0) throw py::value_error("option " + name + " = " + std::string(py::str(py::handle(index))) + " is out of range");
  if (x < INT_MIN || x > INT_MAX) throw py::value_error("option " + name + " = " + std::to_string(x) + " is out of range");
  return static_cast<int>(x);
}

bool bool_value(py::handle v, const std::string& name) {
  if (!py::isinstance<py::bool_>(v) && !is_numpy_bool(v))
    throw py::type_error("option " + name + " must be True or False, got " + type_name(v));
  return PyObject_IsTrue(v.ptr()) == 1;
}

std::string string_value(py::handle v, const std::string& name) {
  if (!py::isinstance<py::str>(v)) throw py::type_error("option " + name + " must be a str, got " + type_name(v));
  std::string s = v.cast<std::string>();
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// ---------------------------------------------------------------------------------------------------
// The option table. An option belongs to groups; a method accepts the options of its groups (a
// multiscale method also those of its base method). `set` writes the value for the group that matched.

struct Option {
  std::string name;
  std::vector<std::string> groups;
  std::string help;
  std::function<void(MethodSettings&, const std::string& group, py::handle value)> set;
  std::function<py::object(const MethodSettings&, const std::string& group)> get;
  // `get` gives None where the option is not in use (no cage given, no remeshed base): None given back,
  // as in Deformer(name, **d.options), leaves the option unset.
  bool none_is_unset = false;
};

template <class Field>
Option real_option(std::string name, std::vector<std::string> groups, std::string help, Field field) {
  return {name, std::move(groups), std::move(help),
          [field, name](MethodSettings& s, const std::string& g, py::handle v) { field(s, g) = real_value(v, name); },
          [field](const MethodSettings& s, const std::string& g) -> py::object { return py::float_(field(s, g)); }};
}

template <class Field>
Option int_option(std::string name, std::vector<std::string> groups, std::string help, Field field) {
  return {name, std::move(groups), std::move(help),
          [field, name](MethodSettings& s, const std::string& g, py::handle v) { field(s, g) = int_value(v, name); },
          [field](const MethodSettings& s, const std::string& g) -> py::object { return py::int_(field(s, g)); }};
}

template <class Field>
Option bool_option(std::string name, std::vector<std::string> groups, std::string help, Field field) {
  return {name, std::move(groups), std::move(help),
          [field, name](MethodSettings& s, const std::string& g, py::handle v) { field(s, g) = bool_value(v, name); },
          [field](const MethodSettings& s, const std::string& g) -> py::object { return py::bool_(field(s, g)); }};
}

// `o` reading None where `unused(settings, group)` holds (the option is not in use there), and accepting
// None back as left out.
template <class Unused>
Option none_when(Option o, Unused unused) {
  o.get = [get = o.get, unused](const MethodSettings& s, const std::string& g) -> py::object {
    return unused(s, g) ? py::object(py::none()) : get(s, g);
  };
  o.none_is_unset = true;
  return o;
}

template <class Enum>
using Choices = std::vector<std::pair<std::string, Enum>>;

template <class Enum>
Enum choice_value(py::handle v, const std::string& name, const Choices<Enum>& choices) {
  const std::string text = string_value(v, name);
  for (const auto& [label, value] : choices)
    if (label == text) return value;
  std::vector<std::string> labels;
  for (const auto& c : choices) labels.push_back("'" + c.first + "'");
  throw py::value_error("option " + name + " must be one of " + joined(labels) + ", got '" + text + "'");
}

template <class Enum>
py::object choice_label(Enum value, const Choices<Enum>& choices) {
  for (const auto& [label, v] : choices)
    if (v == value) return py::str(label);
  return py::none();
}

template <class Enum, class Field>
Option choice_option(std::string name, std::vector<std::string> groups, std::string help, Choices<Enum> choices,
                     Field field) {
  std::vector<std::string> labels;
  for (const auto& c : choices) labels.push_back("'" + c.first + "'");
  help += " (" + joined(labels, " | ") + ")";
  return {name, std::move(groups), std::move(help),
          [field, name, choices](MethodSettings& s, const std::string& g, py::handle v) {
            field(s, g) = choice_value(v, name, choices);
          },
          [field, choices](const MethodSettings& s, const std::string& g) { return choice_label(field(s, g), choices); }};
}

const Choices<msd::PropagationField> kFields = {{"euclidean", msd::PropagationField::Euclidean},
                                                {"geodesic", msd::PropagationField::Geodesic},
                                                {"harmonic", msd::PropagationField::Harmonic}};
const Choices<msd::PropagationBlend> kBlends = {{"matrix", msd::PropagationBlend::Matrix},
                                                {"decomposed", msd::PropagationBlend::Decomposed}};
const Choices<msd::PropagationTransfer> kTransfers = {{"linear", msd::PropagationTransfer::Linear},
                                                      {"smoothstep", msd::PropagationTransfer::SmoothStep}};
const Choices<msd::ArapEnergy> kEnergies = {{"spokes", msd::ArapEnergy::Spokes},
                                            {"spokes-and-rims", msd::ArapEnergy::SpokesAndRims}};
const Choices<msd::DecompositionKind> kBases = {{"low-pass", msd::DecompositionKind::LowPass},
                                                {"fairing", msd::DecompositionKind::Fairing},
                                                {"remeshed", msd::DecompositionKind::Remeshed},
                                                {"subdivision", msd::DecompositionKind::Subdivision}};
const Choices<msd::LowPassSolver> kLowPassSolvers = {
    {"conjugate-gradients", msd::LowPassSolver::ConjugateGradients},
    {"factorisation", msd::LowPassSolver::Factorisation}};
const Choices<msd::FairingOrder> kFairings = {{"membrane", msd::FairingOrder::Membrane},
                                              {"thin-plate", msd::FairingOrder::ThinPlate},
                                              {"minimum-variation", msd::FairingOrder::MinimumVariation}};
const Choices<msd::DisplacementFrame> kFrames = {{"local", msd::DisplacementFrame::Local},
                                                 {"global", msd::DisplacementFrame::Global}};

// Which methods a group configures, for messages.
std::string group_methods(const std::string& group) {
  if (group == "cage") return "cage-mvc, cage-harmonic";
  if (group == "multiscale") return "the multiscale-* methods";
  if (group == "base-points") return "multiscale-normal, multiscale-volumes, multiscale-transfer";
  return group;
}

std::vector<std::string> single_scale_methods() {
  std::vector<std::string> out;
  for (const std::string& n : msd::builtin_methods().names())
    if (!is_multiscale(n)) out.push_back(n);
  return out;
}

const std::vector<Option>& options_table() {
  static const std::vector<Option> table = [] {
    std::vector<Option> t;
    const std::vector<std::string> iterative = {"arap", "primo"}, free_form = {"lattice", "cage"};
    // shell (9.2)
    t.push_back(real_option("ks", {"shell"}, "stretching stiffness ks (membrane term); lengths in mesh units",
                            [](auto& s, const std::string&) -> auto& { return s.shell.ks; }));
    t.push_back(real_option("kb", {"shell"}, "bending stiffness kb (thin-plate term); (0, 1) is pure bending",
                            [](auto& s, const std::string&) -> auto& { return s.shell.kb; }));
    // propagate (9.1)
    t.push_back(choice_option("field", {"propagate"}, "the blend field s", kFields,
                              [](auto& s, const std::string&) -> auto& { return s.propagation.field; }));
    t.push_back(choice_option("blend", {"propagate"},
                              "how a vertex applies its handle's transform: s T(p) + (1 - s) p, or rotation "
                              "slerped about the handle centroid, stretch and translation blended",
                              kBlends, [](auto& s, const std::string&) -> auto& { return s.propagation.blend; }));
    {
      Option o{"transfer", {"propagate"},
               "transfer function of s on the free vertices ('linear' | 'smoothstep'), or a Python callable "
               "t(s) mapping [0, 1] into [0, 1] (called during prepare, once per free vertex)",
               [](MethodSettings& s, const std::string&, py::handle v) {
                 if (!py::isinstance<py::str>(v) && PyCallable_Check(v.ptr())) {
                   s.propagation.transfer = msd::PropagationTransfer::Custom;
                   s.propagation.custom_transfer = PythonTransfer(v);
                 } else if (!py::isinstance<py::str>(v)) {
                   throw py::type_error(
                       "option transfer must be 'linear', 'smoothstep' or a callable t(s), got " +
                       type_name(v));
                 } else {
                   s.propagation.transfer = choice_value(v, "transfer", kTransfers);
                   s.propagation.custom_transfer = nullptr;
                 }
               },
               [](const MethodSettings& s, const std::string&) -> py::object {
                 // The callable itself, so that Deformer(name, **d.options) rebuilds the method.
                 if (const auto* f = s.propagation.custom_transfer.target<PythonTransfer>()) return *f->callable;
                 return choice_label(s.propagation.transfer, kTransfers);
               }};
      t.push_back(std::move(o));
    }
    t.push_back(none_when(real_option("geodesic_time_factor", {"propagate"},
                                      "field='geodesic': heat-method time step t = m h^2 (h the mean edge length); "
                                      "None (its value with another field): unset",
                                      [](auto& s, const std::string&) -> auto& {
                                        return s.propagation.geodesic.time_factor;
                                      }),
                          [](const MethodSettings& s, const std::string&) {
                            return s.propagation.field != msd::PropagationField::Geodesic;
                          }));
    // laplacian (9.4.2)
    t.push_back(bool_option("implicit", {"laplacian"},
                            "True: implicit linearised similarities (9.11); False: the explicit variant with "
                            "harmonically propagated transforms (9.4.3)",
                            [](auto& s, const std::string&) -> auto& { return s.laplacian.implicit; }));
    // arap, primo (9.8)
    t.push_back(int_option("iterations", iterative, "iterations per frame at most (>= 1)",
                           [](auto& s, const std::string& g) -> auto& {
                             return g == "arap" ? s.arap.max_iterations : s.primo.max_iterations;
                           }));
    t.push_back(real_option("tolerance", iterative,
                            "stop when an iteration moves no vertex (arap) or prism corner (primo) by more than "
                            "this fraction of the bounding-box diagonal; 0 runs exactly `iterations`",
                            [](auto& s, const std::string& g) -> auto& {
                              return g == "arap" ? s.arap.tolerance : s.primo.tolerance;
                            }));
    t.push_back(int_option("anderson", {"arap"}, "Anderson acceleration window 0..8 (0: plain local/global)",
                           [](auto& s, const std::string&) -> auto& { return s.arap.anderson; }));
    t.push_back(choice_option("energy", {"arap"}, "the rigid cells", kEnergies,
                              [](auto& s, const std::string&) -> auto& { return s.arap.energy; }));
    t.push_back(real_option(
        "min_weight_ratio", {"arap"},
        "cotangent weights are clamped below at this fraction of the median weight magnitude, in (0, 1]",
        [](auto& s, const std::string&) -> auto& { return s.arap.min_weight_ratio; }));
    t.push_back(real_option("thickness", {"primo"}, "prism height relative to the mean edge length (> 0)",
                            [](auto& s, const std::string&) -> auto& { return s.primo.thickness; }));
    // lattice, cage (9.5)
    {
      Option o{"cells", {"lattice"},
               "lattice cells: an int along the longest side of the bounding box (cells of the same size along "
               "the others), or (nx, ny, nz)",
               [](MethodSettings& s, const std::string&, py::handle v) {
                 if (PyIndex_Check(v.ptr()) && !py::isinstance<py::bool_>(v)) {
                   s.lattice.cells_longest = int_value(v, "cells");
                   s.lattice.cells.setZero();
                   return;
                 }
                 if (!py::isinstance<py::sequence>(v) || py::isinstance<py::str>(v) || py::len(v) != 3)
                   throw py::type_error("option cells must be an int or 3 ints (nx, ny, nz), got " + type_name(v));
                 py::sequence seq = py::reinterpret_borrow<py::sequence>(v);
                 for (int i = 0; i < 3; ++i) s.lattice.cells[i] = int_value(seq[static_cast<size_t>(i)], "cells");
               },
               [](const MethodSettings& s, const std::string&) -> py::object {
                 if (s.lattice.cells.any())
                   return py::make_tuple(s.lattice.cells[0], s.lattice.cells[1], s.lattice.cells[2]);
                 return py::int_(s.lattice.cells_longest);
               }};
      t.push_back(std::move(o));
    }
    // The generated cage's shape options read None once a cage is given (they are not in use then).
    const auto cage_given = [](const MethodSettings& s, const std::string& g) {
      return g == "cage" && s.cage.cage_P.rows() > 0;
    };
    t.push_back(none_when(real_option("margin", free_form,
                            "space left around the input's bounding box (lattice) or offset of the generated cage, "
                            "relative to the bounding-box diagonal",
                            [](auto& s, const std::string& g) -> auto& {
                              return g == "lattice" ? s.lattice.margin : s.cage.margin;
                            }),
                            cage_given));
    {
      // The library's flag is affine_part, the command line's and this option's its negation.
      const auto affine_part = [](auto& s, const std::string& g) -> auto& {
        return g == "lattice" ? s.lattice.least_norm.affine_part : s.cage.least_norm.affine_part;
      };
      t.push_back({"seed_least_norm", free_form,
                   "True: the seed's least-norm solve (9.13) alone; False (default): the constraints' best affine map "
                   "first, so affine edits are reproduced everywhere",
                   [affine_part](MethodSettings& s, const std::string& g, py::handle v) {
                     affine_part(s, g) = !bool_value(v, "seed_least_norm");
                   },
                   [affine_part](const MethodSettings& s, const std::string& g) -> py::object {
                     return py::bool_(!affine_part(s, g));
                   }});
    }
    t.push_back(real_option("regularization", free_form,
                            "Tikhonov weight of the least-norm pseudo-inverse, relative to the mean diagonal of N^T N",
                            [](auto& s, const std::string& g) -> auto& {
                              return g == "lattice" ? s.lattice.least_norm.regularization
                                                    : s.cage.least_norm.regularization;
                            }));
    {
      Option o{"cage", {"cage"},
               "a closed, consistently oriented triangle cage enclosing the input: a mesh file path or a (V, F) "
               "pair of arrays; None or left out: an offset 26-DOP of the input",
               [](MethodSettings& s, const std::string&, py::handle v) {
                 if (py::isinstance<py::tuple>(v) || py::isinstance<py::list>(v)) {
                   py::sequence seq = py::reinterpret_borrow<py::sequence>(v);
                   if (py::len(seq) != 2) throw py::type_error("option cage must be a path or a (V, F) pair");
                   s.cage.cage_P = to_positions(seq[0], "cage V");
                   s.cage.cage_F = to_faces(seq[1], "cage F", static_cast<long>(s.cage.cage_P.rows()));
                   return;
                 }
                 const std::string path = fspath(v, "option cage");
                 require_file(path);
                 msd::Mesh cage;
                 try {
                   cage = msd::load_mesh(path);
                 } catch (const msd::Error& e) {
                   throw msd::InvalidInput(std::string("cage: the cage must be a closed, manifold, consistently "
                                                       "oriented triangle mesh: ") + e.what());
                 }
                 s.cage.cage_P = msd::positions(cage);
                 s.cage.cage_F = msd::faces(cage);
               },
               [](const MethodSettings& s, const std::string&) -> py::object {
                 if (s.cage.cage_P.rows() == 0) return py::none();
                 return py::make_tuple(msd::Positions(s.cage.cage_P), msd::Faces(s.cage.cage_F));
               }};
      o.none_is_unset = true;
      t.push_back(std::move(o));
    }
    t.push_back(none_when(int_option("subdivisions", {"cage"}, "generated cage: midpoint subdivisions of the 26-DOP, 0..4",
                                     [](auto& s, const std::string&) -> auto& { return s.cage.subdivisions; }),
                          cage_given));
    t.push_back(int_option("harmonic_resolution", {"cage-harmonic"},
                           "grid cells along the cage's longest side (4..128; memory grows with its cube: 128 takes about 40 s and "
                           "4 GB with a 186-vertex cage)",
                           [](auto& s, const std::string&) -> auto& { return s.cage.harmonic_resolution; }));
    // rbf (9.6)
    t.push_back(int_option("max_centres", {"rbf"},
                           "most RBF centres (farthest-point samples of the constrained vertices beyond it)",
                           [](auto& s, const std::string&) -> auto& { return s.rbf.max_centres; }));
    // multiscale (9.3)
    {
      Option o{"base_method", {"multiscale"},
               "the single-scale method that deforms the base (its own options apply too)",
               [](MethodSettings& s, const std::string&, py::handle v) {
                 const std::string name = string_value(v, "base_method");
                 const std::vector<std::string> allowed = single_scale_methods();
                 if (std::find(allowed.begin(), allowed.end(), name) == allowed.end())
                   throw py::value_error("option base_method must be a single-scale method (" + joined(allowed) +
                                         "), got '" + name + "'");
                 s.base_method = name;
               },
               [](const MethodSettings& s, const std::string&) -> py::object { return py::str(s.base_method); }};
      t.push_back(std::move(o));
    }
    t.push_back(choice_option("base", {"multiscale"}, "how the smooth base B is computed from S", kBases,
                              [](auto& s, const std::string&) -> auto& { return s.decomposition.kind; }));
    t.push_back(none_when(real_option("detail_scale", {"multiscale"},
                                      "low-pass base: features shorter than this length (mesh units) are details; 0 "
                                      "chooses it from the detail heights; None (its value with a fairing or "
                                      "subdivision base): unset",
                                      [](auto& s, const std::string&) -> auto& {
                                        return s.decomposition.low_pass.detail_scale;
                                      }),
                          [](const MethodSettings& s, const std::string&) {
                            return !msd::reads_detail_scale(s.decomposition.kind);
                          }));
    t.push_back(
        none_when(choice_option(
                      "low_pass_solver", {"multiscale"},
                      "how the low-pass base's system is solved: 'conjugate-gradients' (half the memory of a "
                      "factorisation, right where it fails; the factorisation where they do not apply) or "
                      "'factorisation'; None (its value with a fairing or subdivision base): unset",
                      kLowPassSolvers,
                      [](auto& s, const std::string&) -> auto& { return s.decomposition.low_pass.solver; }),
                  [](const MethodSettings& s, const std::string&) {
                    return !msd::reads_detail_scale(s.decomposition.kind);
                  }));
    {
      Option o{"fairing", {"multiscale"},
               "base='fairing': the order of the fairing, 1 | 2 | 3 or 'membrane' | 'thin-plate' | 'minimum-variation'",
               [](MethodSettings& s, const std::string&, py::handle v) {
                 if (PyIndex_Check(v.ptr()) && !py::isinstance<py::bool_>(v)) {
                   const int order = int_value(v, "fairing");
                   if (order < 1 || order > 3)
                     throw py::value_error("option fairing must be 1, 2 or 3, got " + std::to_string(order));
                   s.decomposition.fairing = static_cast<msd::FairingOrder>(order);
                 } else {
                   s.decomposition.fairing = choice_value(v, "fairing", kFairings);
                 }
               },
               [](const MethodSettings& s, const std::string&) -> py::object {
                 return choice_label(s.decomposition.fairing, kFairings);
               }};
      t.push_back(none_when(std::move(o), [](const MethodSettings& s, const std::string&) {
        return s.decomposition.kind != msd::DecompositionKind::Fairing;
      }));
    }
    t.push_back(none_when(real_option("remesh_edge_length", {"multiscale"},
                                      "remeshed base: target edge length in mesh units (0: the mean edge length); "
                                      "given without `base` it selects base='remeshed'; None (its value with "
                                      "another base): unset",
                                      [](auto& s, const std::string&) -> auto& {
                                        return s.decomposition.remesh_edge_length;
                                      }),
                          [](const MethodSettings& s, const std::string&) {
                            return s.decomposition.kind != msd::DecompositionKind::Remeshed;
                          }));
    t.push_back(real_option("max_fold_ratio", {"multiscale"},
                            "automatic detail scale: the search stops where details come this close to folding, (0, 1]",
                            [](auto& s, const std::string&) -> auto& { return s.decomposition.low_pass.max_fold_ratio; }));
    t.push_back(real_option("plateau_growth", {"multiscale"},
                            "automatic detail scale: the detail layer ends where the rms height grows by less than "
                            "this factor per step (> 1)",
                            [](auto& s, const std::string&) -> auto& { return s.decomposition.low_pass.plateau_growth; }));
    t.push_back(real_option("max_scale_fraction", {"multiscale"},
                            "automatic detail scale: largest candidate, as a fraction of the diameter (> 0)",
                            [](auto& s, const std::string&) -> auto& {
                              return s.decomposition.low_pass.max_scale_fraction;
                            }));
    {
      Option o{"control", {"multiscale"},
               "base='subdivision': the Loop control mesh S refines (msdeform.scene(...).control); None: unset",
               [](MethodSettings& s, const std::string&, py::handle v) {
                 try {
                   s.decomposition.control = v.cast<std::shared_ptr<msd::ControlMesh>>();
                 } catch (const py::cast_error&) {
                   throw py::type_error("option control must be a msdeform.ControlMesh (from msdeform.scene()), got " +
                                        type_name(v));
                 }
               },
               [](const MethodSettings& s, const std::string&) -> py::object {
                 if (!s.decomposition.control) return py::none();
                 return py::cast(std::const_pointer_cast<msd::ControlMesh>(s.decomposition.control));
               }};
      o.none_is_unset = true;
      t.push_back(std::move(o));
    }
    t.push_back(int_option("normal_iterations", {"base-points"}, "Newton steps per vertex of the base-point search",
                           [](auto& s, const std::string&) -> auto& { return s.encoding.normal.max_iterations; }));
    t.push_back(real_option("normal_tolerance", {"base-points"},
                            "base-point search: converged when p - b is this parallel to the normal (relative to "
                            "the base's diagonal)",
                            [](auto& s, const std::string&) -> auto& { return s.encoding.normal.tolerance; }));
    t.push_back(int_option("max_walks", {"base-points"}, "base-point search: triangle walks per vertex at most",
                           [](auto& s, const std::string&) -> auto& { return s.encoding.normal.max_walks; }));
    t.push_back(choice_option("frame", {"multiscale-vectors"}, "where the displacement vectors live", kFrames,
                              [](auto& s, const std::string&) -> auto& { return s.encoding.vectors.frame; }));
    t.push_back(int_option("volume_iterations", {"multiscale-volumes"}, "relaxation sweeps per frame at most (>= 0)",
                           [](auto& s, const std::string&) -> auto& { return s.encoding.volumes.max_iterations; }));
    t.push_back(real_option("volume_tolerance", {"multiscale-volumes"}, "relative volume residual to stop at (>= 0)",
                            [](auto& s, const std::string&) -> auto& { return s.encoding.volumes.volume_tolerance; }));
    t.push_back(real_option("volume_regularization", {"multiscale-volumes"}, "Tikhonov weight of the heights (>= 0)",
                            [](auto& s, const std::string&) -> auto& { return s.encoding.volumes.regularization; }));
    t.push_back(real_option("focal_fraction", {"multiscale-volumes"},
                            "fold guard: heights stay within this fraction of the local focal distance (> 0)",
                            [](auto& s, const std::string&) -> auto& { return s.encoding.volumes.focal_fraction; }));
    t.push_back(real_option("max_height_change", {"multiscale-volumes"},
                            "trust bound on the height change, relative to the local height scale (> 0)",
                            [](auto& s, const std::string&) -> auto& { return s.encoding.volumes.max_height_change; }));
    t.push_back(real_option("relaxation", {"multiscale-volumes"}, "relaxation factor of the Jacobi sweeps, in (0, 2)",
                            [](auto& s, const std::string&) -> auto& { return s.encoding.volumes.relaxation; }));
    t.push_back(bool_option("warm_start", {"multiscale-volumes"}, "start each frame from the last frame's heights",
                            [](auto& s, const std::string&) -> auto& { return s.encoding.volumes.warm_start; }));
    t.push_back(bool_option("chebyshev", {"multiscale-volumes"}, "Chebyshev acceleration of the sweeps",
                            [](auto& s, const std::string&) -> auto& { return s.encoding.volumes.chebyshev; }));
    t.push_back(real_option("max_volume_change", {"multiscale-volumes"},
                            "volume window: cell volumes are kept within a factor 1 + this of the plain heights' (> 0)",
                            [](auto& s, const std::string&) -> auto& { return s.encoding.volumes.max_volume_change; }));
    return t;
  }();
  return table;
}

const Option* find_option(const std::string& name) {
  for (const Option& o : options_table())
    if (o.name == name) return &o;
  return nullptr;
}

// The option groups a method reads: its own, and for a multiscale method those of its base method.
std::vector<std::string> groups_of(const std::string& method, const std::string& base_method) {
  if (is_multiscale(method)) {
    std::vector<std::string> g = {"multiscale", method};
    if (method != "multiscale-vectors") g.push_back("base-points");
    if (!is_multiscale(base_method))
      for (const std::string& b : groups_of(base_method, "")) g.push_back(b);
    return g;
  }
  if (method == "cage-mvc") return {"cage"};
  if (method == "cage-harmonic") return {"cage", "cage-harmonic"};
  return {method};
}

// The first of the option's groups that the method reads, or null.
const std::string* matching_group(const Option& o, const std::vector<std::string>& groups) {
  for (const std::string& g : o.groups)
    if (std::find(groups.begin(), groups.end(), g) != groups.end()) return &g;
  return nullptr;
}

std::vector<std::string> option_names(const std::vector<std::string>& groups) {
  std::vector<std::string> out;
  for (const Option& o : options_table())
    if (matching_group(o, groups)) out.push_back(o.name);
  return out;
}

std::string takes(const std::string& method, const std::vector<std::string>& names) {
  return names.empty() ? method + " takes no options" : method + " takes: " + joined(names);
}

// ---------------------------------------------------------------------------------------------------
// The Deformer wrapper

class PyDeformer {
 public:
  PyDeformer(const std::string& method, const py::kwargs& options);

  std::string method;
  MethodSettings settings;
  std::vector<std::string> groups;
  std::vector<std::string> given;  // option names given, in order
  std::unique_ptr<msd::Deformer> deformer;
  std::atomic<bool> busy{false};
  long num_constrained = -1;  // of the prepared region
};

// One call at a time: the library's deformers are not thread-safe, and prepare() and deform() run with
// the GIL released, so a second Python thread could otherwise enter the same object.
class Busy {
 public:
  explicit Busy(PyDeformer& d) : flag_(d.busy) {
    if (flag_.exchange(true))
      throw std::runtime_error("Deformer('" + d.method + "') is in use by another thread: a Deformer is not thread-safe; "
                               "give each thread its own");
  }
  ~Busy() { flag_ = false; }
  Busy(const Busy&) = delete;
  Busy& operator=(const Busy&) = delete;

 private:
  std::atomic<bool>& flag_;
};

// The Deformer behind a Python object. Deformer.__new__(Deformer) alone makes an object whose C++ part
// was never constructed (pybind11 would hand out uninitialised memory): that is a TypeError here.
PyDeformer& live(py::handle obj) {
  auto* inst = reinterpret_cast<py::detail::instance*>(obj.ptr());
  py::detail::value_and_holder v_h = inst->get_value_and_holder(py::detail::get_type_info(typeid(PyDeformer)));
  if (!v_h.holder_constructed())
    throw py::type_error("this Deformer was made without __init__ (Deformer.__new__): create it as "
                         "msdeform.Deformer(name, **options)");
  return *static_cast<PyDeformer*>(v_h.value_ptr());
}

PyDeformer::PyDeformer(const std::string& name, const py::kwargs& options) : method(name) {
  const msd::Catalogue& catalogue = msd::builtin_methods();
  catalogue.find(method);  // InvalidInput (a ValueError) for an unknown name, listing the known ones
  std::string base_method = settings.base_method;
  if (is_multiscale(method) && options.contains("base_method")) {
    const py::object value = options["base_method"];
    find_option("base_method")->set(settings, "multiscale", value);
    base_method = settings.base_method;
  }
  groups = groups_of(method, base_method);
  const std::vector<std::string> valid = option_names(groups);
  std::vector<std::pair<std::string, std::string>> applied;  // (option, group)
  for (const auto& item : options) {
    const std::string key = py::str(item.first);
    const Option* o = find_option(key);
    if (!o) {
      std::string hint;
      py::list close = py::module_::import("difflib").attr("get_close_matches")(key, py::cast(valid), 1);
      if (py::len(close) > 0) hint = " (did you mean '" + close[0].cast<std::string>() + "'?)";
      throw py::type_error("Deformer('" + method + "'): unknown option '" + key + "'" + hint + ". " +
                           takes(method, valid));
    }
    const std::string* group = matching_group(*o, groups);
    if (!group) {
      std::vector<std::string> where;
      for (const std::string& g : o->groups) where.push_back(group_methods(g));
      const bool single = o->groups.front() != "multiscale" && o->groups.front().rfind("multiscale-", 0) != 0 &&
                          o->groups.front() != "base-points";
      throw py::type_error("Deformer('" + method + "'): option '" + key + "' configures " + joined(where, " and ") +
                           (single ? " (or a multiscale-* method with that base_method)" : "") + ", not " + method +
                           (is_multiscale(method) ? " with base_method='" + base_method + "'" : std::string()) + ". " +
                           takes(method, valid));
    }
    if (o->none_is_unset && item.second.is_none()) continue;  // as left out
    o->set(settings, *group, item.second);
    given.push_back(key);
    applied.emplace_back(key, *group);
  }
  const auto was_given = [&](const std::string& key, const char* group = nullptr) {
    for (const auto& [k, g] : applied)
      if (k == key && (!group || g == group)) return true;
    return false;
  };
  // Options that would be ignored are refused, as the command line does.
  if (was_given("remesh_edge_length")) {
    if (!was_given("base"))
      settings.decomposition.kind = msd::DecompositionKind::Remeshed;
    else if (settings.decomposition.kind != msd::DecompositionKind::Remeshed)
      throw py::value_error("Deformer('" + method + "'): remesh_edge_length applies to base='remeshed', not base='" +
                            msd::to_string(settings.decomposition.kind) + "'");
  }
  if (was_given("fairing") && settings.decomposition.kind != msd::DecompositionKind::Fairing)
    throw py::value_error("Deformer('" + method + "'): fairing applies to base='fairing', not base='" +
                          msd::to_string(settings.decomposition.kind) + "'");
  if (was_given("detail_scale") && !msd::reads_detail_scale(settings.decomposition.kind))
    throw py::value_error("Deformer('" + method + "'): detail_scale applies to the low-pass and remeshed bases, not "
                          "base='" + msd::to_string(settings.decomposition.kind) + "'");
  if (was_given("low_pass_solver") && !msd::reads_detail_scale(settings.decomposition.kind))
    throw py::value_error("Deformer('" + method +
                          "'): low_pass_solver applies to the low-pass and remeshed bases, "
                          "not base='" +
                          msd::to_string(settings.decomposition.kind) + "'");
  if (was_given("geodesic_time_factor") && settings.propagation.field != msd::PropagationField::Geodesic)
    throw py::value_error("Deformer('" + method + "'): geodesic_time_factor applies to field='geodesic', not field='" +
                          choice_label(settings.propagation.field, kFields).cast<std::string>() + "'");
  if (was_given("control") && settings.decomposition.kind != msd::DecompositionKind::Subdivision)
    throw py::value_error("Deformer('" + method + "'): control applies to base='subdivision', not base='" +
                          msd::to_string(settings.decomposition.kind) + "'");
  if (was_given("cage"))
    for (const char* k : {"margin", "subdivisions"})
      if (was_given(k, "cage"))
        throw py::value_error("Deformer('" + method + "'): " + k +
                              " shapes the generated cage; with cage=... the given cage is used as it is");
  // prepare() again on the same mesh (another region) computes the multi-scale base once.
  settings.decomposition.low_pass_cache = std::make_shared<msd::LowPassCache>();
  deformer = catalogue.make(method, settings);  // InvalidInput (a ValueError) for invalid values
}

py::object not_measured(double x) { return x < 0 ? py::object(py::none()) : py::object(py::float_(x)); }

const char* kDeformerDoc =
    R"doc(A deformation method of the catalogue (msdeform.methods()), prepared once per shape
and region and then driven frame by frame.

Deformer(name, **options): name is a catalogue name ('shell', 'arap', 'multiscale-normal', ...);
options set the method's settings, e.g. Deformer('arap', iterations=10, tolerance=0),
Deformer('multiscale-normal', base_method='arap', detail_scale=0.3). msdeform.method_options(name)
lists a method's options; .options gives the values in use. Raises ValueError (msdeform.InvalidInput)
for an unknown name or an invalid value, TypeError for an unknown option, an option of another method,
or a value of the wrong type (each message lists the method's options).

Arrays: V (#V, 3) float64 positions in mesh units, F (#F, 3) int32 triangles, labels (#V,) int32
selection codes (0 fixed, 1 free, 2+k handle k), transforms one affine 4x4 per handle (a 4x4 array
for one handle, a list of them, or an (H, 4, 4) array). Inputs are copied once into the library's
layout (V into column-major float64, F into row-major int32); results are returned without a copy:
the (#V, 3) float64 array wraps the library's buffer, which it keeps alive (its base object; Fortran
order), and is writable.

prepare() and the frames release the GIL. A Deformer is not thread-safe: a second thread calling it
while it works gets a RuntimeError. Warnings of prepare() and of each frame (folds, no convergence,
missed constraints) are issued as msdeform.MsdeformWarning and stay readable in prepare_warnings and
frame_report.warnings. A frame does not check the result's proportions (O(#F)): msdeform.shape_change()
does what the tool's report does (stretched edges, area and volume change, and its warning).)doc";

}  // namespace

void bind_deformer(py::module_& m) {
  py::class_<msd::DeformerTraits>(m, "DeformerTraits",
                                  "What a method declares about itself (Deformer.traits).")
      .def_property_readonly(
          "domain",
          [](const msd::DeformerTraits& t) {
            return t.domain == msd::DeformerDomain::Surface ? "surface" : "space";
          },
          "'surface': moves the mesh's own vertices through its triangles (prepare needs faces); 'space': "
          "deforms "
          "the space around the input (any points, evaluate())")
      .def_property_readonly(
          "solve",
          [](const msd::DeformerTraits& t) {
            return t.solve == msd::DeformerSolve::Linear ? "linear" : "iterative";
          },
          "'linear': a frame is a fixed linear map of the handle data; 'iterative': iterations from an "
          "initial guess")
      .def_readonly("vertex_targets", &msd::DeformerTraits::vertex_targets, "accepts deform_to(targets)")
      .def_readonly("initial_guess", &msd::DeformerTraits::initial_guess, "accepts set_initial_guess(X)")
      .def_readonly(
          "exact_constraints", &msd::DeformerTraits::exact_constraints,
          "fixed vertices stay and handle vertices reach T_k p exactly (to round-off); False: met in the "
          "least-squares sense, frame_report.constraint_error says how closely")
      .def_readonly("reproduces_rigid_motions", &msd::DeformerTraits::reproduces_rigid_motions,
                    "one rigid motion of every constrained vertex moves the whole shape by it")
      .def_readonly("cotan_laplacian", &msd::DeformerTraits::cotan_laplacian,
                    "a surface method that weighs the mesh with the cotan Laplacian (prepare warns where its "
                    "zero-area and needle triangles cut the surface)")
      .def("as_dict",
           [](const msd::DeformerTraits& t) {
             py::dict d;
             d["domain"] = t.domain == msd::DeformerDomain::Surface ? "surface" : "space";
             d["solve"] = t.solve == msd::DeformerSolve::Linear ? "linear" : "iterative";
             d["vertex_targets"] = t.vertex_targets;
             d["initial_guess"] = t.initial_guess;
             d["exact_constraints"] = t.exact_constraints;
             d["reproduces_rigid_motions"] = t.reproduces_rigid_motions;
             d["cotan_laplacian"] = t.cotan_laplacian;
             return d;
           })
      .def("__repr__", [](py::handle self) {
        py::dict d = self.attr("as_dict")();
        std::string s = "DeformerTraits(";
        bool first = true;
        for (const auto& item : d) {
          s += (first ? "" : ", ") + std::string(py::str(item.first)) + "=" + std::string(py::repr(item.second));
          first = false;
        }
        return s + ")";
      });

  py::class_<msd::FrameReport>(m, "FrameReport",
                               "What the last frame measured about its result (Deformer.frame_report; a copy).")
      .def_readonly("iterations", &msd::FrameReport::iterations, "iterations of an iterative frame (0 for linear ones)")
      .def_property_readonly(
          "residual", [](const msd::FrameReport& r) { return not_measured(r.residual); },
          "relative residual at exit of an iterative frame; None when not measured")
      .def_readonly("converged", &msd::FrameReport::converged,
                    "False when an iterative method stopped at its iteration limit")
      .def_property_readonly(
          "folded_faces",
          [](const msd::FrameReport& r) { return r.folded_faces < 0 ? py::object(py::none()) : py::object(py::int_(r.folded_faces)); },
          "multiscale methods: triangles whose normal turned against the deformed base's; None when not measured")
      .def_property_readonly(
          "constraint_error", [](const msd::FrameReport& r) { return not_measured(r.constraint_error); },
          "largest distance of a constrained vertex from its target (mesh units), measured by methods with "
          "inexact constraints; None when not measured")
      .def_property_readonly(
          "start",
          [](const msd::FrameReport& r) { return r.start ? py::object(py::str(r.start)) : py::object(py::none()); },
          "iterative methods that choose their start (arap): 'last result', 'initial guess' (set_initial_guess) or "
          "'cold start', whichever had the lower energy; None where the method has one start")
      .def_readonly("warnings", &msd::FrameReport::warnings, "what the user should know, each naming a remedy")
      .def("__repr__", [](const msd::FrameReport& r) {
        return "FrameReport(iterations=" + std::to_string(r.iterations) +
               ", residual=" + std::string(py::repr(not_measured(r.residual))) +
               ", converged=" + (r.converged ? "True" : "False") + ", folded_faces=" +
               (r.folded_faces < 0 ? std::string("None") : std::to_string(r.folded_faces)) +
               ", constraint_error=" + std::string(py::repr(not_measured(r.constraint_error))) +
               ", start=" + (r.start ? "'" + std::string(r.start) + "'" : std::string("None")) + ", warnings=" + std::to_string(r.warnings.size()) + ")";
      });

  py::class_<PyDeformer>(m, "Deformer", kDeformerDoc)
      .def(py::init([](const std::string& name, const py::kwargs& options) {
             return std::make_unique<PyDeformer>(name, options);
           }),
           py::arg("name"))
      .def(
          "prepare",
          [](py::handle obj, PositionsArg V, FacesArg F, LabelsArg labels) {
            PyDeformer& self = live(obj);
            const msd::Positions P = to_positions(V, "V");
            const msd::Faces T = to_faces(F, "F", static_cast<long>(P.rows()));
            std::vector<int> codes = to_codes(labels, "labels", static_cast<long>(P.rows()));
            const long constrained =
                static_cast<long>(std::count_if(codes.begin(), codes.end(), [](int c) { return c != msd::Region::kFree; }));
            const msd::Region region = msd::Region::from_codes(std::move(codes));
            {
              Busy busy(self);
              py::gil_scoped_release release;
              self.deformer->prepare(P, T, region);
            }
            self.num_constrained = constrained;
            warn(self.deformer->prepare_warnings());
          },
          py::arg("V"), py::arg("F"), py::arg("labels"),
          R"doc(Precomputes everything that depends on the rest shape and the region (decomposition,
factorisations, basis fields). V: (#V, 3) float64 rest positions (copied); F: (#F, 3) int32 triangles
(surface methods need them; space methods take None, an empty array or a soup); labels: (#V,) int32
selection codes, 0 fixed, 1 free, 2+k handle k, at least one handle (msdeform.region() builds them).
Releases the GIL. Issues prepare_warnings as msdeform.MsdeformWarning.

Raises TypeError / ValueError for a wrong dtype or shape, a label count other than #V, a negative label
or a face index out of range; msdeform.InvalidInput (ValueError) for an empty handle or unusable
data; msdeform.TopologyError (ValueError) for a non-manifold mesh or a free part that touches no
constrained vertex; msdeform.SolverError (RuntimeError) when a factorisation fails.)doc")
      .def(
          "deform",
          [](py::handle obj, TransformsArg transforms) {
            PyDeformer& self = live(obj);
            const std::vector<msd::Mat4> T = to_transforms(transforms);
            if (self.deformer->prepared() && static_cast<int>(T.size()) != self.deformer->num_handles())
              throw py::value_error(self.deformer->name() + ": " + std::to_string(T.size()) +
                                    " handle transforms given, the region has " +
                                    std::to_string(self.deformer->num_handles()) + " handle(s): one 4x4 per handle");
            msd::Positions out;
            {
              Busy busy(self);
              py::gil_scoped_release release;
              self.deformer->deform(T, out);
            }
            warn(self.deformer->frame_report().warnings);
            return out;
          },
          py::arg("transforms"),
          R"doc(One frame: transforms[k] (an affine 4x4, mesh units) moves handle k. Returns the deformed
positions, a new (#V, 3) float64 array over a buffer of its own (no copy; kept alive by its base
object; Fortran order). Releases the GIL;
issues the frame's warnings as msdeform.MsdeformWarning (also in frame_report.warnings).

Raises ValueError for a wrong shape or number of transforms, msdeform.InvalidInput (ValueError) for a
non-finite or non-affine matrix (last row not 0 0 0 1), msdeform.UsageError (RuntimeError) before
prepare(), msdeform.SolverError (RuntimeError) naming the vertex if the result is not finite.)doc")
      .def(
          "deform_to",
          [](py::handle obj, PositionsArg targets) {
            PyDeformer& self = live(obj);
            const bool check = self.deformer->prepared() && self.deformer->traits().vertex_targets;
            const msd::Positions X = to_positions(targets, "targets", check ? self.num_constrained : -1, "constrained vertex");
            msd::Positions out;
            {
              Busy busy(self);
              py::gil_scoped_release release;
              self.deformer->deform_to(X, out);
            }
            warn(self.deformer->frame_report().warnings);
            return out;
          },
          py::arg("targets"),
          R"doc(One frame with explicit targets: (#C, 3) float64 positions, one per constrained vertex in
ascending index order (msdeform.constrained_vertices(labels)), fixed ones usually at rest. Returns
(#V, 3) float64 as deform(). Only for methods with traits.vertex_targets (else
msdeform.UsageError, a RuntimeError). Raises ValueError for a row count other than #C.)doc")
      .def(
          "set_initial_guess",
          [](py::handle obj, PositionsArg X) {
            PyDeformer& self = live(obj);
            const msd::Positions G =
                to_positions(X, "X", self.deformer->prepared() ? self.deformer->num_vertices() : -1);
            Busy busy(self);
            self.deformer->set_initial_guess(G);
          },
          py::arg("X"),
          "Iterative methods with traits.initial_guess: the next frame starts from X ((#V, 3) float64, copied) "
          "instead of the last result; arap takes X only where its energy is below its cold start's "
          "(frame_report.start says which start it took). Raises msdeform.UsageError (RuntimeError) for other methods or before "
          "prepare(), ValueError for a wrong shape or a non-finite value.")
      .def(
          "reset",
          [](py::handle obj) {
            PyDeformer& self = live(obj);
            Busy busy(self);
            self.deformer->reset();
          },
          "Back to the rest pose: an iterative method's next frame starts from rest, a space method's map is the "
          "identity, the frame report is cleared; factorisations are kept.")
      .def(
          "evaluate",
          [](py::handle obj, PositionsArg points) {
            PyDeformer& self = live(obj);
            const msd::Positions X = to_positions(points, "points");
            msd::Positions out;
            {
              Busy busy(self);
              py::gil_scoped_release release;
              self.deformer->evaluate(X, out);
            }
            return out;
          },
          py::arg("points"),
          "Space methods: the map of the last frame (the identity before the first frame or after reset()) "
          "applied to any points ((N, 3) float64, copied); returns (N, 3) float64. The map is fitted to the "
          "prepared points: beyond them (outside the lattice's box or the cage, far from the RBF centres) it "
          "extrapolates, and moves points more the farther they lie. Raises msdeform.UsageError "
          "(RuntimeError) for a surface method or before prepare().")
      .def_property_readonly(
          "name", [](py::handle obj) { return live(obj).deformer->name(); }, "the method's catalogue name")
      .def_property_readonly(
          "traits", [](py::handle obj) { return live(obj).deformer->traits(); },
          "DeformerTraits: domain, solve, vertex_targets, initial_guess, exact_constraints, reproduces_rigid_motions")
      .def_property_readonly(
          "frame_report",
          [](py::handle obj) {
            PyDeformer& self = live(obj);
            Busy busy(self);
            return msd::FrameReport(self.deformer->frame_report());
          },
          "FrameReport of the last frame (a copy): iterations, residual, converged, folded_faces, "
          "constraint_error, warnings")
      .def_property_readonly(
          "prepare_warnings",
          [](py::handle obj) {
            PyDeformer& self = live(obj);
            Busy busy(self);
            return self.deformer->prepare_warnings();
          },
          "what prepare() found that the user should know, each naming a remedy (a list of str)")
      .def_property_readonly(
          "prepared", [](py::handle obj) { return live(obj).deformer->prepared(); }, "whether prepare() succeeded")
      .def_property_readonly(
          "num_vertices", [](py::handle obj) { return live(obj).deformer->num_vertices(); },
          "#V of the prepared shape (0 before prepare)")
      .def_property_readonly(
          "num_handles", [](py::handle obj) { return live(obj).deformer->num_handles(); },
          "handles of the prepared region (0 before prepare)")
      .def_property_readonly(
          "options",
          [](py::handle obj) {
            PyDeformer& self = live(obj);
            py::dict d;
            for (const Option& o : options_table())
              if (const std::string* g = matching_group(o, self.groups)) d[py::str(o.name)] = o.get(self.settings, *g);
            return py::module_::import("msdeform._helpers").attr("Options")(d);
          },
          "the values of every option this method reads (a dict whose items cannot be changed; defaults "
          "where none was given): options are set by Deformer(name, **options), an assignment here raises "
          "TypeError")
      .def_property_readonly(
          "base",
          [](py::handle obj) -> py::object {
            PyDeformer& self = live(obj);
            const auto* ms = dynamic_cast<const msd::MultiscaleDeformer*>(self.deformer.get());
            if (!ms || !self.deformer->prepared()) return py::none();
            Busy busy(self);
            return py::make_tuple(msd::Positions(ms->base()), msd::Faces(ms->base_faces()));
          },
          "multiscale methods after prepare(): the smooth base (B (#Vb, 3) float64, FB (#Fb, 3) int32), copies; "
          "else None")
      .def_property_readonly(
          "detail_scale",
          [](py::handle obj) -> py::object {
            PyDeformer& self = live(obj);
            const auto* ms = dynamic_cast<const msd::MultiscaleDeformer*>(self.deformer.get());
            if (!ms || !self.deformer->prepared()) return py::none();
            return py::float_(ms->decomposition_report().low_pass.detail_scale);
          },
          "multiscale methods after prepare(): the detail scale used (mesh units; 0: no detail layer, B = S); "
          "else None")
      .def("__repr__", [](py::handle obj) {
        PyDeformer& self = live(obj);
        std::string s = "Deformer('" + self.method + "'";
        for (const std::string& k : self.given)
          if (const Option* o = find_option(k))
            if (const std::string* g = matching_group(*o, self.groups)) {
              if (k == "cage")  // arrays: their size, not their values
                s += ", cage=<" + std::to_string(self.settings.cage.cage_P.rows()) + " vertices, " +
                     std::to_string(self.settings.cage.cage_F.rows()) + " faces>";
              else
                s += ", " + k + "=" + std::string(py::repr(o->get(self.settings, *g)));
            }
        s += ")";
        if (self.deformer->prepared())
          s += " prepared on " + std::to_string(self.deformer->num_vertices()) + " vertices, " +
               std::to_string(self.deformer->num_handles()) + " handle(s)";
        return "<" + s + ">";
      });

  m.def(
      "_catalogue",
      [] {
        py::list out;
        for (const msd::MethodEntry& e : msd::builtin_methods().entries())
          out.append(py::make_tuple(e.name, e.section, e.summary));
        return out;
      },
      "The catalogue's rows as (name, section, summary) tuples (msdeform.methods() wraps them).");
  m.def(
      "method_options",
      [](const std::string& name, const std::string& base_method) {
        msd::builtin_methods().find(name);
        if (!base_method.empty() && (is_multiscale(base_method) || !is_multiscale(name)))
          throw py::value_error("base_method applies to the multiscale-* methods and must be a single-scale method");
        const std::vector<std::string> groups = groups_of(name, base_method.empty() ? "shell" : base_method);
        const MethodSettings defaults;
        py::dict d;
        for (const Option& o : options_table())
          if (const std::string* g = matching_group(o, groups))
            d[py::str(o.name)] = o.help + " [default " + std::string(py::repr(o.get(defaults, *g))) + "]";
        return d;
      },
      py::arg("name"), py::arg("base_method") = "",
      "The keyword options Deformer(name, ...) accepts: a dict option -> description with its default. For a "
      "multiscale method, those of its base_method (default 'shell') are included. Raises ValueError for an "
      "unknown method.");
}

}  // namespace msdpy
