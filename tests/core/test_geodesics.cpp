#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "msdeform/core/errors.h"
#include "msdeform/core/geodesics.h"
#include "msdeform/core/scenes.h"
#include "test_util.h"

using namespace msd;

namespace {

constexpr double kPi = 3.14159265358979323846;

// The lift scene with bump height 0: the unit square, where geodesics are straight.
Scene flat_lift_plane(int resolution) {
  SceneOptions o;
  o.resolution = resolution;
  o.bump_height = 0.0;
  return make_scene("lift", o);
}

}  // namespace

TEST_CASE("heat-method distances on a flat plane approximate Euclidean distances", "[core][geodesics]") {
  const Scene c = flat_lift_plane(10000);  // bump height 0: the unit square, where geodesics are straight
  const double h = HeatGeodesics(c.P, c.F).mean_edge_length();
  SECTION("from a single interior vertex") {
    int source = 0;
    (c.P.rowwise() - Eigen::RowVector3d(0.5, 0.5, 0)).rowwise().squaredNorm().minCoeff(&source);
    const Eigen::VectorXd d = geodesic_distance(c.P, c.F, {source});
    CHECK(d[source] == 0.0);
    double max_abs = 0, sum_rel = 0;
    int count = 0;
    for (int i = 0; i < c.P.rows(); ++i) {
      const double exact = (c.P.row(i) - c.P.row(source)).norm();
      max_abs = std::max(max_abs, std::abs(d[i] - exact));
      if (exact > 5 * h) sum_rel += std::abs(d[i] - exact) / exact, ++count;
    }
    INFO("h = " << h << ", max abs error " << max_abs << " (" << max_abs / h << " h), mean relative error "
                << sum_rel / count);
    CHECK(max_abs <= 2 * h);         // within two edge lengths everywhere (measured 1.2 h)
    CHECK(sum_rel / count <= 0.02);  // 2% mean relative error beyond 5 h (measured 1.3%)
  }
  SECTION("from the fixed strip: the distance is x - x_strip") {
    const std::vector<int> fixed = c.region.fixed_vertices();
    const Eigen::VectorXd d = geodesic_distance(c.P, c.F, fixed);
    double strip_end = 0;
    for (int v : fixed) strip_end = std::max(strip_end, c.P(v, 0));
    double max_abs = 0;
    for (int i = 0; i < c.P.rows(); ++i) {
      const double exact = std::max(0.0, c.P(i, 0) - strip_end);
      max_abs = std::max(max_abs, std::abs(d[i] - exact));
    }
    INFO("max abs error " << max_abs << " = " << max_abs / h << " h");
    CHECK(max_abs <= 0.5 * h);  // half an edge length (measured 0.13 h)
  }
}

TEST_CASE("heat-method distances on a sphere approach great-circle distances with refinement", "[core][geodesics]") {
  // Tolerances proportional to the mean edge length h, so they shrink with refinement. Measured, levels
  // 2..5 (162..10242 vertices): mean relative error 3.8%, 2.0%, 1.1%, 0.7%; max abs error 0.052, 0.027,
  // 0.016, 0.012 on the unit sphere.
  double previous_mean = INFINITY, previous_max = INFINITY;
  for (int level = 2; level <= 5; ++level) {
    Positions P;
    Faces F;
    test::icosphere(level, P, F);
    HeatGeodesics geodesics(P, F);
    const double h = geodesics.mean_edge_length();
    const Eigen::VectorXd d = geodesics.distance({0});
    double sum_rel = 0, max_abs = 0;
    for (int i = 1; i < P.rows(); ++i) {
      const double exact = std::acos(std::clamp(P.row(i).dot(P.row(0)), -1.0, 1.0));
      sum_rel += std::abs(d[i] - exact) / exact;
      // The antipode is the cut locus, where every method smooths; measure the max away from it.
      if (exact < 0.9 * kPi) max_abs = std::max(max_abs, std::abs(d[i] - exact));
    }
    const double mean_rel = sum_rel / (P.rows() - 1);
    INFO("level " << level << " (" << P.rows() << " vertices, h = " << h << "): mean relative error " << mean_rel
                  << ", max abs error " << max_abs);
    CHECK(mean_rel <= 0.5 * h);
    CHECK(max_abs <= 0.5 * h);
    CHECK(mean_rel < previous_mean);
    CHECK(max_abs < previous_max);
    previous_mean = mean_rel;
    previous_max = max_abs;
  }
  CHECK(previous_mean <= 0.01);  // 1% at 10k vertices
}

TEST_CASE("heat-method distances stay accurate on a mesh far longer than 700 heat lengths", "[core][geodesics]") {
  // A 1500 x 2 strip of unit squares: with t = h² the heat kernel exp(-d/√t) would underflow after ~700
  // edges; the time step is enlarged instead, keeping the distance from the left end equal to x.
  const int nx = 1500, ny = 2;
  Positions P((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) P.row(j * (nx + 1) + i) << i, j, 0;
  Faces F(2 * nx * ny, 3);
  for (int j = 0, f = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      F.row(f++) << a, b, d;
      F.row(f++) << a, d, c;
    }
  std::vector<int> left;
  for (int j = 0; j <= ny; ++j) left.push_back(j * (nx + 1));
  HeatGeodesics geodesics(P, F);
  const Eigen::VectorXd d = geodesics.distance(left);
  const double h = geodesics.mean_edge_length();
  CHECK(geodesics.last_time_step() > h * h);
  double worst = 0;
  for (int i = 0; i < P.rows(); ++i) worst = std::max(worst, std::abs(d[i] - P(i, 0)));
  INFO("max abs error " << worst << " over a length of " << nx);
  CHECK(worst <= 0.1);  // a tenth of an edge over 1500 edges (measured 0.043)
}

TEST_CASE("heat-method distance is infinite on components without a source", "[core][geodesics]") {
  Positions P1, P;
  Faces F1, F;
  test::icosphere(2, P1, F1);
  P.resize(2 * P1.rows(), 3);
  P << P1, P1.rowwise() + Eigen::RowVector3d(3, 0, 0);
  F.resize(2 * F1.rows(), 3);
  F << F1, F1.array() + static_cast<int>(P1.rows());
  const Eigen::VectorXd d = geodesic_distance(P, F, {0});
  CHECK(d.head(P1.rows()).allFinite());
  CHECK(d.tail(P1.rows()).array().isInf().all());
  CHECK_THROWS_AS(geodesic_distance(P, F, {static_cast<int>(P.rows())}), InvalidInput);
  CHECK(geodesic_distance(P, F, {}).array().isInf().all());
}

