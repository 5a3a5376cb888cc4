#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "msdeform/core/kd_tree.h"

using namespace msd;

TEST_CASE("k-d tree: nearest point and distance equal brute force", "[core][kd_tree]") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  Positions P(3000, 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) P.row(i) << u(rng), u(rng), 0.1 * u(rng);
  std::vector<int> subset;
  for (int i = 0; i < P.rows(); i += 3) subset.push_back(i);
  const KdTree all(P), some(P, subset);
  CHECK(all.size() == 3000);
  CHECK(some.size() == static_cast<int>(subset.size()));
  for (int trial = 0; trial < 500; ++trial) {
    const Vec3 q(1.5 * u(rng), 1.5 * u(rng), u(rng));
    double best_all = INFINITY, best_some = INFINITY;
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      const double d = (P.row(i).transpose() - q).norm();
      best_all = std::min(best_all, d);
      if (i % 3 == 0) best_some = std::min(best_some, d);
    }
    const KdNearest a = all.nearest(q), s = some.nearest(q);
    // Exact search (no approximation factor): equal up to the rounding of the norm.
    CHECK(a.distance == Approx(best_all).epsilon(1e-14));
    CHECK(s.distance == Approx(best_some).epsilon(1e-14));
    CHECK((P.row(a.index).transpose() - q).norm() == Approx(a.distance).epsilon(1e-14));
    CHECK(s.index % 3 == 0);
    CHECK((P.row(s.index).transpose() - q).norm() == Approx(s.distance).epsilon(1e-14));
    CHECK(some.nearest_distance(q) == s.distance);
  }
}

TEST_CASE("k-d tree: empty tree and repeated points", "[core][kd_tree]") {
  Positions P(20, 3);
  P.setZero();
  P.row(7) << 1, 0, 0;
  const KdTree empty(P, {});
  CHECK(empty.nearest(Vec3::Zero()).index == -1);
  CHECK(std::isinf(empty.nearest_distance(Vec3::Zero())));
  const KdTree tree(P);
  CHECK(tree.nearest(Vec3(0.9, 0, 0)).index == 7);
  CHECK(tree.nearest(Vec3(0.9, 0, 0)).distance == Approx(0.1).epsilon(1e-15));
  const KdNearest at_origin = tree.nearest(Vec3::Zero());
  CHECK(at_origin.distance == 0.0);
  CHECK(at_origin.index != 7);
}
