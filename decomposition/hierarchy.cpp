#include "msdeform/decomposition/hierarchy.h"

#include <cmath>
#include <string>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"

namespace msd {
namespace {

std::vector<Positions> smoothing_levels(const Positions& P, const Faces& F, const HierarchyOptions& options) {
  if (options.levels < 1)
    throw InvalidInput("build_hierarchy: " + std::to_string(options.levels) +
                       " levels requested (at least 1)");
  if (!(options.time_step_growth > 0) || !std::isfinite(options.time_step_growth))
    throw InvalidInput("build_hierarchy: time step growth must be positive and finite (got " +
                       std::to_string(options.time_step_growth) + ")");
  std::vector<Positions> levels{P};
  SmoothingOptions step = options.smoothing;
  for (int i = 1; i <= options.levels; ++i) {
    levels.push_back(implicit_smoothing(levels.back(), F, step));
    step.time_step *= options.time_step_growth;
  }
  return levels;
}

}  // namespace

DecompositionHierarchy::DecompositionHierarchy(std::vector<Positions> levels, Faces faces)
    : levels_(std::move(levels)), faces_(std::move(faces)) {
  if (levels_.empty()) throw InvalidInput("DecompositionHierarchy: no level given");
  for (size_t i = 1; i < levels_.size(); ++i)
    if (levels_[i].rows() != levels_[0].rows())
      throw InvalidInput("DecompositionHierarchy: level " + std::to_string(i) + " has " +
                         std::to_string(levels_[i].rows()) + " vertices, level 0 has " +
                         std::to_string(levels_[0].rows()));
}

const Positions& DecompositionHierarchy::level(int i) const {
  if (i < 0 || i >= num_levels())
    throw UsageError("DecompositionHierarchy::level: index " + std::to_string(i) + " outside [0, " +
                     std::to_string(num_levels()) + ")");
  return levels_[i];
}

Positions DecompositionHierarchy::difference(int i) const {
  if (i < 1 || i >= num_levels())
    throw UsageError("DecompositionHierarchy::difference: index " + std::to_string(i) + " outside [1, " +
                     std::to_string(num_levels()) + ")");
  return levels_[i - 1] - levels_[i];
}

void DecompositionHierarchy::reconstruct_global(const Positions& base_deformed, Positions& out) const {
  if (levels_.empty()) throw UsageError("DecompositionHierarchy::reconstruct_global: empty hierarchy");
  if (base_deformed.rows() != levels_[0].rows())
    throw UsageError("DecompositionHierarchy::reconstruct_global: deformed base has " +
                     std::to_string(base_deformed.rows()) + " rows, the hierarchy " +
                     std::to_string(levels_[0].rows()));
  if (out.rows() != base_deformed.rows()) out.resize(base_deformed.rows(), 3);
  // B' ⊕ D_k ⊕ … ⊕ D_1, applied coarse to fine as reconstruction/ does with real encodings.
  if (&out != &base_deformed) out = base_deformed;
  for (int i = num_levels() - 1; i >= 1; --i) out += levels_[i - 1] - levels_[i];
}

DecompositionHierarchy build_hierarchy(const Positions& P, const Faces& F, const Region& region,
                                       const HierarchyOptions& options) {
  check_mesh_arrays(P, F, "build_hierarchy");
  if (options.method == HierarchyMethod::Smoothing) return {smoothing_levels(P, F, options), F};
  if (options.orders.empty()) throw InvalidInput("build_hierarchy: no fairing order given");
  if (region.num_vertices() != P.rows())
    throw InvalidInput("build_hierarchy: the region has " + std::to_string(region.num_vertices()) +
                       " vertex labels but the mesh has " + std::to_string(P.rows()) + " vertices");
  for (size_t i = 1; i < options.orders.size(); ++i)
    if (static_cast<int>(options.orders[i]) < static_cast<int>(options.orders[i - 1]))
      throw InvalidInput("build_hierarchy: fairing orders must not decrease (level " + std::to_string(i + 1) +
                         " has " + to_string(options.orders[i]) + " after " +
                         to_string(options.orders[i - 1]) + ")");
  // One boundary band for all levels, wide enough for the highest order.
  Region constraints = region;
  if (options.fix_mesh_boundary) {
    std::vector<int> band;
    for (int v : boundary_band(F, static_cast<int>(P.rows()), static_cast<int>(options.orders.back())))
      if (region.is_free(v)) band.push_back(v);
    constraints.set_fixed(band);
  }
  std::vector<Positions> levels{P};
  for (size_t i = 0; i < options.orders.size(); ++i) {
    if (i > 0 && options.orders[i] == options.orders[i - 1]) {
      levels.push_back(levels.back());  // the same order faires to the same surface
      continue;
    }
    FairingOptions fo;
    fo.order = options.orders[i];
    fo.weights = options.fairing_weights;
    fo.fix_mesh_boundary = false;  // the band is in `constraints`
    // Fairing reads only the constrained rows, and those equal S's on every level: fairing S_{i-1} is
    // fairing S.
    levels.push_back(fair_region(P, F, constraints, fo));
  }
  return {std::move(levels), F};
}

DecompositionHierarchy build_hierarchy(const Positions& P, const Faces& F, const HierarchyOptions& options) {
  if (options.method != HierarchyMethod::Smoothing)
    throw UsageError("build_hierarchy: the fairing hierarchy needs a region; call build_hierarchy(P, F, region, options)");
  return build_hierarchy(P, F, Region(static_cast<int>(P.rows())), options);
}

}  // namespace msd
