#include "msdeform/decomposition/fairing.h"

#include <algorithm>
#include <string>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"

namespace msd {
namespace {

bool valid_order(FairingOrder order) {
  const int k = static_cast<int>(order);
  return k >= 1 && k <= 3;
}

// Region checks with the caller's name in front, and the one case Region::validate words generically
// (no constrained vertex at all) spelled out for fairing.
void check_region(const Faces& F, int num_vertices, const Region& region, const char* who) {
  if (region.num_vertices() == num_vertices && region.num_vertices() > 0 &&
      region.constrained_vertices().empty())
    throw InvalidInput(
        std::string(who) +
        ": the region has no fixed or handle vertex; fairing keeps those vertices and computes the "
        "free ones from them, so mark at least the border of the region to fair as fixed");
  try {
    region.validate(num_vertices, &F);
  } catch (const TopologyError& e) {
    throw TopologyError(std::string(who) + ": " + e.what());
  } catch (const InvalidInput& e) {
    throw InvalidInput(std::string(who) + ": " + e.what());
  }
}

}  // namespace

const char* to_string(FairingOrder order) {
  switch (order) {
    case FairingOrder::Membrane:
      return "membrane";
    case FairingOrder::ThinPlate:
      return "thin plate";
    case FairingOrder::MinimumVariation:
      return "minimum variation";
  }
  return "invalid";
}

RegionFairing::RegionFairing(const Positions& P, const Faces& F, const Region& region, const FairingOptions& options) {
  prepare(P, F, region, options);
}

void RegionFairing::prepare(const Positions& P, const Faces& F, const Region& region, const FairingOptions& options) {
  static const char* who = "fair_region";
  prepared_ = false;
  if (!valid_order(options.order))
    throw InvalidInput(std::string(who) + ": fairing order " +
                       std::to_string(static_cast<int>(options.order)) +
                       " (expected 1 membrane, 2 thin plate or 3 minimum variation)");
  check_mesh_arrays(P, F, who);
  check_region(F, static_cast<int>(P.rows()), region, who);
  options_ = options;
  rest_ = P;
  std::vector<int> known = region.constrained_vertices();
  std::vector<char> is_known(rest_.rows(), 0);
  for (int v : known) is_known[v] = 1;
  if (options.fix_mesh_boundary) {
    for (int v : boundary_band(F, static_cast<int>(P.rows()), static_cast<int>(options.order)))
      if (!is_known[v]) is_known[v] = 1, known.push_back(v);
    std::sort(known.begin(), known.end());
  }
  const LaplaceOperator op = laplace_operator(rest_, F, options.weights);
  for (int v : region.free_vertices())
    if (!is_known[v] && !(op.mass[v] > 0))
      throw InvalidInput(
          std::string(who) + ": free vertex " + std::to_string(v) +
          " has no incident face of non-zero area, so Δ is undefined there; remove it or mark it fixed");
  Q_ = polyharmonic_matrix(op, static_cast<int>(options.order));
  try {
    system_.prepare(Q_, known);
  } catch (const SolverError& e) {
    if (e.index() < 0) throw SolverError(std::string(who) + ": " + e.what());
    throw SolverError(std::string(who) + ": the " + to_string(options.order) +
                          " system is singular at free vertex " + std::to_string(e.index()) +
                          " (degenerate faces around it, it is not coupled to any fixed or handle vertex, or the "
                          "system is singular in floating point: a higher order over a free region many rings wide "
                          "is; a lower order or the low-pass base avoids it)",
                      e.index());
  }
  known_.resize(static_cast<Eigen::Index>(known.size()), 3);
  prepared_ = true;
}

void RegionFairing::fair(const Positions& P, Positions& out) const {
  if (!prepared_) throw UsageError("RegionFairing::fair: call prepare() first");
  if (P.rows() != rest_.rows())
    throw UsageError("RegionFairing::fair: positions have " + std::to_string(P.rows()) +
                     " rows, the mesh has " + std::to_string(rest_.rows()) + " vertices");
  const std::vector<int>& known = system_.known();
  for (size_t c = 0; c < known.size(); ++c) {
    known_.row(c) = P.row(known[c]);
    if (!known_.row(c).allFinite())
      throw InvalidInput("RegionFairing::fair: constrained vertex " + std::to_string(known[c]) +
                         " has a non-finite position");
  }
  solve_known(out);
}

Positions RegionFairing::fair(const Positions& P) const {
  Positions out;
  fair(P, out);
  return out;
}

void RegionFairing::fair_constrained(const Positions& constrained, Positions& out) const {
  if (!prepared_) throw UsageError("RegionFairing::fair_constrained: call prepare() first");
  if (constrained.rows() != known_.rows())
    throw UsageError("RegionFairing::fair_constrained: " + std::to_string(constrained.rows()) + " rows for " +
                     std::to_string(known_.rows()) + " constrained vertices");
  for (Eigen::Index c = 0; c < constrained.rows(); ++c)
    if (!constrained.row(c).allFinite())
      throw InvalidInput("RegionFairing::fair_constrained: row " + std::to_string(c) + " (vertex " +
                         std::to_string(system_.known()[c]) + ") is not finite");
  known_ = constrained;
  solve_known(out);
}

void RegionFairing::solve_known(Positions& out) const {
  system_.solve(known_, x_);  // Q_ff b_f = −Q_fc b_c: Δᵏ b = 0 on the free rows
  if (!x_.allFinite())
    throw SolverError("fair_region: the faired positions are not finite (ill-conditioned system)");
  if (out.rows() != x_.rows()) out.resize(x_.rows(), 3);
  out = x_;
}

Positions fair_region(const Positions& P, const Faces& F, const Region& region, const FairingOptions& options) {
  return RegionFairing(P, F, region, options).base();
}

}  // namespace msd
