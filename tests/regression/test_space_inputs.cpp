// The comparison on inputs that only space methods take: a point cloud (the bumpy plane's vertices without
// its faces) and a soup (the plane with a fin on one of its edges, which makes that edge non-manifold).
// Small (about 1000 vertices) and fast: the space methods run and are measured where the input allows,
// shell fails with its message, no metric fails a method, and the tables say why a cell is n/a.
#include <catch2/catch.hpp>

#include <algorithm>

#include "apps/compare/runner.h"
#include "golden.h"
#include "msdeform/core/surface_check.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

// The lift of the bumpy plane at about 1000 vertices, renamed.
EditCase plane_lift(const std::string& name) {
  EditCase c = scene_case("lift", 1000);
  c.name = name;
  c.control = nullptr;
  return c;
}

// The edit as loaded from a file of these arrays: surface_problem from check_surface, faces oriented.
void recheck(EditCase& c) { c.surface_problem = check_surface(c.P, c.F).problem(); }

EditCase point_cloud() {
  EditCase c = plane_lift("cloud");
  c.F = Faces(0, 3);
  recheck(c);
  return c;
}

// A third face on an interior edge (a, b) of the plane: a fin towards a new free vertex above the edge.
EditCase soup_with_fin() {
  EditCase c = plane_lift("soup");
  const int a = c.F(c.F.rows() / 2, 0), b = c.F(c.F.rows() / 2, 1);
  const int fin = static_cast<int>(c.P.rows());
  c.P.conservativeResize(fin + 1, 3);
  c.P.row(fin) = 0.5 * (c.P.row(a) + c.P.row(b)) + Eigen::RowVector3d(0, 0, 0.05);
  c.F.conservativeResize(c.F.rows() + 1, 3);
  c.F.row(c.F.rows() - 1) << a, b, fin;
  std::vector<int> codes(fin + 1, Region::kFree);
  for (int v = 0; v < fin; ++v) codes[v] = c.region.code(v);
  c.region = Region::from_codes(codes);
  recheck(c);
  return c;
}

ComparisonOptions options() {
  ComparisonOptions o;
  o.methods = {"lattice", "rbf", "shell"};
  o.timed_frames = 1;
  return o;
}

// The cell of metrics_table(results) in the row of `method` and the column `column`.
std::string cell(const std::vector<MethodResult>& results, const std::string& method, const std::string& column) {
  const auto table = metrics_table(results);
  const auto& header = table.front();
  const auto c = std::find(header.begin(), header.end(), column) - header.begin();
  REQUIRE(c < static_cast<long>(header.size()));
  for (size_t r = 1; r < table.size(); ++r)
    if (table[r][1] == method) return table[r][c];
  FAIL("no row for " << method);
  return "";
}

}  // namespace

TEST_CASE("space inputs: a point cloud is deformed by the space methods, with the face metrics n/a and why",
          "[regression][space-inputs]") {
  const EditCase cloud = point_cloud();
  REQUIRE_THAT(cloud.surface_problem, Contains("no faces"));
  const std::vector<MethodResult> results = compare_methods(cloud, options());
  for (const char* method : {"lattice", "rbf"}) {
    const MethodResult& r = test::find_result(results, "cloud", method);
    INFO(method << ": " << r.error);
    REQUIRE(r.ok);
    CHECK(r.result.rows() == cloud.P.rows());
    CHECK(r.handle_error < 1e-2 * bounding_box_diagonal(cloud.P));
    CHECK(r.rigidity.count == 0);
    CHECK(r.distortion.count == 0);
    CHECK(r.distortion_per_vertex.size() == 0);
    CHECK(r.self_intersections == -1);
    CHECK_FALSE(r.volume_change);
    CHECK_THAT(r.not_measured, StartsWith("point cloud: no faces, so rigidity, detail distortion"));
    CHECK(cell(results, method, "handle_error") != "n/a");
    for (const char* column : {"rigidity_mean", "distortion_p95", "self_intersections", "volume_change"})
      CHECK(cell(results, method, column) == "n/a");
    CHECK(cell(results, method, "not_measured") == r.not_measured);
  }
  const MethodResult& shell = test::find_result(results, "cloud", "shell");
  CHECK_FALSE(shell.ok);
  CHECK_THAT(shell.error, Contains("shell is a surface method") && Contains("no faces"));
  CHECK(cell(results, "shell", "rigidity_mean").empty());  // failed: no figures, not n/a

  // One note for the scene, above the Markdown table; the CSV carries the reason in its column.
  const std::vector<std::string> notes = measurement_notes(results);
  REQUIRE(notes.size() == 1);
  CHECK_THAT(notes[0], StartsWith("cloud: point cloud: no faces"));
  CHECK_THAT(metrics_markdown(results), StartsWith(notes[0] + "\n\n|"));
  CHECK_THAT(metrics_csv(results), Contains(",not_measured,message\n"));
}

TEST_CASE("space inputs: a soup with a non-manifold edge is measured on its faces, self-intersections aside",
          "[regression][space-inputs]") {
  const EditCase soup = soup_with_fin();
  REQUIRE_THAT(soup.surface_problem, Contains("shared by 3 faces"));
  const std::vector<MethodResult> results = compare_methods(soup, options());
  for (const char* method : {"lattice", "rbf"}) {
    const MethodResult& r = test::find_result(results, "soup", method);
    INFO(method << ": " << r.error);
    REQUIRE(r.ok);
    // Rigidity needs only the faces' edges, detail distortion a faired base: both are measured.
    CHECK(r.rigidity.count == soup.P.rows());
    CHECK(r.distortion.count > 0);
    CHECK(r.distortion_per_vertex.size() == soup.P.rows());
    // CGAL's count needs a manifold surface: n/a, naming the face that keeps it from being one.
    CHECK(r.self_intersections == -1);
    CHECK_THAT(r.not_measured, StartsWith("self-intersections not measured: count_self_intersections: face"));
  }
  CHECK_FALSE(test::find_result(results, "soup", "shell").ok);
  CHECK(measurement_notes(results).size() == 1);

  // The plane itself, a surface: everything is measured and there is no note.
  const std::vector<MethodResult> surface = compare_methods(plane_lift("plane"), options());
  for (const MethodResult& r : surface) {
    INFO(r.method << ": " << r.error);
    REQUIRE(r.ok);
    CHECK(r.not_measured.empty());
    CHECK(r.self_intersections >= 0);
    CHECK(r.rigidity.count > 0);
  }
  CHECK(measurement_notes(surface).empty());
}

TEST_CASE("space inputs: a metric the edit cannot give never fails a method", "[regression][space-inputs]") {
  // Every vertex constrained: there is no free vertex to measure details on, which used to fail every method.
  EditCase c = plane_lift("all-constrained");
  std::vector<int> codes(c.P.rows());
  for (int v = 0; v < c.P.rows(); ++v) codes[v] = c.region.is_free(v) ? Region::kFixed : c.region.code(v);
  c.region = Region::from_codes(codes);
  ComparisonOptions o = options();
  o.methods = {"lattice"};
  const MethodResult r = compare_methods(c, o).front();
  INFO(r.error);
  REQUIRE(r.ok);
  CHECK(r.distortion.count == 0);
  CHECK(r.rigidity.count > 0);
  CHECK_THAT(r.not_measured, StartsWith("detail distortion not measured: ") && Contains("no free vertex"));
}

TEST_CASE("space inputs: self-intersections are not counted around a vertex of over 10000 faces",
          "[regression][space-inputs]") {
  // CGAL tests all faces around a vertex pairwise: the count took an hour on a flat 47000-face fan. The
  // count is refused with the vertex named; the method and its other metrics are unaffected.
  EditCase c = plane_lift("fan");
  test::fan_disk(10001, c.P, c.F);
  std::vector<int> codes(static_cast<size_t>(c.P.rows()), Region::kFixed);
  codes[0] = Region::kFirstHandle;
  c.region = Region::from_codes(codes);
  c.transforms = {Mat4::Identity()};
  c.transforms[0](2, 3) = 0.1;
  recheck(c);
  ComparisonOptions o = options();
  o.methods = {"lattice"};
  const MethodResult r = compare_methods(c, o).front();
  INFO(r.error);
  REQUIRE(r.ok);
  CHECK(r.self_intersections == -1);
  CHECK_THAT(r.not_measured, Contains("self-intersections not measured: vertex 0 lies on 10001 faces"));
  CHECK(r.rigidity.count > 0);
}
