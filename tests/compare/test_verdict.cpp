#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "apps/compare/runner.h"
#include "apps/compare/verdict.h"
#include "msdeform/core/edit_case.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

MethodResult result(const std::string& scene, const std::string& method, double rigidity, double distortion,
                    int self_intersections = 0, int folded = -1) {
  MethodResult r;
  r.scene = scene;
  r.method = method;
  r.ok = true;
  r.frame_ms = 1.5;
  r.rigidity = {rigidity, rigidity, rigidity, 100};
  r.distortion = {distortion, distortion, distortion, 100};
  r.self_intersections = self_intersections;
  r.folded_faces = folded;
  return r;
}

}  // namespace

TEST_CASE("verdicts: thresholds relative to the edit's most rigid result, reasons in words, one best per edit",
          "[compare][verdict]") {
  std::vector<MethodResult> results = {
      result("bend", "arap", 0.01, 0.05),          // the most rigid
      result("bend", "shell", 0.03, 0.05),         // 3× the most rigid: fair
      result("bend", "lattice", 0.05, 0.05),       // 5×: poor
      result("bend", "normal", 0.011, 0.30),       // details changed by 30 %: poor
      result("bend", "laplacian", 0.001, 0.0, 4),  // most rigid of all, but self-intersecting: broken
      result("bend", "multi", 0.012, 0.02, 0, 7),  // folded over its base: broken
      result("lift", "arap", 0.02, 0.01),          // another edit: judged on its own
  };
  MethodResult failed;
  failed.scene = "bend";
  failed.method = "primo";
  failed.error = "no convergence";
  results.push_back(failed);
  const std::vector<Assessment> a = assess(results);
  REQUIRE(a.size() == results.size());
  CHECK(a[0].verdict == Verdict::Good);
  CHECK(a[0].best);
  CHECK_THAT(a[0].reason, Contains("the most rigid") && Contains("details kept (5 %)"));
  CHECK(a[1].verdict == Verdict::Fair);
  CHECK_THAT(a[1].reason, Contains("rigidity 3× the edit's most rigid"));
  CHECK(a[2].verdict == Verdict::Poor);
  CHECK(a[3].verdict == Verdict::Poor);
  CHECK_THAT(a[3].reason, Contains("details changed by 30 % of their height"));
  CHECK(a[4].verdict == Verdict::Broken);
  CHECK_THAT(a[4].reason, Contains("4 self-intersecting triangle pairs"));
  CHECK_FALSE(a[4].best);  // broken results are never the best, however rigid
  CHECK(a[5].verdict == Verdict::Broken);
  CHECK_THAT(a[5].reason, Contains("7 triangles folded over the base"));
  CHECK(a[6].verdict == Verdict::Good);
  CHECK(a[6].best);
  CHECK(a[7].verdict == Verdict::Failed);
  CHECK(a[7].reason == "no convergence");
  int best = 0;
  for (const Assessment& x : a) best += x.best;
  CHECK(best == 2);  // one per edit

  const std::string summary = verdict_summary(results, a);
  CHECK_THAT(summary, Contains("bend: best arap (good: the most rigid unbroken result") &&
                          Contains("broken: laplacian, multi") && Contains("failed: primo"));
  const std::string svg = edit_charts_svg(results, a, "bend");
  CHECK_THAT(svg, Contains("<svg") && Contains("★ arap") && Contains(">failed<") && Contains("frame time"));
  CHECK(edit_charts_svg(results, a, "no such edit").empty());
}

TEST_CASE("verdicts: a warning caps the verdict at fair, and a result without quality measures is not judged",
          "[compare][verdict]") {
  std::vector<MethodResult> results = {result("lift", "arap", 0.01, 0.02), result("lift", "primo", 0.01, 0.02)};
  results[1].warning = "primo: stopped after 1 iterations with relative residual 0.3";
  MethodResult cloud = result("lift", "rbf", 0, 0);
  cloud.rigidity.count = cloud.distortion.count = 0;
  cloud.not_measured = "point cloud: no faces";
  results.push_back(cloud);
  const std::vector<Assessment> a = assess(results);
  CHECK(a[0].verdict == Verdict::Good);
  CHECK(a[1].verdict == Verdict::Fair);
  CHECK_THAT(a[1].reason, Contains("warning: primo: stopped after 1 iterations"));
  CHECK(a[2].verdict == Verdict::NotJudged);
  CHECK_THAT(a[2].reason, Contains("point cloud: no faces"));
  CHECK_FALSE(a[2].best);
  CHECK(std::string(to_string(Verdict::NotJudged)) == "not-judged");
}

TEST_CASE("verdicts: a result whose self-intersections were not counted is not called unbroken", "[compare][verdict]") {
  // With the count refused (a fan too large for it) the summary said "good: the most rigid unbroken result".
  std::vector<MethodResult> results = {result("lift", "arap", 0.01, 0.02, -1), result("lift", "shell", 0.03, 0.02, -1)};
  const std::vector<Assessment> a = assess(results);
  CHECK(a[0].verdict == Verdict::Fair);
  CHECK(a[0].best);
  CHECK_THAT(a[0].reason, Contains("the most rigid result") && Contains("self-intersections not counted"));
  CHECK_THAT(a[0].reason, !Contains("unbroken"));
  CHECK(a[1].verdict == Verdict::Fair);
  CHECK_THAT(a[1].reason, Contains("rigidity 3× the edit's most rigid result") && !Contains("unbroken"));
  CHECK_THAT(verdict_summary(results, a), !Contains("unbroken"));
  // Compared with a result that was counted, the reference is unbroken.
  results[0].self_intersections = 0;
  const std::vector<Assessment> b = assess(results);
  CHECK_THAT(b[1].reason, Contains("rigidity 3× the edit's most rigid unbroken result"));
}

TEST_CASE("verdicts: the summary gives the best's verdict, and says when an edit has no usable result",
          "[compare][verdict]") {
  // The survey cylinder said "best arap" with ARAP in the poor list on the next line, and an edit whose
  // every result broke printed only its name.
  const std::vector<MethodResult> results = {
      result("cylinder", "arap", 0.01, 0.40),              // details changed by 40 %: poor, yet the best there
      result("cylinder", "shell", 0.001, 0.01, 3),         // broken
      result("camel", "shell", 0.01, 0.01, 12),            // broken
      result("camel", "rbf", 0.02, 0.01, 0, 5),            // broken
  };
  const std::vector<Assessment> a = assess(results);
  CHECK(a[0].best);
  CHECK(a[0].verdict == Verdict::Poor);
  const std::string summary = verdict_summary(results, a);
  CHECK_THAT(summary, Contains("cylinder: best arap (poor: details changed by 40 %"));
  CHECK_THAT(summary, Contains("camel: no usable result (every method failed or broke)"));
  // A point cloud: the space methods' results exist but have no quality measure.
  std::vector<MethodResult> cloud = {result("cloud", "lattice", 0, 0), result("cloud", "shell", 0, 0)};
  cloud[0].rigidity.count = cloud[0].distortion.count = 0;
  cloud[1].ok = false;
  cloud[1].error = "a surface method needs triangles";
  CHECK_THAT(verdict_summary(cloud, assess(cloud)), Contains("cloud: no result could be judged (see not-judged"));
}

TEST_CASE("verdicts: a closed mesh that lost or gained volume under rigid handles is fair or poor",
          "[compare][verdict]") {
  // The survey cylinder's 120° bend: the shell's result lost 51 % of the volume and its verdict named only
  // rigidity and detail change; ARAP lost 13 %.
  std::vector<MethodResult> results = {
      result("cylinder", "arap", 0.01, 0.02), result("cylinder", "shell", 0.01, 0.02),
      result("cylinder", "rbf", 0.01, 0.02), result("cylinder", "laplacian", 0.01, 0.02)};
  results[0].volume_change = -0.128;
  results[1].volume_change = -0.5106;
  results[2].volume_change = -0.20;
  results[3].volume_change = 30.27;
  const std::vector<Assessment> a = assess(results);
  CHECK(a[0].verdict == Verdict::Good);
  CHECK_THAT(a[0].reason, !Contains("volume"));
  CHECK(a[1].verdict == Verdict::Poor);
  CHECK_THAT(a[1].reason, Contains("volume changed by -51 %"));
  CHECK(a[2].verdict == Verdict::Fair);
  CHECK_THAT(a[2].reason, Contains("volume changed by -20 %"));
  // Laplacian editing ballooned the survey cactus to 31 times its volume, rated poor like a mild shear.
  CHECK(a[3].verdict == Verdict::Broken);
  CHECK_THAT(a[3].reason, Contains("volume changed by +3.03e+03 % (the shape is lost)"));
  CHECK(a[0].best);
  // An edit that scales handles asks for the volume to change, as much as they scale: handles shrunk 10
  // times and grown 40 times ask for volumes of x0.001 to x64000; a handle grown by 1.001 leaves the
  // changes judged as before (any scaling handle silenced the volume's verdict).
  for (MethodResult& r : results)
    r.scaling = edit_scaling({Mat4(Eigen::Vector4d(0.1, 0.1, 0.1, 1).asDiagonal()),
                              Mat4(Eigen::Vector4d(40, 40, 40, 1).asDiagonal())});
  const std::vector<Assessment> scaled = assess(results);
  for (int i : {0, 1, 2}) {
    CHECK(scaled[i].verdict == Verdict::Good);
    CHECK_THAT(scaled[i].reason, !Contains("volume"));
  }
  // What the handles ask does not excuse one result 27 times the others' volume: a scaled handle of one
  // vertex asks for any volume and changes nothing (it let the ballooned cactus pass as poor).
  CHECK(scaled[3].verdict == Verdict::Broken);
  for (MethodResult& r : results)
    r.scaling = edit_scaling({Mat4(Eigen::Vector4d(1.001, 1, 1, 1).asDiagonal())});
  CHECK(assess(results)[1].verdict == Verdict::Poor);
  CHECK_THAT(assess(results)[1].reason, Contains("volume changed by -51 %"));
}

TEST_CASE("verdicts: a result far less rigid than the edit's best and beyond a doubling is broken",
          "[compare][verdict]") {
  // The survey cactus under Laplacian editing: rigidity 5.98 (one-rings 3.4 times their size), rated poor
  // like propagation's mild shear at 0.024.
  std::vector<MethodResult> results = {
      result("cactus", "arap", 0.005, 0.02), result("cactus", "propagate", 0.024, 0.02),
      result("cactus", "laplacian", 5.98, 0.02), result("cactus", "cage", 0.5, 0.02)};
  std::vector<Assessment> a = assess(results);
  CHECK(a[1].verdict == Verdict::Poor);
  CHECK(a[2].verdict == Verdict::Broken);
  CHECK_THAT(a[2].reason, Contains("rigidity 5.98, 1196× the edit's most rigid result (the shape is lost)"));
  CHECK(a[3].verdict == Verdict::Poor);  // far less rigid, but below a doubling
  // A scaled handle that moves nothing (one vertex scaled about itself) changes nothing here.
  for (MethodResult& r : results) r.scaling = edit_scaling({Mat4(Eigen::Vector4d(4, 4, 4, 1).asDiagonal())});
  CHECK(assess(results)[2].verdict == Verdict::Broken);
  // A handle pulled to 4 times its distance from the fixed part: every method stretches alike, the most
  // rigid at 6.5 (all were broken, "no usable result").
  results = {result("pull", "arap", 6.49, 0.02), result("pull", "shell", 8.1, 0.02),
             result("pull", "laplacian", 9.3, 0.02)};
  for (MethodResult& r : results) r.volume_change = 3.27;
  a = assess(results);
  CHECK(a[0].best);  // poor for the volume the pull adds, as every result
  for (const Assessment& b : a) CHECK(b.verdict != Verdict::Broken);
}

TEST_CASE("verdicts: rigidity errors at rounding level are rigid, not hundreds of times the best",
          "[compare][verdict]") {
  // homer turned rigidly as a whole: shell 1.9e-31, gradient 1e-28, RBF 1.5e-22 were called poor (542×,
  // 43653×) by ratios of rounding noise.
  const std::vector<MethodResult> results = {result("turn", "shell", 1.9e-31, 0), result("turn", "gradient", 1e-28, 0),
                                             result("turn", "rbf", 1.5e-22, 0), result("turn", "laplacian", 5e-6, 0)};
  const std::vector<Assessment> a = assess(results);
  for (int i : {0, 1, 2}) {
    INFO(results[i].method << ": " << a[i].reason);
    CHECK(a[i].verdict == Verdict::Good);
    CHECK_THAT(a[i].reason, Contains("rigid (rigidity error"));
  }
  CHECK(a[3].verdict == Verdict::Poor);  // 5× the floor: a measurable stretch
  CHECK_THAT(a[3].reason, Contains("rigidity 5× the edit's most rigid unbroken result"));
}

TEST_CASE("compare: a result is broken by the intersections its edit added, not by the input's own",
          "[compare][verdict]") {
  // CGAL's cow intersects itself at rest (101 pairs): every method was called broken.
  EditCase edit = scene_case("lift", 2000);
  const Positions rest = edit.P;
  int near = 0;
  for (Eigen::Index v = 0; v < rest.rows(); ++v)
    if ((rest.row(v).head<2>() - Eigen::RowVector2d(0.05, 0.5)).norm() <
        (rest.row(near).head<2>() - Eigen::RowVector2d(0.05, 0.5)).norm())
      near = static_cast<int>(v);
  REQUIRE(edit.region.code(near) == Region::kFixed);
  // A small upright quad, fixed too, through the fixed part of the plane.
  const Vec3 p = rest.row(near);
  const long n = rest.rows();
  edit.P.conservativeResize(n + 4, 3);
  edit.P.row(n) << p.x() - 0.01, p.y(), p.z() - 0.05;
  edit.P.row(n + 1) << p.x() + 0.01, p.y(), p.z() - 0.05;
  edit.P.row(n + 2) << p.x() + 0.01, p.y(), p.z() + 0.05;
  edit.P.row(n + 3) << p.x() - 0.01, p.y(), p.z() + 0.05;
  const long nf = edit.F.rows();
  edit.F.conservativeResize(nf + 2, 3);
  edit.F.row(nf) << n, n + 1, n + 2;
  edit.F.row(nf + 1) << n, n + 2, n + 3;
  std::vector<int> codes;
  for (long v = 0; v < n; ++v) codes.push_back(edit.region.code(static_cast<int>(v)));
  codes.insert(codes.end(), 4, Region::kFixed);
  edit.region = Region::from_codes(codes);
  ComparisonOptions options;
  options.methods = {"shell"};
  options.reference.clear();
  const std::vector<MethodResult> results = compare_methods(edit, options);
  REQUIRE(results.size() == 1);
  REQUIRE(results[0].ok);
  CHECK(results[0].rest_self_intersections > 0);
  CHECK(results[0].self_intersections == 0);
  CHECK(assess(results)[0].verdict != Verdict::Broken);
}

TEST_CASE("verdicts: under handles that scale, the detail heights are not judged against the rest's",
          "[compare][verdict]") {
  // The survey cylinder with a handle scaled by 3: every result read "poor: details changed by 650–910 %".
  std::vector<MethodResult> results = {result("scaled", "arap", 0.01, 9.1),
                                       result("scaled", "shell", 0.015, 6.5)};
  for (MethodResult& r : results) r.scaling = edit_scaling({Mat4(Eigen::Vector4d(3, 3, 3, 1).asDiagonal())});
  const std::vector<Assessment> a = assess(results);
  CHECK(a[0].verdict == Verdict::Good);
  CHECK(a[1].verdict == Verdict::Good);
  CHECK_THAT(a[0].reason, Contains("detail change not judged (the handles scale the shape"));
  CHECK_THAT(a[0].reason, !Contains("details changed"));
  for (MethodResult& r : results) r.scaling = {};
  CHECK(assess(results)[0].verdict == Verdict::Poor);
  // A scale of 1 % allows 1 % more change, no more (it switched the detail verdict off: 24 % read good).
  results = {result("lift", "propagate", 0.01, 0.24)};
  results[0].scaling = edit_scaling({Mat4(Eigen::Vector4d(1.01, 1.01, 1.01, 1).asDiagonal())});
  CHECK(assess(results)[0].verdict == Verdict::Fair);
  CHECK_THAT(assess(results)[0].reason, Contains("details changed by 24 %"));
}

TEST_CASE("verdicts: a volume far beyond what the handles ask is broken whatever else ran",
          "[compare][verdict]") {
  // The ballooned cactus alone, or beside a self-intersecting shell, was rated "best, poor".
  std::vector<MethodResult> results = {result("cactus", "laplacian", 5.98, 0.02)};
  results[0].volume_change = 30.27;
  CHECK(assess(results)[0].verdict == Verdict::Broken);
  results.push_back(result("cactus", "shell", 0.11, 0.02, 207));
  results[1].volume_change = -0.12;
  const std::vector<Assessment> a = assess(results);
  CHECK(a[0].verdict == Verdict::Broken);
  CHECK_THAT(a[0].reason, Contains("× the edit's most rigid result (the shape is lost)"));
  CHECK_FALSE(a[0].best);
  // A handle pulled 4 times its distance, one method alone: stretched as asked, not broken.
  results = {result("pull", "arap", 6.49, 0.02)};
  results[0].volume_change = 3.27;
  CHECK(assess(results)[0].verdict != Verdict::Broken);
}
