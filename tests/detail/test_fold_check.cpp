#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "msdeform/core/errors.h"
#include "msdeform/core/region.h"
#include "msdeform/core/scenes.h"
#include "msdeform/detail/fold_check.h"
#include "msdeform/detail/normal_displacements.h"
#include "test_util.h"

using namespace msd;

TEST_CASE("fold check: a bend tighter than the bumps folds normal displacements, a gentle one does not",
          "[detail][fold]") {
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Plane, o);
  NormalDisplacements normal;
  normal.encode(s.P, s.F, s.smooth, s.F);
  FoldCheck folds;
  folds.prepare(s.P, s.F, s.smooth, s.F);
  Positions out;
  normal.reconstruct(s.smooth, out);
  CHECK(folds.count(out, s.smooth) == 0);
  // The bumps on the concave side of an arc of radius R (seed 9.3.3: they cross once 1/R > 1/h).
  for (const double R : {0.5 * s.bump_height, 10 * s.bump_height}) {
    const double theta = 120 * M_PI / 180;
    const test::ArcBend bend{0.45 - R * theta / 2, R, theta};
    const Positions B1 = bend(s.smooth);
    normal.reconstruct(B1, out);
    const int n = folds.count(out, B1);
    INFO("R = " << R << ": " << n << " folded triangles");
    if (R < s.bump_height)
      CHECK(n > 0);
    else
      CHECK(n == 0);
  }
  // A rigid motion of S' and B' together folds nothing; a mirror of S' alone turns every triangle.
  const Mat3 R = Eigen::AngleAxisd(2.0, Vec3(1, 1, 0).normalized()).toRotationMatrix();
  CHECK(folds.count(test::rigid_motion(s.P, R, Vec3(3, 0, 1)), test::rigid_motion(s.smooth, R, Vec3(3, 0, 1))) == 0);
  Positions mirrored = s.P;
  mirrored.col(0) *= -1;  // a reflection: the triangles of S' face down while the base faces up
  CHECK(folds.count(mirrored, s.smooth) == static_cast<int>(s.F.rows()));
}

TEST_CASE("fold check: other connectivity, and misuse", "[detail][fold]") {
  Positions P;
  Faces F;
  test::icosphere(3, P, F);
  Positions Pc;
  Faces Fc;
  test::icosphere(1, Pc, Fc);
  FoldCheck folds;
  CHECK_THROWS_AS(folds.count(P, Pc), UsageError);
  folds.prepare(1.1 * P, F, Pc, Fc);
  CHECK(folds.count(1.1 * P, Pc) == 0);
  Positions mirrored = 1.1 * P;
  mirrored.col(0) *= -1;  // turns the triangles facing ±x against their base triangles
  CHECK(folds.count(mirrored, Pc) > static_cast<int>(F.rows()) / 4);
  CHECK_THROWS_AS(folds.count(P, P), UsageError);
}

TEST_CASE("fold check: a zero-area triangle at rest is not counted, a real turn is", "[detail][fold]") {
  // Triangle 0 of S is a sliver of relative area 1e-15 (its orientation at rest is rounding noise);
  // triangle 1 is sound. The base has both sound and facing +z.
  Positions S(4, 3), B(4, 3);
  S << 0, 0, 0, 1, 0, 0, 0.5, -1e-15, 0, 0.5, 0.5, 0;
  B = S;
  B.row(2) << 0.5, 0.3, 0;
  Faces F(2, 3);
  F << 0, 1, 2, 0, 1, 3;
  FoldCheck folds;
  folds.prepare(S, F, B, F);
  Positions moved = S;
  moved(2, 1) = 1e-15;  // the sliver's noise flips sign: not a fold
  CHECK(folds.count(moved, B) == 0);
  moved.row(3) << 0.5, -0.5, 0;  // triangle 1 turns over its base
  CHECK(folds.count(moved, B) == 1);
}

TEST_CASE("fold check: a needle of S turning over is not a fold of the details", "[detail][fold]") {
  // Triangle 0 of S is a needle 1e-8 of its length high (beyond the 1e-14 area rule, within the cotan
  // clamp's 1e5): at the origin its flip counted as a fold with the advice to lower the detail scale, and
  // the same mesh moved 1e6 away counted none.
  Positions S(4, 3);
  S << 0, 0, 0, 1, 0, 0, 0.5, 1e-8, 0, 0.5, -0.5, 0;
  Faces F(2, 3);
  F << 0, 1, 2, 1, 0, 3;
  for (const double offset : {0.0, 1e6}) {
    Positions P = S, B = S;
    P.rowwise() += Eigen::RowVector3d(offset, 0.5 * offset, -offset);
    B.rowwise() += Eigen::RowVector3d(offset, 0.5 * offset, -offset);
    B.row(2) = P.row(2) + Eigen::RowVector3d(0, 0.2, 0);  // a sound base triangle under the needle
    FoldCheck folds;
    folds.prepare(P, F, B, F);
    Positions moved = P;
    moved(2, 1) -= 2e-8;  // the needle turns over
    CHECK(folds.count(moved, B) == 0);
    moved(3, 1) += 1;  // triangle 1 turns over its base
    CHECK(folds.count(moved, B) == 1);
  }
}

TEST_CASE("fold check: right at any finite size (products of normals beyond 1e+-308)", "[detail][fold]") {
  SceneOptions o;
  o.resolution = 2000;
  const Scene s = make_surface(SceneShape::Plane, o);
  for (const double scale : {1e160, 1e-100}) {
    INFO("scale " << scale);
    const Positions S = scale * s.P, B = scale * s.smooth;
    FoldCheck folds;
    folds.prepare(S, s.F, B, s.F);
    CHECK(folds.count(S, B) == 0);
    Positions mirrored = S;
    mirrored.col(0) *= -1;
    CHECK(folds.count(mirrored, B) == static_cast<int>(s.F.rows()));
  }
}

TEST_CASE("fold check: rigidly placed triangles are skipped only where the map keeps their sign",
          "[detail][fold]") {
  // One triangle, all three corners in handle 0. Its normal in S is (1, 1, 0), its base triangle's
  // (1, -0.9, 0): n_S · n_B = 0.1 > 0 at rest.
  Positions S(3, 3), B(3, 3);
  S << 0, 0, 0, 0, 0, 1, 1, -1, 0;
  B << 0, 0, 0, 0.9, 1, 0, 0, 0, 1;
  Faces F(1, 3);
  F << 0, 1, 2;
  FoldCheck folds;
  folds.prepare(S, F, B, F);
  const Region handle(3, Region::kFirstHandle);
  folds.set_placements(handle, handle);
  const auto moved = [](const Positions& X, const Mat4& T) {
    Positions Y(X.rows(), 3);
    for (Eigen::Index i = 0; i < X.rows(); ++i) Y.row(i) = transform_point(T, Vec3(X.row(i)));
    return Y;
  };
  // A rotation with a uniform scale and a translation: skipped, and indeed not folded.
  Mat4 similarity = Mat4::Identity();
  similarity.topLeftCorner<3, 3>() =
      2.5 * Eigen::AngleAxisd(1.0, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  similarity.topRightCorner<3, 1>() = Vec3(4, -1, 2);
  CHECK(folds.skipped({similarity}) == 1);
  CHECK(folds.count(moved(S, similarity), moved(B, similarity), {similarity}) == 0);
  CHECK(folds.count(moved(S, similarity), moved(B, similarity)) == 0);
  // A rotation written with 6 digits, as in the survey's cylinder.def (AᵀA = I to 3e-7): still skipped;
  // a stretch of 1e-5 is not.
  Mat4 written = Mat4::Identity();
  written.topLeftCorner<3, 3>() << -0.5, 0, -0.866025, 0, 1, 0, 0.866025, 0, -0.5;
  CHECK(folds.skipped({written}) == 1);
  CHECK(folds.count(moved(S, written), moved(B, written), {written}) == 0);
  Mat4 slightly = Mat4::Identity();
  slightly(1, 1) = 1 + 1e-5;
  CHECK(folds.skipped({slightly}) == 0);
  // Stretching x tenfold turns the normals by cof(A) = diag(1, 10, 10): (1, 10, 0) · (1, -9, 0) < 0, a fold
  // that a skip of every placed triangle would miss.
  Mat4 stretch = Mat4::Identity();
  stretch(0, 0) = 10;
  CHECK(folds.skipped({stretch}) == 0);
  CHECK(folds.count(moved(S, stretch), moved(B, stretch), {stretch}) == 1);
  CHECK(folds.count(moved(S, stretch), moved(B, stretch)) == 1);
  // Corners with different roles, in S or in B, are always counted.
  Region mixed = handle;
  mixed.set_free({2});
  folds.set_placements(handle, mixed);
  CHECK(folds.skipped({similarity}) == 0);
  folds.set_placements(mixed, handle);
  CHECK(folds.skipped({similarity}) == 0);
  // Fixed corners are skipped whatever the transforms; no transforms: nothing is skipped.
  const Region fixed(3, Region::kFixed);
  folds.set_placements(fixed, fixed);
  CHECK(folds.skipped({stretch}) == 1);
  CHECK(folds.skipped({}) == 0);
  CHECK(folds.count(S, B, {stretch}) == 0);
  CHECK_THROWS_AS(folds.set_placements(Region(4), fixed), UsageError);
}

TEST_CASE("fold check: the count equals a triangle-by-triangle count on a crumpled surface",
          "[detail][fold]") {
  // Random moves of S' fold about a quarter of the triangles, scattered: the branch-free pass over the stored
  // triangles must equal the sign test written out per triangle.
  const auto reference_count = [](const Positions& S, const Positions& S1, const Faces& Fs, const Positions& B,
                                  const Positions& B1, const Faces& Fb, const std::vector<int>& base_of) {
    const auto normal = [](const Positions& X, const Faces& F, long f) {
      const Vec3 a = X.row(F(f, 0)), b = X.row(F(f, 1)), c = X.row(F(f, 2));
      return Vec3((b - a).cross(c - a));
    };
    int folded = 0;
    for (Eigen::Index f = 0; f < Fs.rows(); ++f) {
      const long g = base_of.empty() ? f : base_of[f];
      folded += normal(S, Fs, f).dot(normal(B, Fb, g)) * normal(S1, Fs, f).dot(normal(B1, Fb, g)) < 0;
    }
    return folded;
  };
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0, 1);
  const auto crumple = [&](Positions X, double amount) {
    for (Eigen::Index i = 0; i < X.rows(); ++i)
      for (int c = 0; c < 3; ++c) X(i, c) += amount * noise(random);
    return X;
  };
  SECTION("S and B share their triangles") {
    SceneOptions o;
    o.resolution = 3000;
    const Scene s = make_surface(SceneShape::Plane, o);
    FoldCheck folds;
    folds.prepare(s.P, s.F, s.smooth, s.F);
    const double edge = 1.0 / std::sqrt(double(s.P.rows()));
    const Positions S1 = crumple(s.P, 0.6 * edge), B1 = crumple(s.smooth, 0.05 * edge);
    const int expected = reference_count(s.P, S1, s.F, s.smooth, B1, s.F, {});
    INFO(expected << " of " << s.F.rows() << " triangles folded");
    CHECK(expected > s.F.rows() / 10);
    CHECK(folds.count(S1, B1) == expected);
  }
  SECTION("S finer than B") {
    // A flat coarse base (every base triangle faces +z, so the pairing FoldCheck picks does not matter),
    // turned rigidly with S'.
    SceneOptions fine, coarse;
    fine.resolution = 3000;
    coarse.resolution = 200;
    const Scene s = make_surface(SceneShape::Plane, fine), b = make_surface(SceneShape::Plane, coarse);
    FoldCheck folds;
    folds.prepare(s.P, s.F, b.smooth, b.F);
    const double edge = 1.0 / std::sqrt(double(s.P.rows()));
    const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, -2, 1).normalized()).toRotationMatrix();
    const Positions S1 = test::rigid_motion(crumple(s.P, 0.6 * edge), R, Vec3(1, 2, 3));
    const Positions B1 = test::rigid_motion(b.smooth, R, Vec3(1, 2, 3));
    const std::vector<int> any_base(s.F.rows(), 0);
    const int expected = reference_count(s.P, S1, s.F, b.smooth, B1, b.F, any_base);
    INFO(expected << " of " << s.F.rows() << " triangles folded");
    CHECK(expected > s.F.rows() / 10);
    CHECK(folds.count(S1, B1) == expected);
  }
}
