#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <utility>

#include "msdeform/core/errors.h"
#include "msdeform/detail/closest_point.h"
#include "test_util.h"

using namespace msd;

namespace {

// Brute force: the closest point over a dense barycentric sampling (an upper bound on the distance).
double sampled_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, int n = 200) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const double u = double(i) / n, v = double(j) / n;
      best = std::min(best, (p - ((1 - u - v) * a + u * b + v * c)).squaredNorm());
    }
  return best;
}

}  // namespace

TEST_CASE("closest point on a triangle: every Voronoi region", "[detail][closest]") {
  const Vec3 a(0, 0, 0), b(2, 0, 0), c(0, 1, 0);
  Vec3 w;
  struct Case {
    Vec3 p, expected;
  };
  const Case cases[] = {
      {{-1, -1, 0.5}, a},                // vertex a
      {{3, -0.5, -1}, b},                // vertex b
      {{-0.2, 2, 0.3}, c},               // vertex c
      {{1, -1, 2}, {1, 0, 0}},           // edge ab
      {{-1, 0.5, 0}, {0, 0.5, 0}},       // edge ca
      {{2, 2, 1}, {1.2, 0.4, 0}},        // edge bc: (2, 2) projects onto the line x + 2y = 2 at (1.2, 0.4)
      {{0.5, 0.25, -3}, {0.5, 0.25, 0}}  // interior
  };
  for (const auto& k : cases) {
    INFO("p = " << k.p.transpose());
    const Vec3 q = closest_point_on_triangle(k.p, a, b, c, w);
    CHECK((q - k.expected).norm() <= 1e-15);
    CHECK((w[0] * a + w[1] * b + w[2] * c - q).norm() <= 1e-15);
    CHECK(w.sum() == Approx(1.0).margin(1e-15));
    CHECK(w.minCoeff() >= 0.0);
  }
}

TEST_CASE("closest point on a triangle agrees with dense sampling, also for degenerate triangles",
          "[detail][closest]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  auto random_vec = [&] { return Vec3(u(rng), u(rng), u(rng)); };
  for (int trial = 0; trial < 300; ++trial) {
    Vec3 a = random_vec(), b = random_vec(), c = random_vec();
    if (trial % 3 == 1) c = a + 0.3 * (b - a);  // collinear
    if (trial % 3 == 2) c = b;                  // two corners coincide
    const Vec3 p = 2 * random_vec();
    Vec3 w;
    const Vec3 q = closest_point_on_triangle(p, a, b, c, w);
    const double d2 = (p - q).squaredNorm();
    INFO("trial " << trial);
    CHECK(std::isfinite(d2));
    CHECK((w[0] * a + w[1] * b + w[2] * c - q).norm() <= 1e-14);
    CHECK(w.minCoeff() >= -1e-15);
    // Never farther than the best sample, and never closer than the exact minimum allows.
    const double sampled = sampled_distance2(p, a, b, c);
    CHECK(d2 <= sampled + 1e-14);
    CHECK(std::sqrt(sampled) - std::sqrt(d2) <= 2 * (a - b).norm() / 200 + 2 * (a - c).norm() / 200 + 1e-12);
  }
}

TEST_CASE("ClosestPointQuery matches a brute-force scan over all faces", "[detail][closest]") {
  Positions P;
  Faces F;
  test::icosphere(3, P, F);  // 1280 faces
  const ClosestPointQuery query(P, F);
  CHECK(query.num_faces() == F.rows());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  Positions Q(500, 3);
  for (int i = 0; i < Q.rows(); ++i) Q.row(i) << u(rng), u(rng), u(rng);
  Q.row(0) << 0, 0, 0;                                 // equidistant from everything (ties)
  Q.row(1) = P.row(17);                                // on a vertex
  Q.row(2) = 0.5 * (P.row(F(3, 0)) + P.row(F(3, 1)));  // on an edge
  Q.row(3) << 1e3, -2e3, 5e2;                          // far away
  const std::vector<ClosestPoint> batch = query.query_all(Q);
  REQUIRE(batch.size() == static_cast<size_t>(Q.rows()));
  for (int i = 0; i < Q.rows(); ++i) {
    const Vec3 p = Q.row(i);
    double best = std::numeric_limits<double>::infinity();
    for (int f = 0; f < F.rows(); ++f) {
      Vec3 w;
      best =
          std::min(best, (p - closest_point_on_triangle(p, P.row(F(f, 0)), P.row(F(f, 1)), P.row(F(f, 2)), w))
                             .squaredNorm());
    }
    const ClosestPoint single = query.query(p);
    INFO("query " << i);
    REQUIRE(single.face >= 0);
    CHECK(single.squared_distance == Approx(best).epsilon(1e-12).margin(1e-15));
    CHECK(batch[i].squared_distance == single.squared_distance);
    CHECK(batch[i].face == single.face);
    const Vec3 on_face = single.barycentric[0] * Vec3(P.row(F(single.face, 0))) +
                         single.barycentric[1] * Vec3(P.row(F(single.face, 1))) +
                         single.barycentric[2] * Vec3(P.row(F(single.face, 2)));
    CHECK((on_face - single.point).norm() <= 1e-14);
    CHECK((p - single.point).squaredNorm() == Approx(single.squared_distance).epsilon(1e-12).margin(1e-15));
  }
}

TEST_CASE("ClosestPointQuery with a distance bound finds what the unbounded search finds", "[detail][closest]") {
  // The bound a detail encoding passes: the distance to the base vertex of the same index. Also a
  // bound exactly at the closest distance, and one that breaks the contract (too small: the query
  // searches again without it, same answer). Points around a convex polyhedron's vertices often have
  // that vertex as their closest point, which all its triangles share.
  Positions P;
  Faces F;
  test::icosphere(3, P, F);
  const ClosestPointQuery query(P, F);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (int v = 0; v < P.rows(); ++v) {
    const Vec3 p = Vec3(P.row(v)) * (1 + noise(rng)) + Vec3(noise(rng), noise(rng), noise(rng));
    const ClosestPoint free = query.query(p);
    for (const double bound : {(p - Vec3(P.row(v))).norm(), std::sqrt(free.squared_distance),
                               0.5 * std::sqrt(free.squared_distance)}) {
      const ClosestPoint bounded = query.query(p, bound);
      INFO("vertex " << v << ", bound " << bound);
      REQUIRE(bounded.face >= 0);
      CHECK(bounded.squared_distance == free.squared_distance);
      CHECK((bounded.point - free.point).norm() <= 1e-15);
      // A point on an edge or a corner belongs to several triangles (a tie): either may be returned.
      if (bounded.face == free.face) CHECK(bounded.barycentric == free.barycentric);
      else CHECK(bounded.barycentric.minCoeff() <= 1e-15);
    }
  }
}

TEST_CASE("ClosestPointQuery is exact where Embree's float copy is not", "[detail][closest]") {
  // Two nearly coincident parallel triangles 1e-9 apart, far from the origin: their float copies coincide,
  // the double-precision answer must still pick the nearer one and report its exact distance.
  Positions P(6, 3);
  P << 1000, 1000, 0, 1001, 1000, 0, 1000, 1001, 0,  //
      1000, 1000, 1e-9, 1001, 1000, 1e-9, 1000, 1001, 1e-9;
  Faces F(2, 3);
  F << 0, 1, 2, 3, 4, 5;
  const ClosestPointQuery query(P, F);
  const ClosestPoint above = query.query(Vec3(1000.2, 1000.2, 1.0));
  CHECK(above.face == 1);
  CHECK(above.squared_distance == Approx((1.0 - 1e-9) * (1.0 - 1e-9)).epsilon(1e-15));
  const ClosestPoint below = query.query(Vec3(1000.2, 1000.2, -1.0));
  CHECK(below.face == 0);
  CHECK(below.point.z() == 0.0);
}

// Issue 14, kind 3: a mesh 1e20 from the origin (all its vertices one float) found no triangle (face −1,
// then a crash in multi-scale); tiny and huge meshes too. The answer must be the shifted / scaled one.
TEST_CASE("ClosestPointQuery works wherever the mesh sits and whatever its units", "[detail][closest]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  Positions P(40, 3);
  for (Eigen::Index v = 0; v < P.rows(); ++v) P.row(v) << u(rng), u(rng), 0.1 * u(rng);
  Faces F(20, 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) F.row(f) << 2 * f, 2 * f + 1, (2 * f + 2) % 40;
  const ClosestPointQuery unit(P, F);
  const std::pair<double, double> cases[] = {{1e16, 1e20}, {1.0, 1e8}, {1e-30, 0.0}, {1e30, 0.0}, {1e-6, 1.0}};
  for (const auto& [scale, offset] : cases) {
    INFO("scale " << scale << ", offset " << offset);
    const Positions moved = (scale * P).array() + offset;
    const ClosestPointQuery query(moved, F);
    for (int i = 0; i < 20; ++i) {
      const Vec3 q(u(rng), u(rng), u(rng) - 0.5);
      const ClosestPoint a = unit.query(q), b = query.query((scale * q).array() + offset);
      REQUIRE(b.face >= 0);
      CHECK(std::sqrt(b.squared_distance) / scale == Approx(std::sqrt(a.squared_distance)).margin(1e-9 + 1e-15 * offset / scale));
    }
  }
}

TEST_CASE("ClosestPointQuery reports bad input and use", "[detail][closest][bad-input]") {
  ClosestPointQuery query;
  CHECK(query.empty());
  CHECK_THROWS_AS(query.query(Vec3::Zero()), UsageError);
  Positions P(3, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  Faces F(1, 3);
  F << 0, 1, 3;
  CHECK_THROWS_AS(query.build(P, F), InvalidInput);
  CHECK_THROWS_AS(query.build(P, Faces()), InvalidInput);
  F << 0, 1, 2;
  P(1, 1) = std::nan("");
  CHECK_THROWS_AS(query.build(P, F), InvalidInput);
  P(1, 1) = 0;
  query.build(P, F);
  CHECK_FALSE(query.empty());
  ClosestPointQuery moved = std::move(query);
  CHECK(moved.query(Vec3(0.25, 0.25, 1)).squared_distance == Approx(1.0));
}
