// The seed's §9.7 findings (Fig. 9.16) as measured facts on the Botsch & Sorkine 2008 benchmark files
// (../shared/data/survey): the pure translation of the bumpy plane, the 120° bend of the cylinder and the
// 135° twist of the bar, each method measured against the nonlinear reference (kReference). Thresholds
// come from the figures measured on 2026-11-30 (in the comments), with margins.
#include <catch2/catch.hpp>


#include "apps/compare/runner.h"
#include "golden.h"
#include "msdeform/core/edge_scale.h"
#include "test_util.h"

using namespace msd;

namespace {

const std::string kReference = "arap";
const char* const kEdits[] = {"plane", "cylinder", "bar"};  // translation, 120° bend, 135° twist

struct Figure {
  std::vector<EditCase> cases;
  std::vector<MethodResult> results;
};

const Figure& figure() {
  static const Figure f = [] {
    Figure f;
    ComparisonOptions o;
    o.methods = {kReference, "shell", "multiscale-vectors", "multiscale-normal", "multiscale-volumes",
                 "multiscale-transfer", "gradient", "laplacian", "propagate"};
    if (kReference != "arap") o.methods.push_back("arap");
    o.reference = kReference;
    o.timed_frames = 1;
    for (const char* name : kEdits) {
      const std::string base = test::shared_data(std::string("survey/") + name);
      f.cases.push_back(file_case(base + ".off", base + ".sel", base + ".def"));
      const auto r = compare_methods(f.cases.back(), o);
      f.results.insert(f.results.end(), r.begin(), r.end());
    }
    return f;
  }();
  return f;
}

const MethodResult& result(const std::string& edit, const std::string& method) {
  if (method == "multiscale") {
    const MethodResult* r = best_multiscale(figure().results, edit);
    REQUIRE(r);
    return *r;
  }
  const MethodResult& r = test::find_result(figure().results, edit, method);
  REQUIRE(r.ok);
  return r;
}

// Mean distance to the reference over the bounding-box diagonal.
double to_reference(const std::string& edit, const std::string& method) {
  const MethodResult& r = result(edit, method);
  REQUIRE(r.reference);
  return r.reference->mean;
}

// exp(mean |log(ℓ'/ℓ)|) over the edges with a free end: 1 when no edge around the free region changed length.
double edge_scale_change(const std::string& edit, const std::string& method) {
  const EditCase* c = nullptr;
  for (const EditCase& e : figure().cases)
    if (e.name == edit) c = &e;
  REQUIRE(c);
  return FreeEdgeLengths(c->P, c->F, c->region).mean_scale(result(edit, method).result);
}

}  // namespace

TEST_CASE("Fig. 9.16: every method meets its handles on the three survey edits", "[regression][figure916]") {
  for (const char* edit : kEdits)
    for (const MethodResult& r : figure().results)
      if (r.scene == edit) {
        INFO(edit << " / " << r.method << ": " << r.error);
        CHECK(r.ok);
        CHECK(r.handle_error <= 1e-9);
      }
}

TEST_CASE("Fig. 9.16: shell + multi-scale is close to the reference under translation, far under bend and twist",
          "[regression][figure916]") {
  const double plane = to_reference("plane", "multiscale"), cylinder = to_reference("cylinder", "multiscale"),
               bar = to_reference("bar", "multiscale");
  INFO("mean distance to " << kReference << ": plane " << plane << ", cylinder " << cylinder << ", bar " << bar);
  // Measured: 0.0179, 0.0904, 0.0419.
  CHECK(plane < 0.025);
  CHECK(plane < 0.3 * cylinder);
  CHECK(plane < 0.6 * bar);
}

TEST_CASE("Fig. 9.16: gradient-based editing is close under the rotations, not under the pure translation",
          "[regression][figure916]") {
  // Translation insensitivity: a translated handle has the identity as its gradient, so the Poisson
  // solve only spreads the translation (harmonically, as propagation does) and shears the details.
  // Measured mean distances: plane 0.0413 (multi-scale 0.0179), cylinder 0.0719 (0.0904), bar 0.0278 (0.0419);
  // detail distortion on the plane 0.234 against multi-scale's 0.0188.
  CHECK(to_reference("plane", "gradient") > 1.8 * to_reference("plane", "multiscale"));
  CHECK(result("plane", "gradient").distortion.mean > 5 * result("plane", "multiscale").distortion.mean);
  CHECK(to_reference("plane", "gradient") == Approx(to_reference("plane", "propagate")).epsilon(0.02));
  CHECK(to_reference("cylinder", "gradient") < 0.9 * to_reference("cylinder", "multiscale"));
  CHECK(to_reference("bar", "gradient") < 0.8 * to_reference("bar", "multiscale"));
}

TEST_CASE("Fig. 9.16: Laplacian editing handles translation and bend but scales the surface under rotation",
          "[regression][figure916]") {
  // Measured mean distances: plane 0.0363 (gradient 0.0413), cylinder 0.0818 (shell + multi-scale 0.0904).
  // The linearised rotations (9.11) scale the surface where the edit rotates it: mean edge-length change
  // ×S around the free vertices, measured S = 1.161 on the plane (translated), 1.559 on the bar (twisted),
  // against 1.024 for the reference on the bar.
  CHECK(to_reference("plane", "laplacian") < to_reference("plane", "gradient"));
  CHECK(to_reference("cylinder", "laplacian") < to_reference("cylinder", "multiscale"));
  const double plane = edge_scale_change("plane", "laplacian"), bar = edge_scale_change("bar", "laplacian");
  INFO("edge scale change: plane " << plane << ", bar " << bar << ", bar reference " << edge_scale_change("bar", kReference));
  CHECK(plane < 1.2);
  CHECK(bar > 1.4);
  CHECK(edge_scale_change("bar", kReference) < 1.1);
}

TEST_CASE("Fig. 9.16: the nonlinear methods are the most rigid on all three edits", "[regression][figure916]") {
  // Measured rigidity (one-ring rotation residual, mean): ARAP plane 4.7e-5, cylinder 0.0030, bar 0.0035;
  // the most rigid linear method 0.0032 (multi-scale), 0.0429 (gradient), 0.0093 (gradient).
  for (const char* edit : kEdits) {
    double best_linear = 1e300;
    for (const std::string m : {"shell", "multiscale", "gradient", "laplacian", "propagate"})
      best_linear = std::min(best_linear, result(edit, m).rigidity.mean);
    const double nonlinear = result(edit, kReference).rigidity.mean;
    INFO(edit << ": " << kReference << " " << nonlinear << ", most rigid linear method " << best_linear);
    CHECK(nonlinear < 0.5 * best_linear);
  }
}

TEST_CASE("Fig. 9.16: on the bend, PriMo (the seed's reference) is the most rigid and ARAP the closest to it",
          "[regression][figure916]") {
  // PriMo takes about 2 minutes on the 40k-vertex plane and 50 s on the bar, so it runs here on the
  // cylinder only (about 25 s). Measured: PriMo rigidity 0.0035 against 0.043 (gradient) to 0.124
  // (Laplacian); mean distance to PriMo: ARAP 0.0072, the linear methods 0.072 (gradient) to 0.092 (shell).
  ComparisonOptions o;
  o.methods = {"primo", "arap", "shell", "gradient", "laplacian", "propagate"};
  o.reference = "primo";
  o.timed_frames = 1;
  const std::vector<MethodResult> results = compare_methods(figure().cases[1], o);
  const MethodResult& primo = test::find_result(results, "cylinder", "primo");
  INFO(primo.error << " " << primo.warning);
  REQUIRE(primo.ok);
  CHECK(primo.handle_error <= 1e-9);
  CHECK(primo.warning.empty());
  const double arap = test::find_result(results, "cylinder", "arap").reference->mean;
  for (const std::string m : {"shell", "gradient", "laplacian", "propagate"}) {
    const MethodResult& r = test::find_result(results, "cylinder", m);
    INFO(m << ": rigidity " << r.rigidity.mean << " (PriMo " << primo.rigidity.mean << "), mean distance to PriMo "
           << r.reference->mean << " (ARAP " << arap << ")");
    CHECK(primo.rigidity.mean < 0.25 * r.rigidity.mean);
    CHECK(arap < 0.25 * r.reference->mean);
  }
}
