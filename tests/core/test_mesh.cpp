#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/scenes.h"
#include "test_util.h"

using namespace msd;

namespace {
// Reference: sum of area-weighted face normals, normalised.
Positions naive_normals(const Positions& P, const Faces& F) {
  Positions N = Positions::Zero(P.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = P.row(F(f, 0)), b = P.row(F(f, 1)), c = P.row(F(f, 2));
    const Vec3 n = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) N.row(F(f, k)) += n;
  }
  for (Eigen::Index v = 0; v < P.rows(); ++v)
    if (N.row(v).norm() > 0) N.row(v).normalize();
  return N;
}

// nf random triangles over nv vertices: repeated and degenerate edges, edges of three or more faces,
// unused vertices.
Faces random_faces(std::mt19937& rng, int nv, int nf) {
  Faces F(nf, 3);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) F(f, k) = static_cast<int>(rng() % nv);
  return F;
}
}  // namespace

TEST_CASE("VertexNormals equals the sum of area-weighted face normals", "[core][mesh]") {
  Positions P;
  Faces F;
  SECTION("open bumpy plane") {
    SceneOptions o;
    o.resolution = 2000;
    const Scene s = make_surface(SceneShape::Plane, o);
    P = s.P;
    F = s.F;
  }
  SECTION("closed sphere far from the origin") {
    test::icosphere(3, P, F);
    P.rowwise() += Eigen::RowVector3d(1e3, -2e3, 5e2);
  }
  SECTION("non-manifold: a fin on an edge and a bow-tie vertex, plus an isolated vertex") {
    P.resize(8, 3);
    P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0.2, 0, 0, 1, -1, 0, 0, 0, -1, -1, 9, 9, 9;
    F.resize(5, 3);
    F << 0, 1, 2,  //
        1, 0, 3,   //
        0, 1, 4,   // third face on edge (0, 1)
        0, 5, 6,   // second fan around vertex 0
        2, 5, 0;
  }
  Positions N;
  VertexNormals(F, static_cast<int>(P.rows())).compute(P, N);
  const Positions ref = naive_normals(P, F);
  CHECK((N - ref).cwiseAbs().maxCoeff() <= 1e-9);
  CHECK(N.allFinite());
  CHECK((vertex_normals(P, F) - N).cwiseAbs().maxCoeff() == 0.0);

  // Only a subset: the same rows bit for bit, the other rows untouched.
  std::vector<int> subset;
  for (int v = 1; v < P.rows(); v += 3) subset.push_back(v);
  Positions part = Positions::Constant(P.rows(), 3, 7.0);
  VertexNormals some(F, static_cast<int>(P.rows()));
  some.restrict_to(subset);
  some.compute(P, part);
  for (int v = 0; v < P.rows(); ++v) {
    const bool in_subset = (v - 1) % 3 == 0 && v >= 1;
    CHECK((part.row(v) - (in_subset ? Positions(N.row(v)) : Positions::Constant(1, 3, 7.0))).cwiseAbs().maxCoeff() ==
          0.0);
  }
  // Fewer than four vertices of a fan length are summed one at a time, all of them four at a time where the
  // CPU has AVX2: the same bits either way.
  VertexNormals one(F, static_cast<int>(P.rows()));
  for (int v = 0; v < std::min<int>(40, static_cast<int>(P.rows())); ++v) {
    one.restrict_to({v});
    Positions single = N;
    single.row(v).setConstant(7.0);
    one.compute(P, single);
    CHECK((single.row(v) - N.row(v)).cwiseAbs().maxCoeff() == 0.0);
  }
  CHECK_THROWS_AS(some.restrict_to({0, static_cast<int>(P.rows())}), InvalidInput);
  CHECK_THROWS_AS(some.restrict_to({2, 1}), InvalidInput);
  Positions again = Positions::Constant(P.rows(), 3, 7.0);
  some.compute(P, again);  // a refused list leaves the subset as it was
  CHECK((again - part).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("all_finite finds a NaN or infinity at any position, the four-wide body and the tail",
          "[core][checks]") {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> x(11, -0.0);
  x[3] = std::numeric_limits<double>::max();
  x[4] = -std::numeric_limits<double>::max();
  x[5] = std::numeric_limits<double>::denorm_min();
  CHECK(all_finite(x.data(), 0));
  for (long n = 1; n <= 11; ++n) {
    CHECK(all_finite(x.data(), n));
    for (long i = 0; i < n; ++i)
      for (const double bad : {nan, inf, -inf}) {
        std::vector<double> y = x;
        y[i] = bad;
        INFO("n " << n << ", bad at " << i);
        CHECK_FALSE(all_finite(y.data(), n));
        CHECK(all_finite(y.data() + i + 1, n - i - 1));  // the rest alone is finite
      }
  }
}

TEST_CASE("first_non_finite_row finds the first NaN or infinity in any column, across parallel chunks",
          "[core][checks]") {
  Positions X = Positions::Random(300000, 3);  // several parallel chunks
  CHECK(first_non_finite_row(X) == -1);
  CHECK(first_non_finite_row(Positions(0, 3)) == -1);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  for (const long row : {0L, 65535L, 65536L, 299999L})
    for (int col = 0; col < 3; ++col)
      for (const double bad : {nan, inf, -inf}) {
        Positions Y = X;
        Y(row, col) = bad;
        Y(row + (row < 299999 ? 1 : -1), 2 - col) = bad;  // a second one, after or before it
        CHECK(first_non_finite_row(Y) == std::min(row, row + (row < 299999 ? 1 : -1)));
      }
  X(7, 1) = 1e308;  // large but finite
  CHECK(first_non_finite_row(X) == -1);
  X(9, 0) = nan;
  CHECK_THROWS_WITH(check_finite(X, "who", "the mesh"), "who: vertex 9 of the mesh has a non-finite coordinate");
}

TEST_CASE("boundary_vertices are the ends of edges used by exactly one face, on any face list", "[core][mesh]") {
  // Against a direct count per undirected edge, on random face lists: repeated and degenerate edges, edges of
  // three or more faces, unused vertices.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 500; ++trial) {
    const int nv = 1 + static_cast<int>(rng() % 25), nf = static_cast<int>(rng() % 40);
    const Faces F = random_faces(rng, nv, nf);
    std::map<std::pair<int, int>, int> uses;
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = F(f, k), b = F(f, (k + 1) % 3);
        ++uses[{std::min(a, b), std::max(a, b)}];
      }
    std::vector<char> expected(nv, 0);
    for (const auto& [edge, count] : uses)
      if (count == 1) expected[edge.first] = expected[edge.second] = 1;
    std::vector<int> want;
    for (int v = 0; v < nv; ++v)
      if (expected[v]) want.push_back(v);
    INFO("trial " << trial);
    CHECK(boundary_vertices(F, nv) == want);
  }
  const Scene plane = make_scene("lift", SceneOptions{});
  const auto side = static_cast<size_t>(std::lround(std::sqrt(static_cast<double>(plane.P.rows()))));
  REQUIRE(side * side == static_cast<size_t>(plane.P.rows()));  // the bumpy plane is a square grid
  CHECK(boundary_vertices(plane.F, static_cast<int>(plane.P.rows())).size() == 4 * (side - 1));
}

TEST_CASE("vertex_components numbers the pieces in the order of their first face, -1 for unused vertices",
          "[core][mesh]") {
  // Against a breadth-first search over the face edges, on random face lists (repeated and degenerate
  // faces, unused vertices).
  std::mt19937 rng(11);
  for (int trial = 0; trial < 500; ++trial) {
    const int nv = 1 + static_cast<int>(rng() % 30), nf = static_cast<int>(rng() % 20);
    const Faces F = random_faces(rng, nv, nf);
    const VertexAdjacency adjacency = vertex_adjacency(F, nv);
    std::vector<int> want(nv, -1);
    int count = 0;
    for (int f = 0; f < nf; ++f) {
      if (want[F(f, 0)] >= 0) continue;
      std::vector<int> queue = {F(f, 0)};
      want[F(f, 0)] = count;
      for (size_t i = 0; i < queue.size(); ++i)
        for (const int* n = adjacency.begin(queue[i]); n != adjacency.end(queue[i]); ++n)
          if (want[*n] < 0) want[*n] = count, queue.push_back(*n);
      ++count;
    }
    INFO("trial " << trial);
    CHECK(vertex_components(F, nv) == want);
  }
}

TEST_CASE("extent_outlier_warning: a few strays far in edge lengths, not a coarse cone's apex", "[core][mesh]") {
  Positions P;
  Faces F;
  std::vector<bool> interior;
  test::jittered_grid(40, 0.1, P, F, interior);  // 1600 vertices, edges about 1/39 long
  CHECK(extent_outlier_warning(P, F, "t").empty());
  // Two strays on the same side (one trimmed coordinate per end missed the second), 1000 away.
  Positions strays = P;
  strays(100, 0) += 1000;
  strays(900, 0) += 1001;
  const std::string w = extent_outlier_warning(strays, F, "t");
  CHECK_THAT(w, Catch::Contains(kOutlierWarning) && Catch::Contains("vertex 900 lies"));
  CHECK_FALSE(extent_outlier_warning(strays, Faces(), "t").empty());  // a point cloud: the box alone decides
  // A stray that no face uses is named as such (a leftover of the file, not part of the surface).
  Positions leftover(P.rows() + 1, 3);
  leftover << P, Eigen::RowVector3d(5000, 0, 0);
  CHECK_THAT(extent_outlier_warning(leftover, F, "t"),
             Catch::Contains("vertex " + std::to_string(P.rows()) + ", which no face uses, lies"));
  // A cone of 32 ring vertices and an apex 30 away: the apex sets the box, but its edges are as long.
  Positions cone(34, 3);
  Faces sides(64, 3);
  for (int i = 0; i < 32; ++i) {
    cone.row(i) = Vec3(0, std::cos(i * 2 * std::acos(-1.0) / 32), std::sin(i * 2 * std::acos(-1.0) / 32)).transpose();
    sides.row(i) << i, (i + 1) % 32, 32;       // to the apex
    sides.row(32 + i) << (i + 1) % 32, i, 33;  // the base's cap
  }
  cone.row(32) = Vec3(30, 0, 0).transpose();
  cone.row(33) = Vec3(0, 0, 0).transpose();
  CHECK(extent_outlier_warning(cone, sides, "t").empty());
}
