#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "msdeform/core/errors.h"
#include "msdeform/core/surface_check.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

// Whether every edge shared by two faces is run through in opposite directions by them.
bool consistently_oriented(const Faces& F) {
  std::map<std::pair<int, int>, int> directed;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (++directed[{F(f, k), F(f, (k + 1) % 3)}] > 1) return false;
  return true;
}

// A closed band of n quads (two triangles each) between a lower and an upper ring; with a half twist
// the last quad joins the first with its rows swapped: a Moebius strip.
void band(int n, bool twist, Positions& P, Faces& F) {
  P.resize(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * i / n, w = twist ? 0.5 * t : 0.0;
    const Vec3 centre(std::cos(t), std::sin(t), 0), radial = centre, up(0, 0, 1);
    const Vec3 across = std::cos(w) * up + std::sin(w) * radial;
    P.row(2 * i) = centre - 0.2 * across;
    P.row(2 * i + 1) = centre + 0.2 * across;
  }
  F.resize(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    int a = 2 * i, b = 2 * i + 1, c = 2 * ((i + 1) % n), d = c + 1;
    if (twist && i == n - 1) std::swap(c, d);
    F.row(2 * i) << a, c, d;
    F.row(2 * i + 1) << a, d, b;
  }
}

}  // namespace

TEST_CASE("two triangles wound against each other: one is turned over", "[core][surface]") {
  Positions P(4, 3);
  P << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  Faces F(2, 3);
  F << 0, 1, 2, 0, 3, 2;
  const SurfaceCheck check = check_surface(P, F);
  CHECK(check.flipped_faces == 1);
  CHECK(check.problem().empty());
  CHECK(check.components == 1);
  CHECK(check.edges == 5);
  CHECK(check.boundary_edges == 4);
  CHECK(consistently_oriented(F));
  // The tie keeps the first face's winding: both normals now point along +z.
  CHECK(F.row(0) == Eigen::RowVector3i(0, 1, 2));
  CHECK(F.row(1) == Eigen::RowVector3i(0, 2, 3));
}

TEST_CASE("a closed surface with a third of its faces turned over is restored exactly", "[core][surface]") {
  Positions P;
  Faces original;
  test::icosphere(3, P, original);
  Faces F = original;
  std::mt19937 rng(5);
  int turned = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    if (rng() % 3 == 0) std::swap(F(f, 1), F(f, 2)), ++turned;
  if (F(0, 1) != original(0, 1)) std::swap(F(0, 1), F(0, 2)), --turned;  // the first face sets the winding
  REQUIRE(turned > 0);
  const SurfaceCheck check = check_surface(P, F);
  CHECK(check.flipped_faces == turned);
  CHECK(F == original);
  CHECK(check.problem().empty());
  CHECK(check.boundary_edges == 0);
  CHECK(check.vertices - check.edges + check.faces == 2);
}

TEST_CASE("the smaller set of faces is turned over, whichever face comes first", "[core][surface]") {
  Positions P;
  Faces original;
  test::icosphere(2, P, original);
  Faces F = original;
  for (Eigen::Index f = 0; f < F.rows(); f += 4) std::swap(F(f, 1), F(f, 2));  // face 0 among them
  const SurfaceCheck check = check_surface(P, F);
  CHECK(check.flipped_faces == (F.rows() + 3) / 4);
  CHECK(F == original);
}

TEST_CASE("a third face on an edge is a non-manifold edge, named by its vertex and face ids",
          "[core][surface]") {
  Positions P(5, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1;
  Faces F(3, 3);
  F << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  const SurfaceCheck check = check_surface(P, F);
  REQUIRE(check.nonmanifold_edges.size() == 1);
  CHECK(check.nonmanifold_edges[0].a == 0);
  CHECK(check.nonmanifold_edges[0].b == 1);
  CHECK(check.nonmanifold_edges[0].faces == std::vector<int>{0, 1, 2});
  CHECK(check.nonmanifold_vertices.empty());
  CHECK_THAT(check.problem(), Contains("edge (0, 1)") && Contains("3 faces (0, 1, 2)"));
  CHECK(check.components == 1);
}

TEST_CASE("a Moebius strip is reported non-orientable and left as it was", "[core][surface]") {
  Positions P;
  Faces F;
  band(12, /*twist=*/false, P, F);
  Faces ring = F;
  const SurfaceCheck good = check_surface(P, ring);
  CHECK(good.problem().empty());
  CHECK(good.flipped_faces == 0);
  CHECK(good.boundary_edges == 24);

  band(12, /*twist=*/true, P, F);
  const Faces before = F;
  const SurfaceCheck check = check_surface(P, F);
  CHECK(check.nonmanifold_edges.empty());
  CHECK(check.nonmanifold_vertices.empty());
  REQUIRE(check.nonorientable_faces.size() == 1);
  CHECK(check.nonorientable_faces[0] == 0);
  CHECK(check.nonorientable_components == std::vector<int>{0});
  CHECK(check.flipped_faces == 0);
  CHECK(F == before);
  CHECK_THAT(check.problem(), Contains("component 0") && Contains("not orientable"));
  CHECK(check.boundary_edges == 24);  // one boundary curve twice as long
}

TEST_CASE("two cones touching at their tips: a non-manifold vertex", "[core][surface]") {
  const int n = 8;
  Positions P(2 * n + 1, 3);
  P.row(0) << 0, 0, 0;
  Faces F(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * i / n;
    P.row(1 + i) << std::cos(t), std::sin(t), 1;
    P.row(1 + n + i) << std::cos(t), std::sin(t), -1;
    F.row(i) << 0, 1 + i, 1 + (i + 1) % n;
    F.row(n + i) << 0, 1 + n + (i + 1) % n, 1 + n + i;
  }
  const SurfaceCheck check = check_surface(P, F);
  CHECK(check.nonmanifold_vertices == std::vector<int>{0});
  CHECK(check.nonmanifold_edges.empty());
  CHECK(check.components == 1);
  CHECK_THAT(check.problem(), Contains("vertex 0") && Contains("non-manifold vertex"));
}

TEST_CASE("point clouds, unreferenced vertices, components, duplicates and repeated indices",
          "[core][surface]") {
  Positions P(7, 3);
  P.setRandom();
  Faces none(0, 3);
  const SurfaceCheck cloud = check_surface(P, none);
  CHECK(cloud.unreferenced_vertices == 7);
  CHECK(cloud.components == 0);
  CHECK(cloud.problem() == "no faces (a point cloud)");

  Faces two(2, 3);
  two << 0, 1, 2, 3, 4, 5;
  const SurfaceCheck pieces = check_surface(P, two);
  CHECK(pieces.components == 2);
  CHECK(pieces.unreferenced_vertices == 1);
  CHECK(pieces.problem().empty());

  Faces dup(3, 3);
  dup << 0, 1, 2, 3, 4, 5, 2, 1, 0;
  const SurfaceCheck d = check_surface(P, dup);
  REQUIRE(d.duplicate_faces.size() == 1);
  CHECK(d.duplicate_faces[0] == std::make_pair(0, 2));
  CHECK_THAT(d.problem(), Contains("faces 0 and 2"));

  Faces repeated(2, 3);
  repeated << 0, 1, 2, 3, 3, 4;
  const SurfaceCheck r = check_surface(P, repeated);
  CHECK(r.degenerate_faces == std::vector<int>{1});
  CHECK_THAT(r.problem(), Contains("face 1 repeats"));

  Faces bad(1, 3);
  bad << 0, 1, 7;
  CHECK_THROWS_WITH(check_surface(P, bad), Contains("face 0") && Contains("index 7 out of range"));
}

TEST_CASE("check_surface orients a million scrambled faces", "[core][surface]") {
  Positions P;
  Faces original;
  std::vector<bool> interior;
  test::jittered_grid(707, 0.0, P, original, interior);  // 1,000,000 faces
  Faces F = original;
  int turned = 0;
  for (Eigen::Index f = 1; f < F.rows(); f += 3) std::swap(F(f, 1), F(f, 2)), ++turned;
  const SurfaceCheck check = check_surface(P, F);
  CHECK(F == original);
  CHECK(check.problem().empty());
  CHECK(check.flipped_faces == turned);
}
