#include <catch2/catch.hpp>

#include <cmath>

#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/subdivision.h"
#include "msdeform/detail/normal_displacements.h"
#include "msdeform/detail/phong.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

Mat3 some_rotation() { return Eigen::AngleAxisd(0.9, Vec3(1, -2, 0.5).normalized()).toRotationMatrix(); }

// Base B' = B must give back S; reports the error relative to the bounding-box diagonal.
double identity_error(NormalDisplacements& nd, const Positions& S, const Positions& B) {
  Positions out;
  nd.reconstruct(B, out);
  return test::max_row_distance(out, S) / bounding_box_diagonal(S);
}

// Rigid motion of the base: S' must be the same rigid motion of S.
double rigid_error(NormalDisplacements& nd, const Positions& S, const Positions& B) {
  const Mat3 R = some_rotation();
  const Vec3 t(0.3, -1.2, 2.5);
  Positions out;
  nd.reconstruct(test::rigid_motion(B, R, t), out);
  return test::max_row_distance(out, test::rigid_motion(S, R, t)) / bounding_box_diagonal(S);
}

// The bar's cylinder at a coarser level: linear refinement of the control mesh, vertices pushed radially
// onto the cylinder (as make_surface does for the full level).
Positions bar_base(const Scene& s, const LoopRefinement& r, double radius) {
  Positions B = r.linear * s.coarse_P;
  for (Eigen::Index i = 0; i < B.rows(); ++i) {
    const double phi = std::atan2(B(i, 2), B(i, 1));
    B.row(i) << B(i, 0), radius * std::cos(phi), radius * std::sin(phi);
  }
  return B;
}

// Radial bumps on the unit sphere around ±x, ±y, ±z: height(d) for a unit direction d.
double sphere_bumps(const Vec3& d) {
  double h = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {-1.0, 1.0}) {
      const double r = (d - sign * Vec3::Unit(axis)).norm() / 0.5;
      if (r < 1) h += 0.05 * std::pow(1 - r * r, 3);
    }
  return h;
}

// Explicit umbrella smoothing of the interior of a mesh (boundary where the vertex is on the unit square's
// border): a curved base with varying Phong normals for the Newton search.
Positions umbrella_smooth(const Positions& P, const Faces& F, int iterations) {
  const SparseMatrix W = uniform_laplacian(F, static_cast<int>(P.rows()));
  const Eigen::VectorXd degree = -W.diagonal();
  Positions X = P;
  for (int it = 0; it < iterations; ++it) {
    const Positions delta = degree.cwiseInverse().asDiagonal() * (W * X);
    for (Eigen::Index i = 0; i < X.rows(); ++i) {
      const bool border = X(i, 0) <= 0 || X(i, 0) >= 1 || X(i, 1) <= 0 || X(i, 1) >= 1;
      if (!border) X.row(i) += 0.5 * delta.row(i);
    }
  }
  return X;
}

}  // namespace

TEST_CASE("normal displacements: bumpy plane over its flat base gives the analytic heights and feet",
          "[detail][normal]") {
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Plane, o);
  NormalDisplacements nd;
  nd.encode(s.P, s.F, s.smooth, s.F);
  CHECK(nd.name() == "normal");
  CHECK(nd.report().converged == s.P.rows());
  CHECK(nd.report().fallback == 0);
  CHECK((nd.heights() - s.heights).cwiseAbs().maxCoeff() <= 1e-12);
  Positions feet;
  nd.base_points(s.smooth, feet);
  CHECK(test::max_row_distance(feet, s.smooth) <= 1e-12);
  CHECK(identity_error(nd, s.P, s.smooth) <= 1e-9);
  CHECK(rigid_error(nd, s.P, s.smooth) <= 1e-9);
}

TEST_CASE(
    "normal displacements: each vertex stays on its own piece of the base, also where another is nearer",
    "[detail][normal]") {
  // The bumpy plane and, a bump's height above it, a flat second sheet (its own base): the bump tops are
  // nearer the other sheet's base than their own (the break test's two sheets and UV seam: they were bound
  // to it, and moved with it).
  SceneOptions o;
  o.resolution = 2500;
  const Scene s = make_surface(SceneShape::Plane, o);
  const long n = s.P.rows(), m = s.F.rows();
  const double d = s.heights.maxCoeff();
  REQUIRE(d > 0);
  const Positions sheet = s.smooth.rowwise() + Eigen::RowVector3d(0, 0, d);
  Positions S(2 * n, 3), B(2 * n, 3);
  S << s.P, sheet;
  B << s.smooth, sheet;
  Faces F(2 * m, 3);
  F << s.F, s.F.array() + static_cast<int>(n);
  NormalDisplacements nd;
  nd.encode(S, F, B, F);
  CHECK(nd.report().fallback == 0);
  CHECK((nd.base_faces().head(n).array() < m).all());   // the bumpy sheet over its own base
  CHECK((nd.base_faces().tail(n).array() >= m).all());  // the flat one over its own
  CHECK((nd.heights().head(n) - s.heights).cwiseAbs().maxCoeff() <= 1e-12);
  CHECK(identity_error(nd, S, B) <= 1e-9);
  // The second sheet lifted away: the bumpy sheet does not move.
  Positions lifted = B, out;
  lifted.bottomRows(n).col(2).array() += 1.0;
  nd.reconstruct(lifted, out);
  CHECK(test::max_row_distance(out.topRows(n), s.P) <= 1e-12);
  // A base with other connectivity (a remeshed one): the same triangles, their corners listed from the
  // second, so S's faces are not B's. Each piece of S goes to the piece of B nearest to most of its vertices
  // (the bump tops of the first sheet were bound to the second).
  Faces turned(2 * m, 3);
  turned << F.col(1), F.col(2), F.col(0);
  NormalDisplacements other;
  other.encode(S, F, B, turned);
  CHECK(other.report().fallback == 0);
  CHECK((other.base_faces().head(n).array() < m).all());
  CHECK((other.base_faces().tail(n).array() >= m).all());
  CHECK((other.heights().head(n) - s.heights).cwiseAbs().maxCoeff() <= 1e-12);
  other.reconstruct(lifted, out);
  CHECK(test::max_row_distance(out.topRows(n), s.P) <= 1e-12);
}

TEST_CASE("normal displacements: Newton converges on the bumpy plane over a curved (smoothed) base",
          "[detail][normal]") {
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Plane, o);
  // A base that keeps part of the bumps, so the Phong normals vary and the search must iterate and walk.
  const Positions B = umbrella_smooth(s.P, s.F, 10);
  NormalDisplacements nd;
  nd.encode(s.P, s.F, B, s.F);
  const auto& report = nd.report();
  const double rate = double(report.converged) / s.P.rows();
  INFO("vertices " << s.P.rows() << ", converged " << report.converged << ", fallback " << report.fallback
                   << ", walks " << report.walks << ", most iterations " << report.max_iterations_used
                   << ", rate " << rate);
  CHECK(rate >= 0.999);
  CHECK(report.walks > 0);  // the feet are not all in the closest triangles
  CHECK(report.converged + report.fallback == s.P.rows());
  CHECK(nd.heights().allFinite());
  CHECK(nd.barycentrics().minCoeff() >= -1e-10);
  if (report.fallback == 0) {
    CHECK(identity_error(nd, s.P, B) <= 1e-9);
    CHECK(rigid_error(nd, s.P, B) <= 1e-9);
  }
  // Every converged vertex: p − b is parallel to the Phong normal (reconstruction is exact there).
  Positions out;
  nd.reconstruct(B, out);
  double worst = 0;
  std::vector<bool> fell_back(s.P.rows(), false);
  for (int v : report.fallback_vertices) fell_back[v] = true;
  for (Eigen::Index i = 0; i < s.P.rows(); ++i)
    if (!fell_back[i]) worst = std::max(worst, (out.row(i) - s.P.row(i)).norm());
  CHECK(worst <= 1e-9 * bounding_box_diagonal(s.P));
}

TEST_CASE("normal displacements: bumpy bar over its cylinder", "[detail][normal]") {
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Bar, o);
  const int levels = s.refinement.levels;
  // Heights are signed along B's normals, which follow B's face orientation: outwards, like the
  // analytic heights (core's scene test checks the bar's winding).
  // The bar's vertices lie on the cylinder, but make_surface spaces them by linear refinement of 8 chords
  // around, so the angular gaps vary (by up to ~17%) and vertex normals are radial only up to an angle θ.
  const auto largest_gap = [](const Positions& B,
                              const Faces& F) {  // largest angle around the axis of an edge
    double gap = 0;
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d a(B(F(f, k), 1), B(F(f, k), 2)),
            b(B(F(f, (k + 1) % 3), 1), B(F(f, (k + 1) % 3), 2));
        gap = std::max(gap, std::acos(std::min(1.0, a.dot(b) / (a.norm() * b.norm()))));
      }
    return gap;
  };
  SECTION("base at the same level: heights match up to the tilt of the vertex normals") {
    // S = B + h · radial vertex by vertex. Where the vertex normal is tilted by θ_i from radial, the foot
    // of p_i leaves its vertex by about h_i θ_i along facets that slope by at most Δφ/2 against the
    // tangent plane, so |error_i| ≲ h_i θ_i (Δφ/2 + θ_i): checked per vertex with a factor 2 of slack
    // (measured ratio ≤ 0.9 at 3k, 10k and 40k vertices; the error shrinks ~8× per level).
    const Faces& Fb = s.F;
    NormalDisplacements nd;
    nd.encode(s.P, s.F, s.smooth, Fb);
    CHECK(nd.report().fallback == 0);
    const Positions N = vertex_normals(s.smooth, Fb);
    const double gap = largest_gap(s.smooth, Fb);
    int violations = 0;
    for (Eigen::Index i = 0; i < s.P.rows(); ++i) {
      const double theta = std::acos(std::min(1.0, N.row(i).dot(s.smooth_normals.row(i))));
      const double bound = 2 * s.heights[i] * theta * (gap / 2 + theta) + 1e-12;
      if (std::abs(nd.heights()[i] - s.heights[i]) > bound) ++violations;
    }
    INFO("largest error " << (nd.heights() - s.heights).cwiseAbs().maxCoeff());
    CHECK(violations == 0);
    CHECK((nd.heights() - s.heights).cwiseAbs().maxCoeff() <= 1e-6);
    CHECK(identity_error(nd, s.P, s.smooth) <= 1e-9);
    CHECK(rigid_error(nd, s.P, s.smooth) <= 1e-9);
  }
  SECTION("coarser bases: heights within the facets' sagitta, shrinking by ~4 per level") {
    // On a tube whose vertices lie on the cylinder with radial vertex normals, the Phong normal at a chord
    // point is radial through that point (n_k = position_k / r in the cross-section), so the foot of p is
    // where p's radial line meets the facets, and h − h_analytic = r − ρ with ρ the facets' distance to
    // the axis there: 0 ≤ error ≤ r (1 − cos(Δφ/2)) for the largest angular gap Δφ between neighbours.
    // The normals' small tilt (previous section) and the open ends add a little: 5% of slack.
    std::vector<double> errors;
    for (int base_level = levels - 3; base_level <= levels - 1; ++base_level) {
      const LoopRefinement r = loop_refine(s.coarse_F, static_cast<int>(s.coarse_P.rows()), base_level);
      const Positions B = bar_base(s, r, o.bar_radius);
      const Faces& Fb = r.faces;
      NormalDisplacements nd;
      nd.encode(s.P, s.F, B, Fb);
      const double sagitta = o.bar_radius * (1 - std::cos(largest_gap(B, Fb) / 2));
      const double error = (nd.heights() - s.heights).cwiseAbs().maxCoeff();
      INFO("base level " << base_level << " of " << levels << ": error " << error << ", sagitta " << sagitta
                         << ", fallback " << nd.report().fallback);
      CHECK(nd.report().fallback == 0);
      CHECK(error <= 1.05 * sagitta);
      CHECK(identity_error(nd, s.P, B) <= 1e-9);
      CHECK(rigid_error(nd, s.P, B) <= 1e-9);
      errors.push_back(error);
    }
    CHECK(errors[1] <= errors[0] / 3);
    CHECK(errors[2] <= errors[1] / 3);
  }
}

TEST_CASE("normal displacements: sphere with radial bumps over coarser icospheres", "[detail][normal]") {
  Positions S, Fine;
  Faces Fs;
  test::icosphere(5, Fine, Fs);  // 10242 vertices
  S = Fine;
  Eigen::VectorXd analytic(S.rows());
  for (Eigen::Index i = 0; i < S.rows(); ++i) {
    const Vec3 d = Fine.row(i);
    analytic[i] = sphere_bumps(d);
    S.row(i) = (1 + analytic[i]) * d;
  }
  // The base is an inscribed polyhedron with near-radial Phong normals: the foot of p lies about where
  // p's radial line meets the facets, so h − h_analytic is about the facets' depth below the sphere there,
  // at most the sagitta of the longest edge e, 1 − sqrt(1 − e²/3) ≈ e²/6 (circumradius of an equilateral
  // face), plus a second-order term from the normals' tilt. Bound: e²/4, and it shrinks ~4× per level.
  std::vector<double> errors;
  for (int level = 2; level <= 4; ++level) {
    Positions B;
    Faces Fb;
    test::icosphere(level, B, Fb);
    double longest = 0;
    for (Eigen::Index f = 0; f < Fb.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        longest = std::max(longest, (B.row(Fb(f, k)) - B.row(Fb(f, (k + 1) % 3))).norm());
    NormalDisplacements nd;
    nd.encode(S, Fs, B, Fb);
    const double error = (nd.heights() - analytic).cwiseAbs().maxCoeff();
    INFO("base level " << level << ": " << B.rows() << " vertices, error " << error << ", e²/4 "
                       << longest * longest / 4 << ", fallback " << nd.report().fallback << ", walks "
                       << nd.report().walks);
    CHECK(nd.report().fallback == 0);
    CHECK(error <= longest * longest / 4);
    CHECK(identity_error(nd, S, B) <= 1e-9);
    CHECK(rigid_error(nd, S, B) <= 1e-9);
    errors.push_back(error);
  }
  CHECK(errors[1] <= errors[0] / 3);
  CHECK(errors[2] <= errors[1] / 3);
}

TEST_CASE("normal displacements: a base with different connectivity reproduces S", "[detail][normal]") {
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Plane, o);
  for (int drop : {1, 2}) {
    // The flat base at a coarser level: fewer, larger triangles under the same plane.
    const LoopRefinement r =
        loop_refine(s.coarse_F, static_cast<int>(s.coarse_P.rows()), s.refinement.levels - drop);
    const Positions B = r.linear * s.coarse_P;
    REQUIRE(B.rows() < s.P.rows());
    NormalDisplacements nd;
    nd.encode(s.P, s.F, B, r.faces);
    INFO("base " << drop << " level(s) coarser: " << B.rows() << " vertices");
    CHECK(nd.report().fallback == 0);
    CHECK((nd.heights() - s.heights).cwiseAbs().maxCoeff() <= 1e-12);
    Positions feet;
    nd.base_points(B, feet);
    CHECK(test::max_row_distance(feet, s.smooth) <= 1e-12);
    CHECK(identity_error(nd, s.P, B) <= 1e-9);
    CHECK(rigid_error(nd, s.P, B) <= 1e-9);
  }
  // A differently triangulated, jittered flat base (other diagonals and vertex positions).
  Positions G;
  Faces Fg;
  std::vector<bool> interior;
  test::jittered_grid(37, 0.3, G, Fg, interior);
  NormalDisplacements nd;
  nd.encode(s.P, s.F, G, Fg);
  CHECK(nd.report().fallback == 0);
  CHECK((nd.heights() - s.heights).cwiseAbs().maxCoeff() <= 1e-12);
  CHECK(identity_error(nd, s.P, G) <= 1e-9);
  CHECK(rigid_error(nd, s.P, G) <= 1e-9);
}

TEST_CASE("normal displacements: fallback to the closest point is reported and finite", "[detail][normal]") {
  Positions S, B;
  Faces Fs, Fb;
  test::icosphere(4, S, Fs);
  S *= 1.1;
  test::icosphere(1, B, Fb);
  NormalDisplacementOptions options;
  options.max_iterations = 0;  // no Newton step allowed: only vertices whose closest point already fits
  NormalDisplacements nd(options);
  nd.encode(S, Fs, B, Fb);
  const auto& report = nd.report();
  CHECK(report.fallback > 0);
  CHECK(report.converged + report.fallback == S.rows());
  CHECK(report.fallback_vertices.size() == static_cast<size_t>(report.fallback));
  CHECK(std::is_sorted(report.fallback_vertices.begin(), report.fallback_vertices.end()));
  CHECK(nd.heights().allFinite());
  CHECK(nd.barycentrics().minCoeff() >= 0.0);  // closest points lie in their triangles
  Positions out;
  nd.reconstruct(B, out);
  CHECK(out.allFinite());
  // The dropped tangential part is small here: the result stays near S.
  CHECK(test::max_row_distance(out, S) <= 0.1);
  REQUIRE(nd.encode_warnings().size() == 1);
  CHECK_THAT(nd.encode_warnings()[0], Contains(std::to_string(report.fallback) + " of the " +
                                               std::to_string(S.rows()) + " vertices a frame"));
  // The warning leaves out vertices the caller places: only the fallbacks it still reconstructs.
  NormalDisplacements placed(options);
  std::vector<int> all_but_one(report.fallback_vertices.begin() + 1, report.fallback_vertices.end());
  placed.set_placed_vertices(all_but_one);
  placed.encode(S, Fs, B, Fb);
  REQUIRE(placed.encode_warnings().size() == 1);
  CHECK_THAT(placed.encode_warnings()[0],
             // out of the vertices it reconstructs (it said "1 of" all of S's)
             Contains("1 of the " + std::to_string(S.rows() - static_cast<long>(all_but_one.size())) +
                      " vertices") &&
                 Contains("(vertices " + std::to_string(report.fallback_vertices[0]) + ")"));
  placed.set_placed_vertices(report.fallback_vertices);
  placed.encode(S, Fs, B, Fb);
  CHECK(placed.encode_warnings().empty());
  CHECK(placed.report().fallback == report.fallback);  // the report still counts every vertex

  // With the default options everything converges and the reconstruction is exact.
  NormalDisplacements full;
  full.encode(S, Fs, B, Fb);
  CHECK(full.report().fallback == 0);
  CHECK(full.report().max_iterations_used > 0);
  CHECK(identity_error(full, S, B) <= 1e-9);
  // One-shot heights agree with the class.
  CHECK((normal_displacement_heights(S, B, Fb) - full.heights()).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("normal displacements: bad use and bad input", "[detail][normal][bad-input]") {
  Positions S, B;
  Faces Fs, Fb;
  test::icosphere(2, S, Fs);
  test::icosphere(1, B, Fb);
  NormalDisplacements nd;
  Positions out;
  CHECK_THROWS_AS(nd.reconstruct(B, out), UsageError);
  CHECK_THROWS_AS(nd.base_points(B, out), UsageError);
  CHECK_THROWS_AS(nd.encode(S, Fs, B, Faces()), InvalidInput);
  Faces bad = Fb;
  bad(5, 1) = static_cast<int>(B.rows());
  CHECK_THROWS_WITH(nd.encode(S, Fs, B, bad), Contains("face 5") && Contains("out of range"));
  Positions nan_s = S;
  nan_s(7, 2) = std::nan("");
  CHECK_THROWS_WITH(nd.encode(nan_s, Fs, B, Fb), Contains("vertex 7 of S"));
  CHECK_FALSE(nd.encoded());

  nd.encode(S, Fs, B, Fb);
  CHECK(nd.encoded());
  CHECK_THROWS_AS(nd.reconstruct(S, out), UsageError);  // wrong size: S is not the base
  CHECK_THROWS_WITH(nd.reconstruct(Positions(B.topRows(5)), out), Contains("5 vertices"));
  Positions nan_b = B;
  nan_b(3, 0) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(nd.reconstruct(nan_b, out), Contains("vertex 3"));

  // A bad option is refused when the encoding is made, not after the caller loaded a mesh (fourth break test:
  // Python's Deformer(...) took it and prepare() refused it in C++ words).
  NormalDisplacementOptions options;
  options.tolerance = 0;
  CHECK_THROWS_WITH(NormalDisplacements(options),
                    Contains("NormalDisplacementOptions::tolerance must be finite and > 0, got 0"));
}

TEST_CASE("normal displacements: reconstruct allocates nothing once out is sized", "[detail][normal]") {
  SceneOptions o;
  o.resolution = 2000;
  const Scene s = make_surface(SceneShape::Bar, o);
  NormalDisplacements nd;
  nd.encode(s.P, s.F, s.smooth, s.F);
  Positions out(s.P.rows(), 3);
  const double* data = out.data();
  nd.reconstruct(test::rigid_motion(s.smooth, some_rotation(), Vec3(1, 2, 3)), out);
  nd.reconstruct(s.smooth, out);
  CHECK(out.data() == data);
  CHECK(test::max_row_distance(out, s.P) <= 1e-9 * bounding_box_diagonal(s.P));
}

TEST_CASE("normal displacements: placed vertices are skipped, the others reconstructed bit for bit",
          "[detail][normal]") {
  SceneOptions o;
  o.resolution = 2000;
  const Scene s = make_surface(SceneShape::Plane, o);
  const Positions B = umbrella_smooth(s.P, s.F, 20);
  // A bent base B': the other rows must not depend on which vertices are placed.
  Positions Bd = B;
  for (Eigen::Index i = 0; i < Bd.rows(); ++i) Bd(i, 2) += 0.3 * Bd(i, 0) * Bd(i, 0) - 0.1 * Bd(i, 1);
  NormalDisplacements all;
  all.encode(s.P, s.F, B, s.F);
  Positions expected;
  all.reconstruct(Bd, expected);

  std::vector<int> placed;
  std::vector<char> is_placed(s.P.rows(), 0);
  for (int v = 0; v < s.P.rows(); ++v)
    if (s.P(v, 0) < 0.4 || v % 7 == 0) placed.push_back(v), is_placed[v] = 1;
  REQUIRE(static_cast<Eigen::Index>(placed.size()) > s.P.rows() / 4);
  NormalDisplacements some;
  some.set_placed_vertices(placed);
  some.encode(s.P, s.F, B, s.F);
  CHECK((some.heights() - all.heights()).cwiseAbs().maxCoeff() == 0.0);  // the encoding itself is whole
  Positions out = Positions::Constant(s.P.rows(), 3, 7.0);
  some.reconstruct(Bd, out);
  int differ = 0, touched = 0;
  for (int v = 0; v < s.P.rows(); ++v) {
    if (is_placed[v])
      touched += (out.row(v).array() != 7.0).any();
    else
      differ += (out.row(v) - expected.row(v)).cwiseAbs().maxCoeff() != 0.0;
  }
  CHECK(differ == 0);
  CHECK(touched == 0);

  NormalDisplacements bad;
  bad.set_placed_vertices({0, static_cast<int>(s.P.rows())});
  CHECK_THROWS_WITH(bad.encode(s.P, s.F, B, s.F), Contains("placed vertex") && Contains("out of range"));
  CHECK_FALSE(bad.encoded());
}

TEST_CASE("normal displacements: every reconstructed vertex follows the seed's formula, also where normals vanish",
          "[detail][normal]") {
  // Thousands of vertices: the frame loop runs four vertices at a time where the CPU has AVX2, and a group
  // with a vanishing interpolated normal (the face-normal fallback) one vertex at a time.
  SceneOptions o;
  o.resolution = 3000;
  const Scene s = make_surface(SceneShape::Plane, o);
  const Positions B = umbrella_smooth(s.P, s.F, 20);
  NormalDisplacements nd;
  nd.encode(s.P, s.F, B, s.F);
  // A bent base B' with a disc collapsed to one point: zero vertex and face normals there.
  Positions Bd = B;
  for (Eigen::Index i = 0; i < Bd.rows(); ++i) Bd(i, 2) += 0.3 * Bd(i, 0) * Bd(i, 0) - 0.1 * Bd(i, 1);
  const Eigen::Index middle = B.rows() / 2;
  const Vec3 centre = Bd.row(middle);
  int collapsed = 0;
  for (Eigen::Index i = 0; i < Bd.rows(); ++i)
    if ((B.row(i) - B.row(middle)).norm() < 0.05) Bd.row(i) = centre, ++collapsed;
  REQUIRE(collapsed >= 4);
  Positions out;
  nd.reconstruct(Bd, out);
  // S'(v) = b'(α, β, γ) + h n'(α, β, γ) (seed 9.3.2) with the vertex normals of B'.
  const Positions N = vertex_normals(Bd, s.F);
  const phong::Columns Bc(Bd), Nc(N);
  double worst = 0;
  int fallbacks = 0;
  for (Eigen::Index v = 0; v < s.P.rows(); ++v) {
    const int* corners = &s.F(nd.base_faces()[v], 0);
    const Vec3 w = nd.barycentrics().row(v);
    fallbacks += phong::interpolate(Nc, corners, w).norm() <= phong::kMinNormalLength;
    const Vec3 expected = phong::interpolate(Bc, corners, w) + nd.heights()[v] * phong::direction(Bc, Nc, corners, w);
    worst = std::max(worst, (expected - Vec3(out.row(v))).norm());
  }
  CHECK(fallbacks >= 4);
  CHECK(worst <= 1e-14 * bounding_box_diagonal(s.P));
}
