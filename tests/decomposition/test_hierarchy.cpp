#include <catch2/catch.hpp>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/scenes.h"
#include "msdeform/decomposition/hierarchy.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

double energy(const SparseMatrix& Q, const Positions& P) { return (P.transpose() * (Q * P)).trace(); }

// Σ mᵢ |Δpᵢ|² over interior vertices, Δ of the input surface (the outline's own curvature left out).
double interior_roughness(const LaplaceOperator& op, const std::vector<int>& boundary, const Positions& P) {
  Positions lp = op.mass.cwiseInverse().asDiagonal() * (op.W * P);
  for (int v : boundary) lp.row(v).setZero();
  return (op.mass.asDiagonal() * lp.rowwise().squaredNorm()).sum();
}

}  // namespace

TEST_CASE("smoothing hierarchy: levels get progressively smoother and rebuild S",
          "[decomposition][hierarchy]") {
  SceneOptions o;
  o.resolution = 3000;
  const Scene s = make_surface(SceneShape::Plane, o);
  HierarchyOptions options;  // smoothing, 3 steps
  const DecompositionHierarchy h = build_hierarchy(s.P, s.F, s.region, options);
  REQUIRE(h.num_levels() == 4);
  CHECK(h.level(0) == s.P);
  CHECK(&h.surface() == &h.level(0));
  CHECK(&h.base() == &h.level(3));
  CHECK(h.faces() == s.F);
  CHECK(h.num_vertices() == s.P.rows());
  // Roughness with the operator of S, and the largest bump left.
  const LaplaceOperator op = laplace_operator(s.P, s.F, LaplacianWeights::Cotan);
  const std::vector<int> boundary = boundary_vertices(s.F, static_cast<int>(s.P.rows()));
  double previous_energy = interior_roughness(op, boundary, h.level(0)),
         previous_height = h.level(0).col(2).cwiseAbs().maxCoeff();
  for (int i = 1; i < h.num_levels(); ++i) {
    const double e = interior_roughness(op, boundary, h.level(i)),
                 height = h.level(i).col(2).cwiseAbs().maxCoeff();
    INFO("level " << i << ": roughness " << e << ", max |z| " << height);
    CHECK(e < (i == 1 ? 0.05 : 1.0) * previous_energy);
    CHECK(height < previous_height);
    previous_energy = e;
    previous_height = height;
  }
  // Global differences telescope back to S.
  Positions rebuilt;
  h.reconstruct_global(h.base(), rebuilt);
  CHECK((rebuilt - s.P).cwiseAbs().maxCoeff() <= 1e-12 * s.P.cwiseAbs().maxCoeff());
  Positions sum = h.base();
  for (int i = 1; i < h.num_levels(); ++i) sum += h.difference(i);
  CHECK((sum - s.P).cwiseAbs().maxCoeff() <= 1e-12);
  // A translated base carries the details along.
  const Positions moved = h.base().rowwise() + Eigen::RowVector3d(0, 0, 1);
  h.reconstruct_global(moved, rebuilt);
  CHECK((rebuilt - (s.P.rowwise() + Eigen::RowVector3d(0, 0, 1))).cwiseAbs().maxCoeff() <= 1e-12);
  // The array overload builds the same levels.
  const DecompositionHierarchy h2 = build_hierarchy(s.P, s.F, options);
  CHECK(h2.base() == h.base());
}

TEST_CASE("fairing hierarchy: growing order, each level the smoothest in its own energy",
          "[decomposition][hierarchy]") {
  SceneOptions o;
  o.resolution = 2000;
  Scene s = make_scene("lift", o);
  for (int v : s.region.handle_vertices(0))
    s.P.row(v) = transform_point(s.transforms[0], s.P.row(v).transpose()).transpose();
  HierarchyOptions options;
  options.method = HierarchyMethod::Fairing;
  const DecompositionHierarchy h = build_hierarchy(s.P, s.F, s.region, options);
  REQUIRE(h.num_levels() == 4);
  CHECK((h.base() - fair_region(s.P, s.F, s.region,
                                [] {
                                  FairingOptions f;
                                  f.order = FairingOrder::MinimumVariation;
                                  return f;
                                }()))
            .cwiseAbs()
            .maxCoeff() == 0.0);
  const LaplaceOperator op = laplace_operator(s.P, s.F, LaplacianWeights::Cotan);
  // All levels keep the same vertices: the region's constrained ones and the 3-ring band at the outline.
  Region shared = s.region;
  std::vector<int> band;
  for (int v : boundary_band(s.F, static_cast<int>(s.P.rows()), 3))
    if (s.region.is_free(v)) band.push_back(v);
  shared.set_fixed(band);
  for (int i = 1; i < h.num_levels(); ++i) {
    FairingOptions fo;
    fo.order = options.orders[i - 1];
    fo.fix_mesh_boundary = false;
    CHECK((h.level(i) - fair_region(s.P, s.F, shared, fo)).cwiseAbs().maxCoeff() == 0.0);
    for (int v : shared.constrained_vertices()) REQUIRE(h.level(i).row(v) == s.P.row(v));
    const SparseMatrix Q = polyharmonic_matrix(op, static_cast<int>(fo.order));
    for (int j = 0; j < i; ++j) {
      INFO("level " << i << " vs level " << j);
      CHECK(energy(Q, h.level(i)) <= energy(Q, h.level(j)) * (1 + 1e-9));
    }
  }
  // A repeated order adds an identical level; a decreasing one is refused.
  options.orders = {FairingOrder::ThinPlate, FairingOrder::ThinPlate};
  const DecompositionHierarchy same = build_hierarchy(s.P, s.F, s.region, options);
  CHECK(same.level(1) == same.level(2));
  options.orders = {FairingOrder::ThinPlate, FairingOrder::Membrane};
  CHECK_THROWS_WITH(build_hierarchy(s.P, s.F, s.region, options), Contains("must not decrease"));
  options.orders.clear();
  CHECK_THROWS_AS(build_hierarchy(s.P, s.F, s.region, options), InvalidInput);
}

TEST_CASE("hierarchy reports bad input", "[decomposition][hierarchy][bad-input]") {
  SceneOptions o;
  o.resolution = 300;
  const Scene s = make_surface(SceneShape::Plane, o);
  HierarchyOptions options;
  options.levels = 0;
  CHECK_THROWS_WITH(build_hierarchy(s.P, s.F, options), Contains("0 levels"));
  options.levels = 2;
  options.time_step_growth = -1;
  CHECK_THROWS_WITH(build_hierarchy(s.P, s.F, options), Contains("growth"));
  options.method = HierarchyMethod::Fairing;
  CHECK_THROWS_AS(build_hierarchy(s.P, s.F, options), UsageError);
  const DecompositionHierarchy h = build_hierarchy(s.P, s.F, HierarchyOptions{});
  CHECK_THROWS_AS(h.level(4), UsageError);
  CHECK_THROWS_AS(h.level(-1), UsageError);
  CHECK_THROWS_AS(h.difference(0), UsageError);
  Positions out;
  CHECK_THROWS_AS(h.reconstruct_global(Positions(3, 3), out), UsageError);
  CHECK_THROWS_AS(DecompositionHierarchy({}, s.F), InvalidInput);
  CHECK_THROWS_AS(DecompositionHierarchy({s.P, Positions(2, 3)}, s.F), InvalidInput);
  // Fairing with a region of the wrong size.
  options = HierarchyOptions{};
  options.method = HierarchyMethod::Fairing;
  CHECK_THROWS_WITH(build_hierarchy(s.P, s.F, Region(3), options), Contains("vertex labels"));
}
