#include <catch2/catch.hpp>

#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/scenes.h"
#include "msdeform/decomposition/detail_check.h"
#include "msdeform/decomposition/low_pass.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

TEST_CASE("low-pass base: the automatic scale removes the bumps and keeps the plane", "[decomposition][low-pass]") {
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Plane, o);
  LowPassReport report;
  const Positions B = low_pass_base(s.P, s.F, {}, &report);
  INFO("detail scale " << report.detail_scale << ", max height " << report.check.max_height);
  CHECK(report.no_layer_reason.empty());
  CHECK(report.automatic);
  CHECK(report.detail_scale > 0.1);  // longer than the bumps (on a 0.1 lattice)
  CHECK(report.check.fold_ratio_p999 <= 0.5);
  // Away from the outline, B lies within 15 % of the bump height of the analytic smooth plane, and the
  // detail heights are the bumps.
  double off_base = 0, off_detail = 0;
  for (int v = 0; v < s.P.rows(); ++v) {
    if (std::min({s.P(v, 0), s.P(v, 1), 1 - s.P(v, 0), 1 - s.P(v, 1)}) < 0.1) continue;
    off_base = std::max(off_base, std::abs(B(v, 2) - s.smooth(v, 2) - s.heights.mean()));
    off_detail = std::max(off_detail, std::abs((s.P(v, 2) - B(v, 2)) - (s.heights[v] - s.heights.mean())));
  }
  CHECK(off_base <= 0.15 * s.bump_height);
  CHECK(off_detail <= 0.15 * s.bump_height);
}

TEST_CASE("low-pass base: a cylinder keeps its radius (fairing shrank it to a thread)", "[decomposition][low-pass]") {
  // Closed tube of radius 1 and length 12 along z, 48 × 97 vertices.
  const int around = 48, along = 97;
  Positions P(around * along, 3);
  Faces F(2 * around * (along - 1), 3);
  for (int j = 0; j < along; ++j)
    for (int i = 0; i < around; ++i) {
      const double t = 2 * M_PI * i / around;
      P.row(j * around + i) << std::cos(t), std::sin(t), 12.0 * j / (along - 1);
    }
  int f = 0;
  for (int j = 0; j + 1 < along; ++j)
    for (int i = 0; i < around; ++i) {
      const int a = j * around + i, b = j * around + (i + 1) % around, c = a + around, d = b + around;
      F.row(f++) << a, b, d;
      F.row(f++) << a, d, c;
    }
  LowPassReport report;
  const Positions B = low_pass_base(P, F, {}, &report);
  INFO("detail scale " << report.detail_scale);
  // No detail layer on a smooth tube, and the reason is the one the search stopped at (the break test's
  // camel stopped at a fold ratio of 0.526 and was told the heights "grow with every scale tried").
  CHECK(report.detail_scale == 0);
  const LowPassCandidate& last = report.candidates.back();
  if (last.area_ratio < 0.5 || last.check.fold_ratio_p999 > 0.5)
    CHECK_THAT(report.no_layer_reason,
               Catch::Matchers::StartsWith("the candidate scale " + format_number(last.detail_scale) +
                                           " already removes shape ("));
  else
    CHECK_THAT(report.no_layer_reason,
               Catch::Matchers::StartsWith("the detail heights grow with every scale tried"));
  for (int v = 0; v < P.rows(); ++v) {
    if (P(v, 2) < 2 || P(v, 2) > 10) continue;  // the open ends may move a little
    CHECK(std::hypot(B(v, 0), B(v, 1)) == Approx(1).epsilon(0.02));
  }
}

TEST_CASE("low-pass base: moves with S under rigid motions and scaling", "[decomposition][low-pass]") {
  SceneOptions o;
  o.resolution = 3000;
  const Scene s = make_surface(SceneShape::Bar, o);
  LowPassReport r0, r1;
  const Positions B0 = low_pass_base(s.P, s.F, {}, &r0);
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const double scale = 250;
  const Vec3 t(1000, -2000, 500);
  const Positions S1 = test::rigid_motion(s.P * scale, R, t);
  const Positions B1 = low_pass_base(S1, s.F, {}, &r1);
  CHECK(r1.detail_scale == Approx(scale * r0.detail_scale).epsilon(1e-9));
  CHECK(test::max_row_distance(B1, test::rigid_motion(B0 * scale, R, t)) <= 1e-8 * bounding_box_diagonal(S1));
}

TEST_CASE("low-pass base: a given scale is used as is, bad options are refused", "[decomposition][low-pass]") {
  SceneOptions o;
  o.resolution = 3000;
  const Scene s = make_surface(SceneShape::Plane, o);
  LowPassOptions options;
  options.detail_scale = 0.05;
  LowPassReport report;
  low_pass_base(s.P, s.F, options, &report);
  CHECK_FALSE(report.automatic);
  CHECK(report.detail_scale == 0.05);
  CHECK(report.candidates.empty());
  options.detail_scale = -1;
  CHECK_THROWS_AS(low_pass_base(s.P, s.F, options), InvalidInput);
  options.detail_scale = 1e100;  // (L/2π)⁴ overflows: refused by its cause, not as a non-finite solve
  CHECK_THROWS_WITH(low_pass_base(s.P, s.F, options), Contains("1e+100") && Contains("diameter"));
  options.detail_scale = 0;
  options.max_fold_ratio = 0;
  CHECK_THROWS_WITH(low_pass_base(s.P, s.F, options), Contains("max_fold_ratio"));
}

TEST_CASE("low-pass base: a given scale far below the edge length is no detail layer, and says so",
          "[decomposition][low-pass]") {
  // The bumpy plane at 1e-3 of its mean edge length: the base moves by rounding only (a break test: the
  // details came out at 1e-11 of the mesh, the edit was the base deformer's alone, and nothing said so).
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_scene("lift", o);
  LowPassOptions options;
  options.detail_scale = 1e-3 * mean_edge_length(s.P, s.F);
  LowPassReport report;
  const Positions B = low_pass_base(s.P, s.F, options, &report);
  CHECK_FALSE(report.automatic);
  CHECK_THAT(report.no_layer_reason, Contains("removes nothing measurable") && Contains("mean edge length"));
  CHECK(B == s.P);
  CHECK_FALSE(report.has_detail_layer());
  CHECK_THAT(report.no_layer_remedy(), Contains("a larger --detail-scale"));
  options.detail_scale = 0.3;  // a scale that removes the bumps is a layer
  low_pass_base(s.P, s.F, options, &report);
  CHECK(report.no_layer_reason.empty());
  CHECK(report.has_detail_layer());
}

TEST_CASE("low-pass base: a mesh whose vertices all lie on its boundary is its own base", "[decomposition][low-pass]") {
  // A strip of 10 quads: the boundary keeps its place, so nothing is left to smooth.
  Positions P(22, 3);
  Faces F(20, 3);
  for (int i = 0; i <= 10; ++i) P.row(2 * i) << i, 0, 0.1 * (i % 2), P.row(2 * i + 1) << i, 1, 0;
  for (int i = 0; i < 10; ++i) F.row(2 * i) << 2 * i, 2 * i + 2, 2 * i + 3, F.row(2 * i + 1) << 2 * i, 2 * i + 3, 2 * i + 1;
  Positions Q(24, 3);  // the same with two vertices no face uses
  Q << P, 5, 5, 1, 6, 5, 1;
  for (const Positions& X : {P, Q})
    for (const double scale : {0.0, 0.5}) {
      LowPassOptions options;
      options.detail_scale = scale;
      LowPassReport report;
      CHECK(low_pass_base(X, F, options, &report) == X);
      CHECK(report.detail_scale == 0);
      CHECK(report.all_boundary);
      CHECK(report.no_layer_reason ==
            "every vertex lies on the mesh boundary, which the low-pass keeps in place");
    }
}

TEST_CASE("low-pass base: sizes outside 1e-70..1e70 and meshes without extent are refused", "[decomposition][low-pass]") {
  SceneOptions o;
  o.resolution = 500;
  const Scene s = make_surface(SceneShape::Plane, o);
  // 1e160 overflowed the squared areas (the factorisation then never finished); one point gave a base.
  CHECK_THROWS_WITH(low_pass_base(1e160 * s.P, s.F), Contains("coordinates too large") && Contains("1e+160"));
  CHECK_THROWS_WITH(low_pass_base(1e-100 * s.P, s.F), Contains("coordinates too small"));
  CHECK_THROWS_WITH(low_pass_base(Positions::Zero(s.P.rows(), 3), s.F), Contains("no extent"));
}

TEST_CASE("detail check: the fold ratio is height over curvature radius on a sphere", "[decomposition][low-pass]") {
  Positions P;
  Faces F;
  test::icosphere(4, P, F);
  const Positions B = 2.0 * P;  // radius 2, outward normals
  // Details pointing inwards by 0.5 (S on radius 1.5): ratio 0.25; by 3 (through the centre): it folds.
  const DetailCheck in = check_details(1.5 * P, B, F);
  CHECK(in.max_fold_ratio == Approx(0.25).epsilon(0.1));  // exact with exact normals; area-weighted ones deviate
  CHECK(in.min_curvature_radius == Approx(2).epsilon(0.1));
  CHECK(in.max_height == Approx(0.5));
  CHECK(in.folding_vertices == 0);
  const DetailCheck through = check_details(-1.0 * P, B, F);
  CHECK(through.max_fold_ratio == Approx(1.5).epsilon(0.1));
  CHECK(through.folding_vertices == P.rows());
  // Outward details never fold on a convex base.
  CHECK(check_details(3.0 * P, B, F).max_fold_ratio == 0);
}

TEST_CASE("low-pass cache: the same mesh and options give the stored base, any change computes anew",
          "[decomposition][low-pass]") {
  SceneOptions o;
  o.resolution = 3000;
  const Scene s = make_scene("lift", o);
  LowPassOptions options;  // the automatic scale: several candidates
  LowPassReport fresh_report, report;
  const Positions fresh = low_pass_base(s.P, s.F, options, &fresh_report);
  REQUIRE(fresh_report.detail_scale > 0);
  LowPassCache cache;
  CHECK(cache.base(s.P, s.F, options, &report) == fresh);
  CHECK_FALSE(report.reused);
  CHECK(cache.base(s.P, s.F, options, &report) == fresh);
  CHECK(report.reused);
  CHECK(report.detail_scale == fresh_report.detail_scale);
  CHECK(report.candidates.size() == fresh_report.candidates.size());

  // One coordinate, the faces, or an option changed: a miss, and the base of the new input.
  Positions moved = s.P;
  moved(17, 2) += 1e-3;
  CHECK(cache.base(moved, s.F, options, &report) == low_pass_base(moved, s.F, options));
  CHECK_FALSE(report.reused);
  Faces flipped = s.F;
  std::swap(flipped(0, 1), flipped(0, 2));
  CHECK(cache.base(moved, flipped, options, &report) == low_pass_base(moved, flipped, options));
  CHECK_FALSE(report.reused);
  LowPassOptions given = options;
  given.detail_scale = 0.2;
  CHECK(cache.base(moved, flipped, given, &report) == low_pass_base(moved, flipped, given));
  CHECK_FALSE(report.reused);
  CHECK(report.detail_scale == 0.2);

  // A failed call keeps the stored base.
  given.detail_scale = -1;
  CHECK_THROWS_AS(cache.base(moved, flipped, given), InvalidInput);
  given.detail_scale = 0.2;
  cache.base(moved, flipped, given, &report);
  CHECK(report.reused);
}

TEST_CASE("low-pass base: a scale that makes the system singular is named as too large, not blamed on a vertex",
          "[decomposition][low-pass]") {
  // CGAL's homer at L = 1000 (about 500 diameters): "singular near vertex 4929 (degenerate faces around it?)".
  const Mesh homer = load_mesh(test::cgal_mesh("homer.off"));
  LowPassOptions options;
  options.detail_scale = 1000;
  try {
    low_pass_base(positions(homer), faces(homer), options);
    SUCCEED("factored at this scale on this machine's BLAS");
  } catch (const SolverError& e) {
    CHECK_THAT(e.what(), Contains("times the mesh's diameter") && !Contains("degenerate faces"));
  }
}

TEST_CASE(
    "low-pass base: conjugate gradients give the factorisation's base on planes, tubes and closed scans",
    "[decomposition][low-pass]") {
  struct Case {
    std::string name;
    Positions P;
    Faces F;
    double detail_scale;
  };
  std::vector<Case> cases;
  SceneOptions o;
  o.resolution = 6000;
  for (const char* name : {"lift", "bend120"}) {
    const Scene s = make_scene(name, o);
    cases.push_back({name, s.P, s.F, 0.3});
  }
  const Mesh armadillo = load_mesh(test::cgal_mesh("armadillo.off"));  // closed: no known vertex
  cases.push_back({"armadillo", positions(armadillo), faces(armadillo), 8});
  for (const Case& c : cases) {
    INFO(c.name);
    LowPassOptions options;
    options.detail_scale = c.detail_scale;
    options.solver = LowPassSolver::Factorisation;
    LowPassReport factored, iterated;
    const Positions B = low_pass_base(c.P, c.F, options, &factored);
    options.solver = LowPassSolver::ConjugateGradients;
    const Positions B_cg = low_pass_base(c.P, c.F, options, &iterated);
    CHECK(factored.iterations == 0);
    CHECK(iterated.iterations >= 5);  // κ ≤ 2: 15–17 to 1e-13
    CHECK(iterated.iterations <= 25);
    CHECK(test::max_row_distance(B, B_cg) <= 1e-9 * bounding_box_diagonal(c.P));
  }
  // The automatic choice picks the same scale either way.
  const Scene plane = make_scene("lift", o);
  LowPassOptions automatic;
  LowPassReport factored, iterated;
  automatic.solver = LowPassSolver::Factorisation;
  low_pass_base(plane.P, plane.F, automatic, &factored);
  automatic.solver = LowPassSolver::ConjugateGradients;
  low_pass_base(plane.P, plane.F, automatic, &iterated);
  CHECK(factored.detail_scale > 0);
  CHECK(iterated.detail_scale == factored.detail_scale);
}

TEST_CASE("low-pass base: detail heights at rounding level are no detail layer, whichever solver",
          "[decomposition][low-pass]") {
  // bend120's smooth tube before its bumps: every candidate removes 1e-16..1e-13 (the rounding of the solve).
  // Those heights grew with L under the factorisation and stayed flat under conjugate gradients, which read
  // the flat noise as a plateau at L = 0.08 and made a "detail layer" of it.
  SceneOptions o;
  o.resolution = 6000;
  const Scene tube = make_scene("bend120", o);
  for (LowPassSolver solver : {LowPassSolver::Factorisation, LowPassSolver::ConjugateGradients}) {
    LowPassOptions options;
    options.solver = solver;
    LowPassReport report;
    const Positions B = low_pass_base(tube.smooth, tube.F, options, &report);
    CHECK(report.detail_scale == 0);
    CHECK_THAT(report.no_layer_reason, Contains("removes nothing measurable"));
    CHECK(B == tube.smooth);
  }
}

TEST_CASE(
    "low-pass base: a closed piece far smaller than the detail scale stays where it is, whatever the mesh "
    "size",
    "[decomposition][low-pass]") {
  // A break test's survey plane with an 18-vertex sphere of radius 0.01 floating above it: the factorisation
  // (then the default below 500k unknowns) put the sphere's base 47 radii off its centre, at radius 0.001 it
  // called the system singular "near vertex 40414 (degenerate faces around it?)"; conjugate gradients (then
  // the default above) gave the centre. The tiny piece's system is singular to double precision for a
  // factorisation ((L / r)⁴ ≈ 1e18), while the preconditioned iteration's condition number stays 2.
  SceneOptions o;
  o.resolution = 2000;
  const Scene plane = make_scene("lift", o);
  for (double r : {1e-3, 1e-4}) {
    INFO("radius " << r);
    Positions ball;
    Faces ball_faces;
    test::icosphere(1, ball, ball_faces);
    const Vec3 centre(0.5, 0.5, 0.3);
    Positions P(plane.P.rows() + ball.rows(), 3);
    Faces F(plane.F.rows() + ball_faces.rows(), 3);
    P << plane.P, (ball * r).rowwise() + centre.transpose();
    F << plane.F, ball_faces.array() + static_cast<int>(plane.P.rows());
    LowPassOptions options;
    options.detail_scale = 0.3;
    LowPassReport report;
    const Positions B = low_pass_base(P, F, options, &report);
    CHECK(report.iterations > 0);
    CHECK(report.solver_fallback.empty());
    for (Eigen::Index v = plane.P.rows(); v < P.rows(); ++v)
      CHECK((B.row(v) - centre.transpose()).norm() <= r);
    // The plane's base is the plane's alone.
    const Positions B_plane = low_pass_base(plane.P, plane.F, options);
    CHECK(test::max_row_distance(B.topRows(plane.P.rows()), B_plane) <= 1e-9);
  }
}

TEST_CASE(
    "low-pass base: the rounding of far-off coordinates is no detail layer, and no candidate claims no "
    "growth",
    "[decomposition][low-pass]") {
  // A flat tilted unit plane moved to 1e7: its "details" are the coordinates' rounding (rms 2.4e-10, above
  // 1e-10 of the diameter), and the search found a layer at L = 0.091.
  const int n = 40;
  Positions P(n * n, 3);
  Faces F(2 * (n - 1) * (n - 1), 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = double(i) / (n - 1), y = double(j) / (n - 1);
      P.row(j * n + i) << 1e7 + x, 1e7 + y, 1e7 + 0.3 * x + 0.2 * y;
    }
  int f = 0;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i;
      F.row(f++) << a, a + 1, a + n + 1;
      F.row(f++) << a, a + n + 1, a + n;
    }
  for (LowPassSolver solver : {LowPassSolver::ConjugateGradients, LowPassSolver::Factorisation}) {
    LowPassOptions options;
    options.solver = solver;
    LowPassReport report;
    low_pass_base(P, F, options, &report);
    CHECK(report.detail_scale == 0);
    CHECK_THAT(report.no_layer_reason, Contains("removes nothing measurable"));
  }
  // An icosahedron: its smallest candidate (4 mean edge lengths) is beyond 0.6 of its diameter, so nothing
  // is tried; the reason said "the detail heights grow with every scale tried".
  Positions ico;
  Faces ico_faces;
  test::icosphere(0, ico, ico_faces);
  LowPassReport report;
  low_pass_base(ico, ico_faces, {}, &report);
  CHECK(report.candidates.empty());
  CHECK_THAT(report.no_layer_reason, Contains("no candidate scale fits the mesh"));
}
