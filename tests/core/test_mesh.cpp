#include <catch2/catch.hpp>

#include <limits>

#include "msdeform/core/checks.h"
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
