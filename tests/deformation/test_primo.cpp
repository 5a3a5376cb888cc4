#include <catch2/catch.hpp>

#include "msdeform/analysis/metrics.h"
#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/edit_case.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/primo.h"
#include "msdeform/deformation/shell.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

// 600 vertices keep every case here within a few seconds (the Gauss-Newton solve is ~6·#F unknowns).
Scene scene(const std::string& name, int resolution = 600) {
  SceneOptions o;
  o.resolution = resolution;
  return make_scene(name, o);
}

Mat4 rigid(const Vec3& axis, double angle, const Vec3& t) {
  Mat4 T = Mat4::Identity();
  T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  T.topRightCorner<3, 1>() = t;
  return T;
}

}  // namespace

TEST_CASE("primo: options are checked", "[primo]") {
  PrimoOptions o;
  o.thickness = 0;
  CHECK_THROWS_WITH(PrimoDeformer(o), Contains("thickness"));
  o = {};
  o.max_iterations = 0;
  CHECK_THROWS_WITH(PrimoDeformer(o), Contains("max_iterations"));
  o = {};
  o.tolerance = -1;
  CHECK_THROWS_WITH(PrimoDeformer(o), Contains("tolerance"));
}

TEST_CASE("primo: constraints are met exactly and the frame report is filled", "[primo]") {
  for (const std::string name : {"bend120", "bar-twist135"}) {
    const Scene s = scene(name);
    const double diag = bounding_box_diagonal(s.P);
    PrimoDeformer d;
    d.prepare(s.P, s.F, s.region);
    const Positions out = d.deform(s.transforms);
    CHECK(test::constraint_error(s.P, out, s.region, s.transforms) <= 1e-12 * diag);
    const FrameReport r = d.frame_report();
    CHECK(r.converged);
    CHECK(r.iterations >= 1);
    CHECK(r.iterations < PrimoOptions{}.max_iterations);
    CHECK(r.residual >= 0);
    CHECK(r.residual <= PrimoOptions{}.tolerance);
    CHECK(r.warnings.empty());
    // The last stage of the continuation (the target constraints): at most all iterations plus its start.
    CHECK(d.energy_history().size() >= 2);
    CHECK(d.energy_history().size() <= static_cast<size_t>(r.iterations) + 1);
    // Warm start: the same frame again starts at the optimum and stops almost at once.
    const Positions again = d.deform(s.transforms);
    CHECK(d.frame_report().iterations < r.iterations);
    CHECK(test::max_row_distance(again, out) <= 1e-5 * diag);
  }
}

TEST_CASE("primo: a rigid motion of all constrained vertices moves the whole shape rigidly", "[primo]") {
  const Scene s = scene("bend120");
  const double diag = bounding_box_diagonal(s.P);
  std::vector<int> codes = s.region.codes();
  for (int& c : codes)
    if (c != Region::kFree) c = Region::kFirstHandle;
  const Region one = Region::from_codes(codes);
  PrimoDeformer d;
  d.prepare(s.P, s.F, one);
  const Mat3 R = Eigen::AngleAxisd(2.0, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
  const Vec3 t(0.4, 1.5, -0.3);
  const Positions out = d.deform({rigid(Vec3(1, -2, 0.5), 2.0, t)});
  CHECK(test::max_row_distance(out, test::rigid_motion(s.P, R, t)) <= 1e-9 * diag);
  CHECK(d.frame_report().converged);
  // A translation after it, then the rigid motion again (the conformance suite's sequence): each is
  // reproduced although E → 0 makes the relative energy change meaningless.
  const Positions shifted = d.deform({rigid(Vec3(0, 0, 1), 0, Vec3(0.3, -0.2, 0.5))});
  CHECK(test::max_row_distance(shifted, test::rigid_motion(s.P, Mat3::Identity(), Vec3(0.3, -0.2, 0.5))) <= 1e-9 * diag);
  CHECK(test::max_row_distance(d.deform({rigid(Vec3(1, -2, 0.5), 2.0, t)}), out) <= 1e-9 * diag);
}

TEST_CASE("primo: the energy never increases over the iterations", "[primo]") {
  const Scene s = scene("twist135");
  PrimoOptions o;
  o.max_iterations = 60;
  o.tolerance = 0;  // exactly 60 iterations
  PrimoDeformer d(o);
  d.prepare(s.P, s.F, s.region);
  d.deform(s.transforms);
  CHECK(d.frame_report().iterations == 60);
  const std::vector<double>& E = d.energy_history();
  REQUIRE(E.size() >= 2);  // the last continuation stage
  CHECK(E.back() < 0.5 * E.front());
  for (size_t i = 1; i < E.size(); ++i) {
    INFO("iteration " << i << ": " << E[i - 1] << " -> " << E[i]);
    CHECK(E[i] <= E[i - 1] * (1 + 1e-12) + 1e-300);
  }
}

TEST_CASE("primo: reset returns to rest, and an initial guess at the solution stays there", "[primo]") {
  const Scene s = scene("bend120");
  const double diag = bounding_box_diagonal(s.P);
  PrimoDeformer d;
  d.prepare(s.P, s.F, s.region);
  const Positions first = d.deform(s.transforms);
  const int first_iterations = d.frame_report().iterations;
  d.reset();
  CHECK(test::max_row_distance(d.deform(s.transforms), first) <= 1e-12 * diag);
  CHECK(d.frame_report().iterations == first_iterations);
  d.set_initial_guess(first);
  const Positions from_guess = d.deform(s.transforms);
  CHECK(d.frame_report().converged);
  CHECK(d.frame_report().iterations < first_iterations);
  CHECK(test::max_row_distance(from_guess, first) <= 1e-6 * diag);
}

TEST_CASE("primo: more rigid than the linear shell on the 120 degree bend and the 135 degree twist", "[primo]") {
  for (const std::string name : {"bend120", "twist135"}) {
    const Scene s = scene(name);
    PrimoDeformer primo;
    primo.prepare(s.P, s.F, s.region);
    const Positions p = primo.deform(s.transforms);
    ShellDeformer shell;
    shell.prepare(s.P, s.F, s.region);
    const Positions q = shell.deform(s.transforms);
    const double primo_rigidity = rigidity_error(s.P, p, s.F).stats.mean;
    const double shell_rigidity = rigidity_error(s.P, q, s.F).stats.mean;
    INFO(name << ": primo " << primo_rigidity << " (" << primo.frame_report().iterations << " iterations), shell "
              << shell_rigidity);
    // Measured (2.5k vertices): bend 0.00053 vs shell ~0.03, twist 0.066 vs 0.146 (the 135° twist of the
    // plane stretches its long edges by a factor ~2: a rigid-prism surface wrinkles there, and has
    // self-intersecting bumps as the shell does).
    CHECK(primo_rigidity * 1.5 < shell_rigidity);
    if (name == "bend120") CHECK(count_self_intersections(p, s.F) == 0);
  }
}

TEST_CASE("primo: CGAL's cactus edit has no self-intersecting face pair and is as rigid as CGAL's SRE-ARAP",
          "[primo][cgal]") {
  const EditCase c = file_case(test::cgal_mesh("cactus.off"), test::cgal_deformation_data("cactus.sel"),
                               test::cgal_deformation_data("cactus.def"));
  PrimoDeformer d;
  d.prepare(c.P, c.F, c.region);
  const Positions out = d.deform(c.transforms);
  const RigidityError r = RigidityMetric(c.P, c.F).measure(out);
  INFO("rigidity " << r.stats.mean << ", iterations " << d.frame_report().iterations);
  CHECK(d.frame_report().converged);
  // Issue 11: CGAL's SRE-ARAP reaches rigidity mean 0.0243 with 0 pairs (our metric, bench_arap_cgal).
  // Measured with the default thickness 2: 0.0202, 0 pairs (0.5: 0.0288 with 89 pairs).
  CHECK(count_self_intersections(out, c.F) == 0);
  CHECK(r.stats.mean <= 0.0243);
}

TEST_CASE("primo: constraints act through whole faces, and a region without them is refused or warned about", "[primo]") {
  const Scene s = scene("bend120", 600);
  // No face with three constrained vertices: nothing holds the prisms.
  Region sparse(static_cast<int>(s.P.rows()));
  sparse.set_fixed({s.F(0, 0)});
  sparse.set_handle({s.F(s.F.rows() - 1, 0)}, 0);
  PrimoDeformer d;
  CHECK_THROWS_AS(d.prepare(s.P, s.F, sparse), TopologyError);
  // A one-vertex handle beside a fixed band: it moves only its own vertex, and prepare() says so.
  std::vector<int> codes = s.region.codes();
  for (int& c : codes)
    if (c >= Region::kFirstHandle) c = Region::kFree;
  codes[s.region.handle_vertices(0)[0]] = Region::kFirstHandle;
  d.prepare(s.P, s.F, Region::from_codes(codes));
  REQUIRE(d.prepare_warnings().size() == 1);
  CHECK_THAT(d.prepare_warnings()[0], Contains("handle 0"));
}
