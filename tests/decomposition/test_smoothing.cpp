#include <catch2/catch.hpp>

#include <random>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/scenes.h"
#include "msdeform/decomposition/smoothing.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

// Thin-plate roughness Σ mᵢ |Δpᵢ|² over the interior vertices, with Δ = M⁻¹W of the reference surface
// (boundary vertices carry the outline's curvature, which smoothing is not meant to remove).
struct Roughness {
  LaplaceOperator lap;
  std::vector<char> interior;
  Roughness(const Positions& P, const Faces& F) : lap(cotan_laplacian(P, F)), interior(P.rows(), 1) {
    for (int v : boundary_vertices(F, static_cast<int>(P.rows()))) interior[v] = 0;
  }
  double operator()(const Positions& P) const {
    const Positions lp = lap.mass.cwiseInverse().asDiagonal() * (lap.W * P);
    double e = 0;
    for (Eigen::Index v = 0; v < P.rows(); ++v)
      if (interior[v]) e += lap.mass[v] * lp.row(v).squaredNorm();
    return e;
  }
};

Vec3 centroid(const Positions& P, const Eigen::VectorXd& mass) { return P.transpose() * mass / mass.sum(); }

void noisy_sphere(Positions& P, Faces& F) {
  test::icosphere(3, P, F);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.03, 0.03);
  for (Eigen::Index v = 0; v < P.rows(); ++v) P.row(v) *= 1.0 + u(rng);
  P.col(0) = P.col(0) * 1.5 + Eigen::VectorXd::Constant(P.rows(), 0.7);  // off-centre ellipsoid
}

double volume(const Positions& P, const Faces& F) {
  double v = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    v += Vec3(P.row(F(f, 0))).dot(Vec3(P.row(F(f, 1))).cross(Vec3(P.row(F(f, 2)))));
  return v / 6;
}

}  // namespace

TEST_CASE("implicit smoothing reduces roughness and keeps the mass-weighted centroid",
          "[decomposition][smoothing]") {
  SceneOptions o;
  o.resolution = 3000;
  const Scene s = make_surface(SceneShape::Plane, o);
  const Roughness roughness(s.P, s.F);
  const double before = roughness(s.P);
  SmoothingOptions options;
  options.fix_boundary = false;  // no constraint: each step preserves Σ mᵢpᵢ exactly
  options.time_step = 4.0;
  options.iterations = 3;
  const Positions smoothed = implicit_smoothing(s.P, s.F, options);
  const double after = roughness(smoothed);
  INFO("roughness " << before << " -> " << after);
  CHECK(after < 0.05 * before);
  const Vec3 c0 = centroid(s.P, roughness.lap.mass), c1 = centroid(smoothed, roughness.lap.mass);
  CHECK((c1 - c0).norm() <= 1e-12 * bounding_box_diagonal(s.P));
  // The bumps are damped, the plane is where it was.
  CHECK(smoothed.col(2).cwiseAbs().maxCoeff() < 0.5 * s.bump_height);

  SECTION("more time smooths more") {
    options.time_step = 16.0;
    CHECK(roughness(implicit_smoothing(s.P, s.F, options)) < after);
  }
  SECTION("updating the operator per step also smooths") {
    options.update_operator = true;
    CHECK(roughness(implicit_smoothing(s.P, s.F, options)) < 0.05 * before);
  }
  SECTION("uniform weights also smooth") {
    // Measured with the cotan operator, which also sees the tangential drift the umbrella causes.
    options.weights = LaplacianWeights::Uniform;
    CHECK(roughness(implicit_smoothing(s.P, s.F, options)) < 0.5 * before);
  }
}

TEST_CASE("implicit smoothing keeps boundary vertices when asked", "[decomposition][smoothing]") {
  SceneOptions o;
  o.resolution = 2000;
  const Scene s = make_surface(SceneShape::Plane, o);
  SmoothingOptions options;  // fix_boundary is the default
  options.time_step = 10;
  const Positions smoothed = implicit_smoothing(s.P, s.F, options);
  const std::vector<int> boundary = boundary_vertices(s.F, static_cast<int>(s.P.rows()));
  REQUIRE(boundary.size() > 100);
  for (int v : boundary) REQUIRE(smoothed.row(v) == s.P.row(v));
  CHECK(Roughness(s.P, s.F)(smoothed) < 0.1 * Roughness(s.P, s.F)(s.P));
}

TEST_CASE("implicit smoothing time units and rescaling", "[decomposition][smoothing]") {
  Positions P;
  Faces F;
  noisy_sphere(P, F);
  const LaplaceOperator lap = cotan_laplacian(P, F);
  SmoothingOptions options;
  options.time_step = 0.01;
  options.unit = SmoothingTimeUnit::BoundingBoxDiagonalSquared;
  const double t = smoothing_time(P, F, options);
  CHECK(t == Approx(0.01 * std::pow(bounding_box_diagonal(P), 2)).epsilon(1e-14));
  const Positions a = implicit_smoothing(P, F, options);
  options.unit = SmoothingTimeUnit::Absolute;
  options.time_step = t;
  CHECK((implicit_smoothing(P, F, options) - a).cwiseAbs().maxCoeff() <= 1e-14);
  options.unit = SmoothingTimeUnit::MeanEdgeLengthSquared;
  options.time_step = 2;
  CHECK(smoothing_time(P, F, options) == Approx(2 * std::pow(mean_edge_length(P, F), 2)));

  // Closed mesh: no boundary to fix; volume or area restored, centroid kept.
  options.iterations = 4;
  options.time_step = 20;
  const Positions shrunk = implicit_smoothing(P, F, options);
  CHECK(volume(shrunk, F) < 0.99 * volume(P, F));
  options.rescale = SmoothingRescale::Volume;
  const Positions v = implicit_smoothing(P, F, options);
  CHECK(volume(v, F) == Approx(volume(P, F)).epsilon(1e-12));
  CHECK((centroid(v, lap.mass) - centroid(P, lap.mass)).norm() <= 1e-12);
  options.rescale = SmoothingRescale::Area;
  const Positions ar = implicit_smoothing(P, F, options);
  CHECK(face_areas(ar, F).sum() == Approx(face_areas(P, F).sum()).epsilon(1e-12));
  CHECK(Roughness(P, F)(ar) < Roughness(P, F)(P));
}

TEST_CASE("implicit smoothing reports bad input", "[decomposition][smoothing][bad-input]") {
  SceneOptions o;
  o.resolution = 300;
  const Scene s = make_surface(SceneShape::Plane, o);
  SmoothingOptions options;
  CHECK(implicit_smoothing(s.P, s.F, [] {
          SmoothingOptions z;
          z.iterations = 0;
          return z;
        }()) == s.P);
  options.time_step = 0;
  CHECK_THROWS_WITH(implicit_smoothing(s.P, s.F, options), Contains("time step"));
  options.time_step = std::numeric_limits<double>::infinity();
  CHECK_THROWS_AS(implicit_smoothing(s.P, s.F, options), InvalidInput);
  options.time_step = 1;
  options.iterations = -1;
  CHECK_THROWS_WITH(implicit_smoothing(s.P, s.F, options), Contains("-1 iterations"));
  options.iterations = 1;
  Faces bad = s.F;
  bad(7, 1) = static_cast<int>(s.P.rows());
  CHECK_THROWS_WITH(implicit_smoothing(s.P, bad, options), Contains("face 7"));
  Positions nan = s.P;
  nan(11, 2) = std::nan("");
  CHECK_THROWS_WITH(implicit_smoothing(nan, s.F, options), Contains("vertex 11"));
  options.rescale = SmoothingRescale::Volume;
  options.fix_boundary = false;
  CHECK_THROWS_WITH(implicit_smoothing(s.P, s.F, options), Contains("closed mesh"));
  options.rescale = SmoothingRescale::Area;
  options.fix_boundary = true;
  CHECK_THROWS_WITH(implicit_smoothing(s.P, s.F, options), Contains("fix_boundary"));
  // An unreferenced vertex has no area and nothing to diffuse with.
  Positions extra(s.P.rows() + 1, 3);
  extra << s.P, Eigen::RowVector3d(2, 2, 2);
  options.rescale = SmoothingRescale::None;
  CHECK_THROWS_WITH(implicit_smoothing(extra, s.F, options),
                    Contains("vertex " + std::to_string(s.P.rows())));
}
