#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "apps/compare/verdict.h"

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
