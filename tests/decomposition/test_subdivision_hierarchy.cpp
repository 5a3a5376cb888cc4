#include <catch2/catch.hpp>

#include <random>

#include "msdeform/core/errors.h"
#include "msdeform/core/scenes.h"
#include "msdeform/decomposition/subdivision_hierarchy.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

Scene surface(SceneShape shape, int resolution) {
  SceneOptions o;
  o.resolution = resolution;
  return make_surface(shape, o);
}

SubdivisionHierarchy build(const Scene& s, ControlPointFit fit) {
  SubdivisionHierarchyOptions options;
  options.control_points = fit;
  SubdivisionHierarchy h;
  h.build(s.P, s.F, s.coarse_P, s.coarse_F, s.refinement, options);
  return h;
}

}  // namespace

TEST_CASE("subdivision hierarchy: refining the unedited control points plus details returns S exactly",
          "[decomposition][subdivision]") {
  const SceneShape shape = GENERATE(SceneShape::Plane, SceneShape::Bar);
  const ControlPointFit fit = GENERATE(ControlPointFit::Given, ControlPointFit::LeastSquares);
  const Scene s = surface(shape, 5000);
  INFO(s.name << (fit == ControlPointFit::Given ? " given" : " least squares"));
  const SubdivisionHierarchy h = build(s, fit);
  REQUIRE(h.built());
  CHECK(h.num_fine_vertices() == s.P.rows());
  CHECK(h.num_coarse_vertices() == s.coarse_P.rows());
  CHECK(h.fine_faces() == s.F);
  CHECK(h.coarse_faces() == s.coarse_F);
  Positions out;
  h.reconstruct_global(h.control_points(), out);
  const double scale = s.P.cwiseAbs().maxCoeff();
  CHECK((out - s.P).cwiseAbs().maxCoeff() <= 1e-12 * scale);
  CHECK((h.base() + h.details() - s.P).cwiseAbs().maxCoeff() <= 1e-12 * scale);
  if (fit == ControlPointFit::Given) CHECK(h.control_points() == s.coarse_P);
}

TEST_CASE("subdivision hierarchy: refine() is the linear map loop · c", "[decomposition][subdivision]") {
  const SceneShape shape = GENERATE(SceneShape::Plane, SceneShape::Bar);
  const Scene s = surface(shape, 20000);
  const SubdivisionHierarchy h = build(s, ControlPointFit::LeastSquares);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  Positions c1 = s.coarse_P, c2 = s.coarse_P;
  for (Eigen::Index i = 0; i < c1.size(); ++i) c1.data()[i] += 0.1 * u(rng), c2.data()[i] = u(rng);
  Positions f1, f2, f12;
  h.refine(c1, f1);
  h.refine(c2, f2);
  const Positions reference = s.refinement.loop * c1;
  CHECK((f1 - reference).cwiseAbs().maxCoeff() <= 1e-13 * reference.cwiseAbs().maxCoeff());
  h.refine(2.0 * c1 - 3.0 * c2, f12);
  CHECK((f12 - (2.0 * f1 - 3.0 * f2)).cwiseAbs().maxCoeff() <= 1e-12);
  CHECK((h.base() - s.refinement.loop * h.control_points()).cwiseAbs().maxCoeff() <= 1e-13);
  // A rigid motion of the control mesh moves the base rigidly (stencil rows sum to 1).
  const Mat3 R = Eigen::AngleAxisd(0.4, Vec3(0, 1, 1).normalized()).toRotationMatrix();
  const Positions moved = (h.control_points() * R.transpose()).rowwise() + Eigen::RowVector3d(1, 2, 3);
  const Positions expected = (h.base() * R.transpose()).rowwise() + Eigen::RowVector3d(1, 2, 3);
  CHECK((h.refine(moved) - expected).cwiseAbs().maxCoeff() <= 1e-12);
  // The compressed stencils store far fewer weights than the matrix has entries.
  INFO(h.num_stencil_patterns() << " patterns, " << h.num_stored_weights() << " weights for "
                                << s.refinement.loop.nonZeros() << " non-zeros");
  CHECK(h.num_stored_weights() < s.refinement.loop.nonZeros() / 2);
}

TEST_CASE("subdivision hierarchy: least-squares control points minimise the details",
          "[decomposition][subdivision]") {
  const Scene s = surface(SceneShape::Plane, 5000);
  const SubdivisionHierarchy given = build(s, ControlPointFit::Given);
  const SubdivisionHierarchy fitted = build(s, ControlPointFit::LeastSquares);
  CHECK(fitted.details().norm() < given.details().norm());
  // Normal equations: loopᵀ (S − B) = 0.
  const Positions gradient = s.refinement.loop.transpose() * fitted.details();
  CHECK(gradient.cwiseAbs().maxCoeff() <=
        1e-10 * (s.refinement.loop.transpose() * s.P).cwiseAbs().maxCoeff());
  // A surface that is itself a Loop surface is fitted exactly.
  Positions c = s.coarse_P;
  c.col(2) = 0.1 * c.col(0).array().sin() + 0.05 * c.col(1).array().square();
  const Positions S = s.refinement.loop * c;
  SubdivisionHierarchy exact;
  exact.build(S, s.F, s.coarse_P, s.coarse_F, s.refinement);
  CHECK((exact.control_points() - c).cwiseAbs().maxCoeff() <= 1e-10);
  CHECK(exact.details().cwiseAbs().maxCoeff() <= 1e-12);
}

TEST_CASE("subdivision hierarchy: coarse region from the fine one", "[decomposition][subdivision]") {
  const Scene s = surface(SceneShape::Plane, 5000);
  const SubdivisionHierarchy h = build(s, ControlPointFit::LeastSquares);
  const std::vector<int>& map = h.coarse_to_fine();
  REQUIRE(map.size() == static_cast<size_t>(s.coarse_P.rows()));
  CHECK(map == coarse_to_fine_vertices(s.refinement));
  // The vertex-child sits where its coarse vertex is (the fine grid is the linear refinement).
  for (size_t j = 0; j < map.size(); ++j) REQUIRE(s.smooth.row(map[j]) == s.coarse_P.row(j));
  const Region coarse = h.coarse_region(s.region);
  REQUIRE(coarse.num_vertices() == s.coarse_P.rows());
  CHECK(coarse.num_handles() == 1);
  for (Eigen::Index j = 0; j < s.coarse_P.rows(); ++j) {
    const double x = s.coarse_P(j, 0);
    INFO("coarse vertex " << j << " at x = " << x);
    CHECK(coarse.code(static_cast<int>(j)) == (x < 0.2   ? Region::kFixed
                                               : x > 0.8 ? Region::kFirstHandle
                                                         : Region::kFree));
  }
  CHECK(coarse_region(s.region, s.refinement).codes() == coarse.codes());
  CHECK_NOTHROW(coarse.validate(static_cast<int>(s.coarse_P.rows()), &s.coarse_F));
}

TEST_CASE("subdivision hierarchy reports bad input", "[decomposition][subdivision][bad-input]") {
  const Scene s = surface(SceneShape::Plane, 2000);
  SubdivisionHierarchy h;
  Positions out;
  CHECK_FALSE(h.built());
  CHECK_THROWS_AS(h.refine(s.coarse_P, out), UsageError);
  CHECK_THROWS_AS(h.coarse_region(s.region), UsageError);
  CHECK_THROWS_WITH(h.build(s.P.topRows(10), s.F, s.coarse_P, s.coarse_F, s.refinement),
                    Contains("stencil matrices"));
  Faces swapped = s.F;
  swapped.row(3).swap(swapped.row(4));
  CHECK_THROWS_WITH(h.build(s.P, swapped, s.coarse_P, s.coarse_F, s.refinement), Contains("fine face 3"));
  CHECK_THROWS_WITH(h.build(s.P, s.F, s.coarse_P, s.coarse_F.topRows(3), s.refinement),
                    Contains("coarse faces"));
  Positions nan = s.P;
  nan(9, 0) = std::nan("");
  CHECK_THROWS_WITH(h.build(nan, s.F, s.coarse_P, s.coarse_F, s.refinement), Contains("vertex 9"));
  CHECK_FALSE(h.built());

  h.build(s.P, s.F, s.coarse_P, s.coarse_F, s.refinement);
  CHECK_THROWS_AS(h.refine(s.coarse_P.topRows(5), out), UsageError);
  Positions bad = s.coarse_P;
  bad(4, 2) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(h.refine(bad, out), Contains("control point 4"));
  CHECK_THROWS_WITH(h.coarse_region(Region(12)), Contains("vertex labels"));
  // A handle made of one fine vertex between coarse vertices vanishes on the coarse mesh.
  Region tiny = s.region;
  const std::vector<int>& map = h.coarse_to_fine();
  int between = 0;
  while (std::find(map.begin(), map.end(), between) != map.end() || !s.region.is_free(between)) ++between;
  tiny.set_handle({between}, 1);
  CHECK_THROWS_WITH(h.coarse_region(tiny), Contains("handle 1") && Contains("no vertex on the coarse mesh"));
}
