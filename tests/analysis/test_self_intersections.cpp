#include <catch2/catch.hpp>

#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

TEST_CASE("self intersections: clean closed and open meshes have none", "[analysis][self_intersections]") {
  Positions P;
  Faces F;
  SECTION("icosphere") { test::icosphere(3, P, F); }
  SECTION("flat grid: coplanar neighbours only share edges") {
    std::vector<bool> interior;
    test::jittered_grid(10, 0.3, P, F, interior);
  }
  SECTION("real mesh: decimated knight") {
    const Mesh m = load_mesh(test::shared_data("decimated-knight.off"));
    P = positions(m);
    F = faces(m);
  }
  std::vector<std::pair<int, int>> pairs = {{1, 2}};
  int degenerate = -1;
  CHECK(count_self_intersections(P, F, &pairs, &degenerate) == 0);
  CHECK(pairs.empty());
  CHECK(degenerate == 0);
}

TEST_CASE("self intersections: a vertex pushed through the opposite side", "[analysis][self_intersections]") {
  Positions P;
  Faces F;
  test::icosphere(2, P, F);
  P.row(0) *= -1.4;  // the apex pokes out through the far side of the sphere
  std::vector<std::pair<int, int>> pairs;
  const int count = count_self_intersections(P, F, &pairs);
  CHECK(count > 0);
  REQUIRE(pairs.size() == static_cast<size_t>(count));
  for (const auto& [f, g] : pairs) {
    CHECK(f < g);
    CHECK(g < F.rows());
    // Every pair involves one of the faces around the moved vertex.
    const bool moved = (F.row(f).array() == 0).any() || (F.row(g).array() == 0).any();
    CHECK(moved);
  }
  CHECK(std::is_sorted(pairs.begin(), pairs.end()));
  CHECK(count_self_intersections(P, F) == count);
}

TEST_CASE("self intersections: an edit's new pairs count beside a contact at rest, its sliding does not",
          "[analysis][self_intersections]") {
  // Two unit spheres overlapping at rest (A at the origin, B at x = 1.98: its surface cuts the faces around
  // A's tip) and a third, C, at x = -3.
  Positions S;
  Faces G;
  test::icosphere(2, S, G);
  const Eigen::Index n = S.rows(), m = G.rows();
  Positions P(3 * n, 3);
  Faces F(3 * m, 3);
  for (int piece = 0; piece < 3; ++piece) {
    P.middleRows(piece * n, n) = S.rowwise() + Eigen::RowVector3d(piece == 0   ? 0
                                                                  : piece == 1 ? 1.98
                                                                               : -3,
                                                                  0, 0);
    F.middleRows(piece * m, m) = G.array() + static_cast<int>(piece * n);
  }
  const AddedSelfIntersections added(P, F);
  REQUIRE(added.rest_pairs() > 0);
  // B slid a little along A: its contact moves to neighbouring faces, which is no new intersection.
  Positions slid = P;
  slid.middleRows(n, n).col(1).array() += 0.05;
  CHECK(added.count(slid) == 0);
  // A's vertex inside B (in the contact at rest) pushed through A and into C: new pairs, all with a face of
  // the contact at rest (the third break test: such pairs were all left out, 0 counted).
  Eigen::Index tip = 0;
  P.topRows(n).col(0).maxCoeff(&tip);
  Positions pushed = P;
  pushed(tip, 0) = -3.5;
  std::vector<int> faces;
  CHECK(added.count(pushed, &faces) > 0);
}

TEST_CASE("self intersections: degenerate faces are counted, not crashed on",
          "[analysis][self_intersections]") {
  Positions S;
  Faces G;
  test::icosphere(2, S, G);
  // The sphere plus a zero-area triangle (collinear corners) and a triangle that repeats an index, both
  // away from the sphere, and a needle of collinear points through its middle.
  const int n = static_cast<int>(S.rows());
  Positions P(n + 8, 3);
  P.topRows(n) = S;
  P.row(n) << 3, 0, 0;
  P.row(n + 1) << 4, 0, 0;
  P.row(n + 2) << 5, 0, 0;
  P.row(n + 3) << 3, 3, 0;
  P.row(n + 4) << 4, 3, 0;
  P.row(n + 5) << -2, 0.01, 0.02;
  P.row(n + 6) << 0, 0.01, 0.02;
  P.row(n + 7) << 2, 0.01, 0.02;
  Faces F(G.rows() + 3, 3);
  F.topRows(G.rows()) = G;
  F.row(G.rows()) << n, n + 1, n + 2;
  F.row(G.rows() + 1) << n + 3, n + 4, n + 3;
  F.row(G.rows() + 2) << n + 5, n + 6, n + 7;
  std::vector<std::pair<int, int>> pairs;
  int degenerate = 0;
  const int count = count_self_intersections(P, F, &pairs, &degenerate);
  CHECK(degenerate == 3);
  CHECK(count == 0);  // degenerate faces are not tested against the others (see the header)
  CHECK(pairs.empty());
}

TEST_CASE("self intersections: bad input is named", "[analysis][self_intersections]") {
  Positions P;
  Faces F;
  test::icosphere(1, P, F);
  Faces bad = F;
  bad(4, 1) = -1;
  CHECK_THROWS_WITH(count_self_intersections(P, bad), Contains("face 4"));
  Positions nan = P;
  nan(2, 0) = std::nan("");
  CHECK_THROWS_AS(count_self_intersections(nan, F), InvalidInput);
  // A face repeated with the same orientation cannot be part of a manifold surface.
  Faces repeated(F.rows() + 1, 3);
  repeated.topRows(F.rows()) = F;
  repeated.row(F.rows()) = F.row(0);
  CHECK_THROWS_WITH(count_self_intersections(P, repeated), Contains("face " + std::to_string(F.rows())));
}
