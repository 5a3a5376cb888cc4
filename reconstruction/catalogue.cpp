#include "msdeform/reconstruction/catalogue.h"

#include <tuple>

#include "msdeform/core/errors.h"

namespace msd {

void Catalogue::add(MethodEntry entry) {
  if (entry.name.empty()) throw InvalidInput("catalogue: a method needs a name");
  if (!entry.make) throw InvalidInput("catalogue: method '" + entry.name + "' has no factory");
  for (const auto& e : entries_)
    if (e.name == entry.name) throw InvalidInput("catalogue: method '" + entry.name + "' is already listed");
  entries_.push_back(std::move(entry));
}

std::vector<std::string> Catalogue::names() const {
  std::vector<std::string> out;
  for (const auto& e : entries_) out.push_back(e.name);
  return out;
}

const MethodEntry& Catalogue::find(const std::string& name) const {
  for (const auto& e : entries_)
    if (e.name == name) return e;
  std::string known;
  for (const auto& e : entries_) known += (known.empty() ? "" : ", ") + e.name;
  throw InvalidInput("unknown method '" + name + "' (known: " + known + ")");
}

std::unique_ptr<Deformer> Catalogue::make(const std::string& name, const MethodSettings& settings) const {
  return find(name).make(settings, *this);
}

namespace {

Catalogue make_builtin() {
  Catalogue c;
  c.add({"shell", "9.2", "linearised thin shell −ks·Δd + kb·Δ²d = 0, factored once, precomputed basis per handle",
         [](const MethodSettings& s, const Catalogue&) { return std::make_unique<ShellDeformer>(s.shell); }});
  c.add({"propagate", "9.1", "transformation propagation: a blend field damps each handle's transform",
         [](const MethodSettings& s, const Catalogue&) {
           return std::make_unique<TransformationPropagation>(s.propagation);
         }});
  c.add({"gradient", "9.4.1", "gradient-based editing: harmonic propagation of the handle gradients, Poisson solve (9.10)",
         [](const MethodSettings&, const Catalogue&) { return std::make_unique<GradientEditing>(); }});
  c.add({"laplacian", "9.4.2", "Laplacian editing: implicit linearised similarities per vertex (9.11), factored once",
         [](const MethodSettings& s, const Catalogue&) { return std::make_unique<LaplacianEditing>(s.laplacian); }});
  c.add({"arap", "9.8", "as-rigid-as-possible (Sorkine & Alexa 2007): local rotations and a global solve factored once, warm-started",
         [](const MethodSettings& s, const Catalogue&) { return std::make_unique<ArapDeformer>(s.arap); }});
  c.add({"primo", "9.8",
         "PriMo (Botsch et al. 2006): a rigid prism per face, coupled across shared edges; damped Newton "
         "with a line search on the prisms' motions",
         [](const MethodSettings& s, const Catalogue&) { return std::make_unique<PrimoDeformer>(s.primo); }});
  c.add({"lattice", "9.5.1", "lattice free-form deformation: cubic B-spline lattice, handles by the least-norm solve (9.13)",
         [](const MethodSettings& s, const Catalogue&) { return std::make_unique<LatticeDeformer>(s.lattice); }});
  for (const auto& [name, kind, what] :
       {std::tuple{"cage-mvc", CageCoordinates::MeanValue, "mean value coordinates (Ju et al. 2005)"},
        std::tuple{"cage-harmonic", CageCoordinates::Harmonic, "harmonic coordinates (Joshi et al. 2007) on a grid"}})
    c.add({name, "9.5.2",
           std::string("cage free-form deformation: ") + what +
               " of a closed cage (given, or an offset 26-DOP), handles by the least-norm solve (9.13)",
           [kind = kind](const MethodSettings& s, const Catalogue&) {
             CageOptions o = s.cage;
             o.coordinates = kind;
             return std::make_unique<CageDeformer>(o);
           }});
  c.add({"rbf", "9.6", "triharmonic radial basis functions r³ with a linear polynomial, precomputed affine basis per handle",
         [](const MethodSettings& s, const Catalogue&) { return std::make_unique<RbfDeformer>(s.rbf); }});
  for (const std::string& encoding : encoding_names())
    c.add({"multiscale-" + encoding, "9.3",
           "multi-scale: decompose S = B ⊕ D, deform B with the base method, add the " + encoding + " details back",
           [encoding](const MethodSettings& s, const Catalogue& catalogue) -> std::unique_ptr<Deformer> {
             if (is_multiscale(s.base_method))
               throw InvalidInput("multiscale-" + encoding + ": the base method '" + s.base_method +
                                  "' is itself multi-scale; give a single-scale method (shell, propagate, ...)");
             MultiscaleOptions o;
             o.decomposition = s.decomposition;
             o.encoding = s.encoding;
             o.encoding.kind = encoding_kind(encoding);
             return std::make_unique<MultiscaleDeformer>(o, catalogue.make(s.base_method, s),
                                                         "multiscale-" + encoding);
           }});
  return c;
}

}  // namespace

const Catalogue& builtin_methods() {
  static const Catalogue catalogue = make_builtin();
  return catalogue;
}

}  // namespace msd
