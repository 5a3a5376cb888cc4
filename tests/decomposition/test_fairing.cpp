#include <catch2/catch.hpp>

#include <cmath>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/scenes.h"
#include "msdeform/decomposition/fairing.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

// The lift scene with its handle already moved: a bumpy plane whose handle strip sits 0.3 higher, so the
// faired free region is a non-trivial ramp.
Scene lifted_plane(int resolution) {
  SceneOptions o;
  o.resolution = resolution;
  Scene s = make_scene("lift", o);
  for (int v : s.region.handle_vertices(0))
    s.P.row(v) = transform_point(s.transforms[0], s.P.row(v).transpose()).transpose();
  return s;
}

// Δᵏ = (M⁻¹W)ᵏ built here from core's operator, independently of polyharmonic_matrix().
SparseMatrix laplacian_power(const Positions& P, const Faces& F, int k) {
  const LaplaceOperator lap = cotan_laplacian(P, F);
  const SparseMatrix L = lap.mass.cwiseInverse().asDiagonal() * lap.W;
  SparseMatrix Lk = L;
  for (int i = 1; i < k; ++i) Lk = SparseMatrix(L * Lk);
  return Lk;
}

SparseMatrix abs(const SparseMatrix& A) { return A.cwiseAbs(); }

}  // namespace

TEST_CASE("fairing solves Δᵏb = 0 on free vertices and keeps constrained ones exactly",
          "[decomposition][fairing]") {
  const Scene s = lifted_plane(3000);
  const Mesh mesh = make_mesh(s.P, s.F);
  const int k = GENERATE(1, 2, 3);
  const bool fix_mesh_boundary = GENERATE(true, false);
  INFO("order k = " << k << ", fix_mesh_boundary " << fix_mesh_boundary);
  FairingOptions options;
  options.order = static_cast<FairingOrder>(k);
  options.fix_mesh_boundary = fix_mesh_boundary;
  const RegionFairing fairing(s.P, s.F, s.region, options);
  const Positions b = fairing.base();
  REQUIRE(b.rows() == s.P.rows());
  REQUIRE(b.allFinite());
  for (int v : fairing.constrained_vertices()) REQUIRE(b.row(v) == s.P.row(v));
  if (!fix_mesh_boundary) CHECK(fairing.free_vertices() == s.region.free_vertices());
  CHECK(fairing.free_vertices().size() + fairing.constrained_vertices().size() ==
        static_cast<size_t>(s.P.rows()));

  // Residual of Δᵏb relative to the size of its terms, |Δᵏ|·|b|, at every faired vertex.
  const SparseMatrix Lk = laplacian_power(s.P, s.F, k);
  const Positions r = Lk * b;
  const Eigen::VectorXd scale = abs(Lk) * b.cwiseAbs().rowwise().maxCoeff();
  double worst = 0;
  for (int v : fairing.free_vertices()) worst = std::max(worst, r.row(v).cwiseAbs().maxCoeff() / scale[v]);
  INFO("max relative residual " << worst);
  CHECK(worst <= 1e-9);
  // The free region actually moved: the bumps are gone and the ramp rises towards the handle.
  CHECK((b - s.P).cwiseAbs().maxCoeff() > 0.01);
}

TEST_CASE("fairing with uniform weights solves the umbrella equation", "[decomposition][fairing]") {
  const Scene s = lifted_plane(2000);
  const Mesh mesh = make_mesh(s.P, s.F);
  FairingOptions options;
  options.order = FairingOrder::ThinPlate;
  options.weights = LaplacianWeights::Uniform;
  const RegionFairing fairing(s.P, s.F, s.region, options);
  const Positions b = fairing.base();
  const SparseMatrix W = uniform_laplacian(s.F, static_cast<int>(s.P.rows()));
  const Eigen::VectorXd degree = -W.diagonal();
  const SparseMatrix L = degree.cwiseInverse().asDiagonal() * W;
  const SparseMatrix L2 = L * L;
  const Positions r = L2 * b;
  const Eigen::VectorXd scale = abs(L2) * b.cwiseAbs().rowwise().maxCoeff();
  for (int v : fairing.free_vertices()) REQUIRE(r.row(v).cwiseAbs().maxCoeff() <= 1e-9 * scale[v]);
  for (int v : fairing.constrained_vertices()) REQUIRE(b.row(v) == s.P.row(v));
}

TEST_CASE("fairing the bumpy plane's free region removes the bumps there", "[decomposition][fairing]") {
  SceneOptions o;
  o.resolution = 10000;  // 97 x 97 vertices, spacing h = 1/96
  const Scene s = make_surface(SceneShape::Plane, o);
  const Mesh mesh = make_mesh(s.P, s.F);
  const double h = 1.0 / 96;
  double bumps_before = 0;
  for (int v : s.region.free_vertices()) bumps_before = std::max(bumps_before, std::abs(s.P(v, 2)));
  REQUIRE(bumps_before == Approx(s.bump_height).epsilon(0.05));
  auto max_height = [&](const Positions& b) {
    double z = 0;
    for (int v : s.region.free_vertices()) z = std::max(z, std::abs(b(v, 2)));
    return z;
  };
  auto in_plane_drift = [&](const Positions& b) {
    double drift = 0;
    for (int v : s.region.free_vertices())
      drift = std::max(drift, (b.row(v).head<2>() - s.P.row(v).head<2>()).norm());
    return drift;
  };
  // What Δᵏb = 0 sees of the bumps is the first k rings of constrained vertices. The last bump rows end at
  // x = 0.195 and start at 0.805, so only the first ring (x = 19/96, 77/96) is flat; the second and third
  // rings hold bump tails up to z = 0.0014 and 0.013. Along the outline the band of fix_mesh_boundary
  // holds similar tails (bumps reach down to y = 0.005).
  FairingOptions options;
  options.order = FairingOrder::Membrane;
  Positions b = fair_region(s.P, s.F, s.region, options);
  CHECK(max_height(b) == 0.0);  // the flat first ring determines the membrane: exactly flat
  CHECK(in_plane_drift(b) <= h);
  options.order = FairingOrder::ThinPlate;
  b = fair_region(s.P, s.F, s.region, options);
  INFO("thin plate: max |z| " << max_height(b) << ", drift " << in_plane_drift(b));
  CHECK(max_height(b) <= 0.1 * s.bump_height);  // measured 0.0035: the slope of the second ring's tails
  CHECK(in_plane_drift(b) <= 1.5 * h);
  // Minimum variation continues the curvature of the tails in rings 2 and 3 (C² at the border) across
  // the whole free strip: heights beyond the bumps' (measured 0.14). It shrinks with the spacing.
  options.order = FairingOrder::MinimumVariation;
  b = fair_region(s.P, s.F, s.region, options);
  CHECK(max_height(b) > s.bump_height);
  // With the tails removed from every constrained vertex all three orders give the exact plane.
  Positions tailless = s.P;
  for (Eigen::Index v = 0; v < tailless.rows(); ++v)
    if (s.P(v, 0) < 0.25 || s.P(v, 0) > 0.75 || s.P(v, 1) < 0.05 || s.P(v, 1) > 0.95) tailless(v, 2) = 0;
  const Mesh tailless_mesh = make_mesh(tailless, s.F);
  for (int k = 1; k <= 3; ++k) {
    options.order = static_cast<FairingOrder>(k);
    CHECK(max_height(fair_region(tailless, s.F, s.region, options)) <= 1e-12);
  }
  // Uniform weights do not see the bumps' metric: the regular grid is reproduced in the plane, to the
  // rounding that Δ³'s conditioning amplifies (measured for k = 3: 9.8e-9 with CHOLMOD's factorisation,
  // 1.01e-8 with SparseSPDSolver's two-thread one).
  options.weights = LaplacianWeights::Uniform;
  for (int k = 1; k <= 3; ++k) {
    options.order = static_cast<FairingOrder>(k);
    CHECK(in_plane_drift(fair_region(s.P, s.F, s.region, options)) <= 5e-8);
  }
  // Δb = 0 literally on the outline too (fix_mesh_boundary off): the membrane minimises area and pulls
  // the outline in by several spacings.
  options = FairingOptions{};
  options.order = FairingOrder::Membrane;
  options.fix_mesh_boundary = false;
  CHECK(in_plane_drift(fair_region(s.P, s.F, s.region, options)) > 10 * h);
}

TEST_CASE("fairing reproduces a planar region: linear precision of the cotan operator",
          "[decomposition][fairing]") {
  Positions P;
  Faces F;
  std::vector<bool> interior;
  const int n = 14;
  test::jittered_grid(n, 0.3, P, F, interior);
  // Tilt the plane into 3D: linear precision does not depend on the plane's orientation.
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, -0.5).normalized()).toRotationMatrix();
  P = (P * R.transpose()).rowwise() + Vec3(0.3, -1.0, 2.0).transpose();
  // Fix three rings at the boundary so every free vertex's 2-ring is interior (Δᵏp = 0 there for k <= 3).
  std::vector<int> codes(P.rows());
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      codes[j * (n + 1) + i] = std::min({i, j, n - i, n - j}) < 3 ? Region::kFixed : Region::kFree;
  const Region region = Region::from_codes(codes);
  // New constrained positions from an affine map (shear, scale, translation, out of plane too).
  Mat4 A = Mat4::Identity();
  A.topLeftCorner<3, 3>() << 1.2, 0.3, -0.1, 0.2, 0.9, 0.4, -0.3, 0.1, 1.1;
  A.topRightCorner<3, 1>() << 0.5, 0.25, -2.0;
  Positions moved(P.rows(), 3);
  for (Eigen::Index v = 0; v < P.rows(); ++v)
    moved.row(v) = transform_point(A, P.row(v).transpose()).transpose();
  for (int k = 1; k <= 3; ++k) {
    INFO("order " << k);
    FairingOptions options;
    options.order = static_cast<FairingOrder>(k);
    RegionFairing fairing(P, F, region, options);
    // Round-off grows with the condition number of L^k (about h^-2k): order 3 gave 1.4e-12 with OpenBLAS's
    // AVX-512 kernels (1e-12 failed there), so the bound is 1e-12 · 10^(k-1).
    const double tolerance = 1e-12 * std::pow(10.0, k - 1);
    const double base_error = (fairing.base() - P).cwiseAbs().maxCoeff();
    INFO("base error " << std::scientific << base_error);
    CHECK(base_error <= tolerance);
    // Re-fairing affinely moved constraints with the stored factorisation gives the affine image.
    Positions out;
    fairing.fair(moved, out);
    CHECK((out - moved).cwiseAbs().maxCoeff() <= tolerance);
    // The same constraints passed as #C rows.
    Positions constrained(fairing.constrained_vertices().size(), 3);
    for (size_t c = 0; c < fairing.constrained_vertices().size(); ++c)
      constrained.row(c) = moved.row(fairing.constrained_vertices()[c]);
    Positions out2;
    fairing.fair_constrained(constrained, out2);
    CHECK(out2 == out);
  }
}

TEST_CASE("RegionFairing re-fairs new constraint positions without refactoring", "[decomposition][fairing]") {
  const Scene lifted = lifted_plane(2000);
  SceneOptions o;
  o.resolution = 2000;
  const Scene flat = make_surface(SceneShape::Plane, o);
  // Prepared on the flat bumpy plane, re-faired with the lifted handle: the constraints are met exactly,
  // the result is linear in them, and fair() of the rest positions is fair_region().
  RegionFairing fairing(flat.P, flat.F, flat.region);
  CHECK(fairing.prepared());
  CHECK(fairing.num_vertices() == flat.P.rows());
  // The free vertices within two rings of the outline are kept (fix_mesh_boundary, thin plate) and count
  // as constrained.
  const std::vector<int> outline = boundary_band(flat.F, static_cast<int>(flat.P.rows()), 2);
  CHECK(boundary_band(flat.F, static_cast<int>(flat.P.rows()), 1) == boundary_vertices(flat.F, static_cast<int>(flat.P.rows())));
  CHECK(boundary_band(flat.F, static_cast<int>(flat.P.rows()), 0).empty());
  std::vector<int> expected_free;
  for (int v : flat.region.free_vertices())
    if (!std::binary_search(outline.begin(), outline.end(), v)) expected_free.push_back(v);
  CHECK(fairing.free_vertices() == expected_free);
  CHECK(fairing.constrained_vertices().size() == flat.P.rows() - expected_free.size());
  const Positions b0 = fairing.base();
  CHECK((b0 - fair_region(flat.P, flat.F, flat.region)).cwiseAbs().maxCoeff() <= 1e-14);
  Positions b1;
  fairing.fair(lifted.P, b1);
  for (int v : fairing.constrained_vertices()) REQUIRE(b1.row(v) == lifted.P.row(v));
  const Positions half = fairing.fair(0.5 * (flat.P + lifted.P));
  CHECK((half - 0.5 * (b0 + b1)).cwiseAbs().maxCoeff() <= 1e-12);
  // out may alias the input.
  Positions inplace = lifted.P;
  fairing.fair(inplace, inplace);
  CHECK(inplace == b1);
}

TEST_CASE("fairing reports bad input", "[decomposition][fairing][bad-input]") {
  SceneOptions o;
  o.resolution = 500;
  const Scene s = make_surface(SceneShape::Plane, o);
  const Mesh mesh = make_mesh(s.P, s.F);
  const int nv = static_cast<int>(s.P.rows());

  CHECK_THROWS_AS(fair_region(s.P, s.F, Region(nv, Region::kFree)), InvalidInput);
  CHECK_THROWS_WITH(fair_region(s.P, s.F, Region(nv, Region::kFree)), Contains("no fixed or handle vertex"));
  CHECK_THROWS_AS(fair_region(s.P, s.F, Region(nv - 1, Region::kFixed)), InvalidInput);
  CHECK_THROWS_WITH(fair_region(s.P, s.F, Region(nv - 1, Region::kFixed)),
                    Contains("fair_region") && Contains("vertex labels"));
  // Handle codes must be consecutive: handle 1 used while handle 0 is empty.
  Region gap = s.region;
  gap.set_handle(s.region.handle_vertices(0), 1);
  CHECK_THROWS_WITH(fair_region(s.P, s.F, gap), Contains("fair_region") && Contains("handle 0"));

  FairingOptions bad;
  bad.order = static_cast<FairingOrder>(4);
  CHECK_THROWS_WITH(fair_region(s.P, s.F, s.region, bad), Contains("order 4"));

  RegionFairing fairing;
  CHECK_FALSE(fairing.prepared());
  Positions out;
  CHECK_THROWS_AS(fairing.fair(s.P, out), UsageError);
  fairing.prepare(s.P, s.F, s.region);
  CHECK_THROWS_AS(fairing.fair(Positions(nv + 1, 3), out), UsageError);
  CHECK_THROWS_AS(fairing.fair_constrained(Positions(3, 3), out), UsageError);
  Positions nan = s.P;
  const int c = s.region.constrained_vertices()[5];
  nan(c, 1) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(fairing.fair(nan, out),
                    Contains("constrained vertex " + std::to_string(c)) && Contains("non-finite"));
  // A NaN on a free vertex is never read.
  Positions free_nan = s.P;
  free_nan(fairing.free_vertices()[0], 0) = std::numeric_limits<double>::quiet_NaN();
  CHECK_NOTHROW(fairing.fair(free_nan, out));
  CHECK(out.allFinite());
}

TEST_CASE("fairing names the free vertex without area and the unanchored free component",
          "[decomposition][fairing][bad-input]") {
  // A quad with fixed vertices, and a separate triangle that is all free.
  Positions P(7, 3);
  P << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 5, 5, 0, 6, 5, 0, 5, 6, 0;
  Faces F(3, 3);
  F << 0, 1, 2, 0, 2, 3, 4, 5, 6;
  Region region(7, Region::kFree);
  region.set_fixed({0, 1, 2});
  CHECK_THROWS_AS(fair_region(P, F, region), TopologyError);
  CHECK_THROWS_WITH(fair_region(P, F, region),
                    Contains("fair_region") && Contains("touches no fixed or handle vertex"));

  // A free vertex whose only face is degenerate (collinear): Δ is undefined there.
  Positions Q(5, 3);
  Q << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0;
  Faces G(3, 3);
  G << 0, 1, 2, 0, 2, 3, 1, 4, 2;
  Q.row(4) << 1, 0.5, 0;  // on the edge 1-2: face (1, 4, 2) has zero area
  Region r2(5, Region::kFixed);
  r2.set_free({4});
  FairingOptions literal;
  literal.fix_mesh_boundary = false;  // vertex 4 is on the outline
  CHECK_THROWS_WITH(fair_region(Q, G, r2, literal),
                    Contains("free vertex 4") && Contains("non-zero area"));
}
