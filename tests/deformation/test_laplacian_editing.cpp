#include <catch2/catch.hpp>

#include <numeric>

#include "deformation/edit_measures.h"
#include "msdeform/analysis/metrics.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/laplacian_editing.h"
#include "msdeform/deformation/shell.h"
#include "test_util.h"

using namespace msd;

namespace {
Mat4 rotation(double angle, const Vec3& axis, const Vec3& t = Vec3::Zero()) {
  Mat4 T = Mat4::Identity();
  T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  T.topRightCorner<3, 1>() = t;
  return T;
}
}  // namespace

TEST_CASE("laplacian: identity frame is the rest shape and constraints are exact", "[deformation][laplacian]") {
  const Scene s = test::small_scene("bend120");
  const double diag = bounding_box_diagonal(s.P);
  for (bool implicit : {true, false}) {
    INFO("implicit " << implicit);
    LaplacianEditing l(LaplacianEditingOptions{implicit});
    l.prepare(s.P, s.F, s.region);
    CHECK(test::max_row_distance(l.deform({Mat4::Identity()}), s.P) <= 1e-10 * diag);
    const Positions out = l.deform(s.transforms);
    CHECK(test::constraint_error(s.P, out, s.region, s.transforms) == 0.0);
    CHECK(out.allFinite());
  }
}

TEST_CASE("laplacian: linearised rotations are not rigid (implicit), propagated ones are (explicit)",
          "[deformation][laplacian]") {
  const Scene s = test::small_scene("bar-bend120");
  std::vector<int> codes = s.region.codes();
  for (int& c : codes)
    if (c != Region::kFree) c = Region::kFirstHandle;
  const Region one = Region::from_codes(codes);
  const double diag = bounding_box_diagonal(s.P);
  const Mat4 T = rotation(0.7, Vec3(1, 2, 3), Vec3(0.3, -0.2, 0.5));
  const Positions expected = test::rigid_motion(s.P, T.topLeftCorner<3, 3>(), T.topRightCorner<3, 1>());
  LaplacianEditing implicit, explicit_(LaplacianEditingOptions{false});
  implicit.prepare(s.P, s.F, one);
  explicit_.prepare(s.P, s.F, one);
  const double e_implicit = test::max_row_distance(implicit.deform({T}), expected);
  const double e_explicit = test::max_row_distance(explicit_.deform({T}), expected);
  WARN("0.7 rad rigid motion of all constraints: implicit error " << e_implicit / diag << " diag, explicit "
                                                                     << e_explicit / diag);
  CHECK(e_implicit > 1e-3 * diag);
  CHECK(e_explicit <= 1e-8 * diag);
  // A translation is reproduced by both.
  const Mat4 shift = rotation(0, Vec3::UnitX(), Vec3(0.3, -0.2, 0.5));
  const Positions shifted = test::rigid_motion(s.P, Mat3::Identity(), Vec3(0.3, -0.2, 0.5));
  CHECK(test::max_row_distance(implicit.deform({shift}), shifted) <= 1e-9 * diag);
  CHECK(test::max_row_distance(explicit_.deform({shift}), shifted) <= 1e-9 * diag);
}

TEST_CASE("laplacian: the explicit variant is translation-insensitive (shell's bending under a lift)",
          "[deformation][laplacian]") {
  // δ' = δ for a translated handle, so Δ²p' = Δδ is the shell equation Δ²d = 0 (seed 9.4.2).
  const Scene s = test::small_scene("lift");
  LaplacianEditing l(LaplacianEditingOptions{false});
  ShellDeformer shell(ShellOptions{0, 1});
  l.prepare(s.P, s.F, s.region);
  shell.prepare(s.P, s.F, s.region);
  CHECK(test::max_row_distance(l.deform(s.transforms), shell.deform(s.transforms)) <= 1e-8 * bounding_box_diagonal(s.P));
}

TEST_CASE("laplacian: survey edits against the survey's own Laplacian-editing results, and the twist's scale artifact",
          "[deformation][laplacian][survey]") {
  for (const std::string name : {"plane", "cylinder", "bar"}) {
    const EditCase c = test::survey_case(name);
    const double diag = bounding_box_diagonal(c.P);
    LaplacianEditing l;
    ShellDeformer shell;
    l.prepare(c.P, c.F, c.region);
    shell.prepare(c.P, c.F, c.region);
    const Positions out = l.deform(c.transforms);
    const Positions ref = shell.deform(c.transforms);
    CHECK(test::constraint_error(c.P, out, c.region, c.transforms) <= 1e-12 * diag);
    const Positions theirs = load_edit_case(test::shared_data("survey/" + name + "-laplacian_editing.off")).P;
    REQUIRE(theirs.rows() == c.P.rows());
    const double to_theirs = test::max_row_distance(out, theirs) / diag;
    const double shell_to_theirs = test::max_row_distance(ref, theirs) / diag;
    const RigidityError el = rigidity_error(c.P, out, c.F), es = rigidity_error(c.P, ref, c.F);
    const test::ScaleChange sl = test::local_scale_change(c.P, out, c.F, c.region);
    const test::ScaleChange ss = test::local_scale_change(c.P, ref, c.F, c.region);
    WARN(name << ": laplacian to published " << to_theirs << " (shell " << shell_to_theirs << "); rigidity mean "
              << el.stats.mean << " (shell " << es.stats.mean << "); scale change max " << sl.max << " mean " << sl.mean
              << " (shell " << ss.max << ", " << ss.mean << ")");
    if (name == "cylinder") CHECK(to_theirs < 0.75 * shell_to_theirs);  // measured 0.047 against 0.089
    if (name == "bar") {
      // The linearised-rotation artifact under the 135° twist: the free region's triangles change their
      // size (measured mean |√(area'/area) − 1| = 0.47 against shell's 0.09, max 0.96), but stay bounded.
      CHECK(sl.mean > 3 * ss.mean);
      CHECK(sl.max < 1.5);
      CHECK(el.stats.mean < 0.5);  // measured 0.27
    }
  }
}

TEST_CASE("laplacian: a frame that scales the free region says so in its report", "[deformation][laplacian][survey]") {
  // Measured exp(mean |log(ℓ'/ℓ)|) over the edges at free vertices: plane (translation) below 1.25, cylinder
  // (120° bend) 1.50, bar (135° twist) 1.56, cactus 1.67 (its free branch reaches a rigidity residual of 6).
  for (const std::string name : {"plane", "cylinder", "bar", "cactus"}) {
    INFO(name);
    const EditCase c = test::survey_case(name);
    LaplacianEditing l;
    l.prepare(c.P, c.F, c.region);
    l.deform(c.transforms);
    const std::vector<std::string>& warnings = l.frame_report().warnings;
    if (name == "plane") {
      CHECK(warnings.empty());
    } else {
      REQUIRE(warnings.size() == 1);
      CHECK_THAT(warnings[0], Catch::Matchers::Contains("linearised rotations"));
    }
  }
}

TEST_CASE("laplacian: a vertex of 15500 neighbours is refused by name, not an out-of-memory",
          "[deformation][laplacian]") {
  // R^T R couples x, y and z of every two neighbours of a vertex: (3 · 15501)² > 2^31 − 1 entries.
  Positions P;
  Faces F;
  test::fan_disk(15500, P, F);
  Region region(static_cast<int>(P.rows()));
  std::vector<int> rim(100);
  std::iota(rim.begin(), rim.end(), 1);
  region.set_fixed(rim);
  region.set_handle({0}, 0);
  LaplacianEditing laplacian;
  CHECK_THROWS_WITH(laplacian.prepare(P, F, region), Catch::Contains("laplacian: the least-squares system") &&
                                                         Catch::Contains("vertex 0 has 15500"));
}
