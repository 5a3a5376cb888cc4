#include "apps/compare/runner.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <memory>
#include <new>
#include <optional>
#include <utility>

#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"

namespace msd {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

std::string format(const char* fmt, double x) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), fmt, x);
  return buf;
}

// What went wrong, for a result's page: std::bad_alloc's own text is "std::bad_alloc".
std::string failure(const std::exception& e) {
  return dynamic_cast<const std::bad_alloc*>(&e) ? "out of memory" : e.what();
}

}  // namespace

void check_comparison(const ComparisonOptions& options) {
  const std::vector<std::string>& methods = options.methods;
  if (methods.empty()) throw InvalidInput("no method to compare");
  for (size_t i = 0; i < methods.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (methods[i] == methods[j]) throw InvalidInput("method '" + methods[i] + "' is listed twice");
  for (const auto& m : methods) builtin_methods().find(m);  // throws for an unknown name, listing the known ones
  if (!options.reference.empty() && std::find(methods.begin(), methods.end(), options.reference) == methods.end())
    throw InvalidInput("the reference method '" + options.reference + "' is not among the compared methods");
}

std::vector<MethodResult> compare_methods(const EditCase& edit, const ComparisonOptions& options) {
  check_comparison(options);
  const Positions& rest = edit.P;
  const Faces& F = edit.F;
  // The rest-shape side of the metrics, once for every method. A metric this input cannot give is left
  // out, with the reason each result then carries; it never fails a method.
  std::vector<std::string> unmeasured;  // reasons that hold for every result of this edit
  std::optional<RigidityMetric> rigidity;
  std::optional<DetailDistortionMetric> distortion;
  std::optional<VolumeChangeMetric> volume;
  const bool has_faces = F.rows() > 0;
  // Runs one metric's step; if it throws, the metric is not measured and `reasons` says why.
  auto attempt = [](std::vector<std::string>& reasons, const char* metric, auto&& step) {
    try {
      step();
    } catch (const std::exception& e) {
      reasons.push_back(std::string(metric) + " not measured: " + failure(e));
    }
  };
  if (!has_faces) {
    unmeasured.push_back(
        "point cloud: no faces, so rigidity, detail distortion, self-intersections and volume change are not "
        "measured");
  } else {
    attempt(unmeasured, "rigidity", [&] { rigidity.emplace(rest, F); });
    attempt(unmeasured, "detail distortion", [&] { distortion.emplace(rest, F, edit.region); });
    attempt(unmeasured, "volume change", [&] { volume.emplace(rest, F); });
  }
  // CGAL's count needs a manifold, consistently oriented surface, which depends on the faces alone: once
  // it has refused them, it is not asked again.
  std::string self_intersections_refused;
  // A scan may intersect itself already: a result is judged by the pairs the edit added.
  std::optional<AddedSelfIntersections> added;
  if (options.self_intersections && has_faces) {
    try {
      added.emplace(rest, F);
    } catch (const InvalidInput& e) {
      self_intersections_refused = std::string(e.what()) + " (--no-self-intersections)";
    }
  }
  std::vector<MethodResult> results;
  // The multi-scale encodings decompose this mesh alike: the low-pass base is computed once.
  const auto low_pass_cache = std::make_shared<LowPassCache>();
  bool outliers_said = false;
  for (const auto& method : options.methods) {
    MethodResult r;
    r.scene = edit.name;
    r.method = method;
    r.vertices = static_cast<int>(rest.rows());
    r.scaling = edit_scaling(edit.transforms);
    try {
      MethodSettings settings = options.settings;
      if (settings.decomposition.kind == DecompositionKind::Subdivision && !settings.decomposition.control)
        settings.decomposition.control = edit.control;
      if (!settings.decomposition.low_pass_cache) settings.decomposition.low_pass_cache = low_pass_cache;
      auto deformer = builtin_methods().make(method, settings);
      if (deformer->traits().domain == DeformerDomain::Surface && !edit.surface_problem.empty()) {
        r.refused_input = true;
        require_surface(edit, method);  // throws, saying why
      }
      auto t0 = Clock::now();
      deformer->prepare(edit.P, edit.F, edit.region);
      r.prepare_ms = ms_since(t0);
      // A base taken from the cache counts as computed, so the encodings' prepare times stay comparable.
      if (const auto* ms = dynamic_cast<const MultiscaleDeformer*>(deformer.get()))
        if (ms->decomposition_report().low_pass.reused) r.prepare_ms += 1e3 * ms->decomposition_report().low_pass.seconds;
      // Linear methods: a warm-up frame, then the timed ones. Iterative methods: one frame from rest (a
      // second frame would start from the first's result and measure a different, shorter solve).
      const bool iterative = deformer->traits().solve == DeformerSolve::Iterative;
      if (!iterative) deformer->deform(edit.transforms, r.result);
      std::vector<double> frames;
      for (int f = 0; f < (iterative ? 1 : std::max(1, options.timed_frames)); ++f) {
        t0 = Clock::now();
        deformer->deform(edit.transforms, r.result);
        frames.push_back(ms_since(t0));
      }
      std::sort(frames.begin(), frames.end());
      r.frame_ms = frames[frames.size() / 2];
      const FrameReport& report = deformer->frame_report();
      r.folded_faces = report.folded_faces;
      r.iterations = report.iterations;
      for (const auto* list : {&deformer->prepare_warnings(), &report.warnings})
        for (const std::string& w : *list) {
          // Stray vertices are the input's: said by the first method that ran, not by each.
          if (w.find(kOutlierWarning) != std::string::npos && std::exchange(outliers_said, true)) continue;
          r.warning += (r.warning.empty() ? "" : "; ") + w;
        }
      if (!r.result.allFinite()) throw Error(method + " returned a non-finite position");
      r.handle_error = handle_error(rest, r.result, edit.region, edit.transforms);
      r.ok = true;
    } catch (const std::exception& e) {
      r.ok = false;
      r.error = failure(e);
    }
    if (r.ok) {
      std::vector<std::string> lacking = unmeasured;
      if (rigidity) attempt(lacking, "rigidity", [&] { r.rigidity = rigidity->measure(r.result).stats; });
      if (distortion)
        attempt(lacking, "detail distortion", [&] {
          DetailDistortion d = distortion->measure(r.result);
          r.distortion = d.stats;
          r.distortion_per_vertex = std::move(d.per_vertex);
        });
      if (options.self_intersections && has_faces) {
        if (self_intersections_refused.empty()) {
          try {
            r.self_intersections = added->count(r.result, &r.self_intersecting_faces);
            r.rest_self_intersections = added->rest_pairs();
          } catch (const InvalidInput& e) {
            self_intersections_refused = e.what();  // the faces, as the result is finite: so for every result
          } catch (const std::exception& e) {
            lacking.push_back("self-intersections not measured: " + failure(e));
          }
        }
        if (!self_intersections_refused.empty())
          lacking.push_back("self-intersections not measured: " + self_intersections_refused);
      }
      if (volume) attempt(lacking, "volume change", [&] { r.volume_change = volume->measure(r.result); });
      for (const std::string& reason : lacking) r.not_measured += (r.not_measured.empty() ? "" : "; ") + reason;
    }
    if (options.progress)
      options.progress(edit.name + " / " + method + ": " +
                       (r.ok ? format("prepare %.0f ms", r.prepare_ms) + format(", frame %.2f ms", r.frame_ms)
                             : "FAILED: " + r.error));
    results.push_back(std::move(r));
  }
  for (const MethodResult& ref : results)
    if (ref.ok && ref.method == options.reference)
      for (MethodResult& r : results)
        if (r.ok) r.reference = distance_to_reference(r.result, F, ref.result, F);
  return results;
}

const MethodResult* best_multiscale(const std::vector<MethodResult>& results, const std::string& scene) {
  const MethodResult* best = nullptr;
  auto score = [](const MethodResult& r) { return r.reference ? r.reference->mean : r.distortion.mean; };
  for (const MethodResult& r : results)
    if (r.ok && r.scene == scene && is_multiscale(r.method) && (!best || score(r) < score(*best)))
      best = &r;
  return best;
}

namespace {

struct Column {
  const char* name;
  std::function<std::string(const MethodResult&)> value;
};

std::vector<Column> columns() {
  auto g = [](double x) { return format("%.4g", x); };
  // A measured column: empty for a failed run, which has no figures (a 0 there would read as perfect).
  using Value = std::function<std::string(const MethodResult&)>;
  auto measured = [](Value f) -> Value { return [f](const MethodResult& r) { return r.ok ? f(r) : std::string(); }; };
  auto count = [](int n) { return n < 0 ? std::string("n/a") : std::to_string(n); };
  // A summary of no values was not measured (MethodResult::not_measured says why).
  auto stat = [=](const Stats& s, double x) { return s.count > 0 ? g(x) : std::string("n/a"); };
  return {
      {"scene", [](const MethodResult& r) { return r.scene; }},
      {"method", [](const MethodResult& r) { return r.method; }},
      {"vertices", [](const MethodResult& r) { return std::to_string(r.vertices); }},
      {"ok", [](const MethodResult& r) { return std::string(r.ok ? "yes" : "no"); }},
      {"prepare_ms", measured([=](const MethodResult& r) { return g(r.prepare_ms); })},
      {"frame_ms", measured([=](const MethodResult& r) { return g(r.frame_ms); })},
      {"handle_error", measured([=](const MethodResult& r) { return g(r.handle_error); })},
      {"rigidity_mean", measured([=](const MethodResult& r) { return stat(r.rigidity, r.rigidity.mean); })},
      {"rigidity_p95", measured([=](const MethodResult& r) { return stat(r.rigidity, r.rigidity.p95); })},
      {"rigidity_max", measured([=](const MethodResult& r) { return stat(r.rigidity, r.rigidity.max); })},
      {"distortion_mean", measured([=](const MethodResult& r) { return stat(r.distortion, r.distortion.mean); })},
      {"distortion_p95", measured([=](const MethodResult& r) { return stat(r.distortion, r.distortion.p95); })},
      {"distortion_max", measured([=](const MethodResult& r) { return stat(r.distortion, r.distortion.max); })},
      {"self_intersections", measured([=](const MethodResult& r) { return count(r.self_intersections); })},
      {"rest_self_intersections",
       measured([=](const MethodResult& r) { return count(r.self_intersections < 0 ? -1 : r.rest_self_intersections); })},
      // Multi-scale methods count the triangles that folded over the deformed base; others do not (n/a).
      {"folded_faces", measured([=](const MethodResult& r) { return count(r.folded_faces); })},
      {"volume_change", measured([=](const MethodResult& r) { return r.volume_change ? g(*r.volume_change) : std::string("n/a"); })},
      // Distance to the reference method's result (relative to its diagonal), when a reference ran.
      {"reference_max", measured([=](const MethodResult& r) { return r.reference ? g(r.reference->max) : std::string("n/a"); })},
      {"reference_mean", measured([=](const MethodResult& r) { return r.reference ? g(r.reference->mean) : std::string("n/a"); })},
      {"not_measured", [](const MethodResult& r) { return r.not_measured; }},  // why cells read n/a
      {"message", [](const MethodResult& r) { return r.ok ? r.warning : r.error; }},  // error, or warning
  };
}

}  // namespace

std::vector<std::string> measurement_notes(const std::vector<MethodResult>& results) {
  std::vector<std::string> notes;
  for (const MethodResult& r : results) {
    if (r.not_measured.empty()) continue;
    std::string note = r.scene + ": " + r.not_measured;
    if (std::find(notes.begin(), notes.end(), note) == notes.end()) notes.push_back(std::move(note));
  }
  return notes;
}

std::vector<std::vector<std::string>> metrics_table(const std::vector<MethodResult>& results) {
  const auto cols = columns();
  std::vector<std::vector<std::string>> table(1);
  for (const auto& c : cols) table[0].push_back(c.name);
  for (const auto& r : results) {
    table.emplace_back();
    for (const auto& c : cols) table.back().push_back(c.value(r));
  }
  return table;
}

std::string metrics_csv(const std::vector<MethodResult>& results) {
  std::string out;
  for (const auto& row : metrics_table(results)) {
    for (size_t c = 0; c < row.size(); ++c) {
      std::string v = row[c];
      if (v.find_first_of(",\"\n") != std::string::npos) {  // quote per RFC 4180
        std::string q = "\"";
        for (char ch : v) q += ch == '"' ? std::string("\"\"") : std::string(1, ch == '\n' ? ' ' : ch);
        v = q + "\"";
      }
      out += (c ? "," : "") + v;
    }
    out += '\n';
  }
  return out;
}

std::string metrics_markdown(const std::vector<MethodResult>& results) {
  const auto table = metrics_table(results);
  std::string out;
  for (const std::string& note : measurement_notes(results)) out += note + "\n\n";
  for (size_t r = 0; r < table.size(); ++r) {
    out += "|";
    for (std::string v : table[r]) {
      for (auto& ch : v)
        if (ch == '|' || ch == '\n') ch = ' ';
      out += " " + v + " |";
    }
    out += '\n';
    if (r == 0) {
      out += "|";
      for (size_t c = 0; c < table[0].size(); ++c) out += "---|";
      out += '\n';
    }
  }
  return out;
}

}  // namespace msd
