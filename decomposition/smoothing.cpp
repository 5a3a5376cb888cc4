#include "msdeform/decomposition/smoothing.h"

#include <cmath>
#include <string>
#include <vector>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/solver.h"

namespace msd {
namespace {

constexpr const char* kWho = "implicit_smoothing";

Vec3 weighted_centroid(const Positions& P, const Eigen::VectorXd& mass) {
  return (P.transpose() * mass) / mass.sum();
}

double measure(const Positions& P, const Faces& F, SmoothingRescale rescale) {
  return rescale == SmoothingRescale::Area ? face_areas(P, F).sum() : signed_volume(P, F);
}

void prepare_step(ConstrainedQuadratic& system, const LaplaceOperator& op, double t,
                  const std::vector<int>& known) {
  const SparseMatrix A = SparseMatrix(op.mass.asDiagonal()) - t * op.W;  // M − t·W
  try {
    system.prepare(A, known);
  } catch (const SolverError& e) {
    if (e.index() < 0) throw SolverError(std::string(kWho) + ": " + e.what());
    throw SolverError(std::string(kWho) + ": the step matrix M − tW is singular at vertex " +
                          std::to_string(e.index()) + " (degenerate faces around it)",
                      e.index());
  }
}

}  // namespace

double smoothing_time(const Positions& P, const Faces& F, const SmoothingOptions& options) {
  switch (options.unit) {
    case SmoothingTimeUnit::MeanEdgeLengthSquared: {
      const double h = mean_edge_length(P, F);
      return options.time_step * h * h;
    }
    case SmoothingTimeUnit::BoundingBoxDiagonalSquared: {
      const double d = bounding_box_diagonal(P);
      return options.time_step * d * d;
    }
    case SmoothingTimeUnit::Absolute:
      return options.time_step;
  }
  throw InvalidInput(std::string(kWho) + ": unknown time unit");
}

Positions implicit_smoothing(const Positions& P, const Faces& F, const SmoothingOptions& options) {
  check_mesh_arrays(P, F, kWho);
  if (!(options.time_step > 0) || !std::isfinite(options.time_step))
    throw InvalidInput(std::string(kWho) + ": time step must be positive and finite (got " +
                       std::to_string(options.time_step) + ")");
  if (options.iterations < 0)
    throw InvalidInput(std::string(kWho) + ": " + std::to_string(options.iterations) +
                       " iterations requested");
  const int nv = static_cast<int>(P.rows());
  const std::vector<int> boundary = boundary_vertices(F, nv);
  if (options.rescale == SmoothingRescale::Volume && !boundary.empty())
    throw InvalidInput(std::string(kWho) + ": volume rescaling needs a closed mesh, but vertex " +
                       std::to_string(boundary.front()) + " is on a boundary; use Area or None");
  if (options.rescale != SmoothingRescale::None && options.fix_boundary && !boundary.empty())
    throw InvalidInput(std::string(kWho) + ": rescaling would move the fixed boundary (vertex " +
                       std::to_string(boundary.front()) + "); set fix_boundary = false or rescale = None");
  if (options.iterations == 0 || nv == 0) return P;

  const std::vector<int> known = options.fix_boundary ? boundary : std::vector<int>{};
  std::vector<char> is_known(nv, 0);
  for (int v : known) is_known[v] = 1;
  const double t = smoothing_time(P, F, options);
  const LaplaceOperator input_op = laplace_operator(P, F, options.weights);
  auto check_mass = [&](const LaplaceOperator& op) {
    for (int v = 0; v < nv; ++v)
      if (!is_known[v] && !(op.mass[v] > 0))
        throw InvalidInput(std::string(kWho) + ": vertex " + std::to_string(v) +
                           " has no incident face of non-zero area (isolated or degenerate); remove it");
  };
  check_mass(input_op);
  const double input_measure = options.rescale == SmoothingRescale::None ? 0 : measure(P, F, options.rescale);
  const Vec3 input_centroid = weighted_centroid(P, input_op.mass);

  ConstrainedQuadratic system;
  prepare_step(system, input_op, t, known);
  LaplaceOperator op;  // the current operator when it is updated per step
  const Eigen::VectorXd* mass = &input_op.mass;
  Eigen::MatrixXd current = P, next, rhs(nv, 3), known_values(static_cast<Eigen::Index>(known.size()), 3);
  for (size_t c = 0; c < known.size(); ++c) known_values.row(c) = P.row(known[c]);
  for (int it = 0; it < options.iterations; ++it) {
    if (options.update_operator && it > 0) {
      op = laplace_operator(current, F, options.weights);
      check_mass(op);
      prepare_step(system, op, t, known);
      mass = &op.mass;
    }
    // ConstrainedQuadratic minimises ½xᵀAx + xᵀf, i.e. solves A x = −f: f = −M p_n.
    rhs.noalias() = -(mass->asDiagonal() * current);
    system.solve(known_values, next, &rhs);
    current.swap(next);
  }
  if (!current.allFinite()) throw SolverError(std::string(kWho) + ": smoothed positions are not finite");
  Positions out = current;
  if (options.rescale != SmoothingRescale::None) {
    const double now = measure(out, F, options.rescale);
    if (!(now > 0) || !(input_measure > 0))
      throw InvalidInput(
          std::string(kWho) + ": cannot rescale, the " +
          (options.rescale == SmoothingRescale::Area ? "area" : "enclosed volume (check the orientation)") +
          " is not positive");
    const double ratio = input_measure / now;
    const double s = options.rescale == SmoothingRescale::Area ? std::sqrt(ratio) : std::cbrt(ratio);
    const Vec3 c = weighted_centroid(out, input_op.mass);
    out = ((out.rowwise() - c.transpose()) * s).rowwise() + input_centroid.transpose();
  }
  return out;
}

}  // namespace msd
