#include <catch2/catch.hpp>

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
