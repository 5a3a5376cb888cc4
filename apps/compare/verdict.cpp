#include "apps/compare/verdict.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>
#include <tuple>

namespace msd {
namespace {

std::string fmt(const char* f, double x) {
  char text[64];
  std::snprintf(text, sizeof text, f, x);
  return text;
}

const char* colour(Verdict v) {
  switch (v) {
    case Verdict::Good: return "#5cb85c";
    case Verdict::Fair: return "#c6d64a";
    case Verdict::Poor: return "#f0a030";
    case Verdict::Broken: return "#d9362b";
    case Verdict::NotJudged: return "#9fb3c8";
    default: return "#9e9e9e";
  }
}

// A message for a cell: at most 300 characters, cut at a space.
std::string shortened(const std::string& text) {
  if (text.size() <= 300) return text;
  const size_t cut = text.rfind(' ', 300);
  return text.substr(0, cut == std::string::npos ? 300 : cut) + " …";
}

// Results of one scene, by index into `results`, in their order.
std::vector<size_t> of_scene(const std::vector<MethodResult>& results, const std::string& scene) {
  std::vector<size_t> out;
  for (size_t i = 0; i < results.size(); ++i)
    if (results[i].scene == scene) out.push_back(i);
  return out;
}

}  // namespace

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) out += c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '&' ? "&amp;" : std::string(1, c);
  return out;
}

const char* to_string(Verdict v) {
  switch (v) {
    case Verdict::Good: return "good";
    case Verdict::Fair: return "fair";
    case Verdict::Poor: return "poor";
    case Verdict::Broken: return "broken";
    case Verdict::NotJudged: return "not-judged";
    default: return "failed";
  }
}

std::vector<Assessment> assess(const std::vector<MethodResult>& results, const VerdictThresholds& t) {
  std::vector<Assessment> out(results.size());
  std::vector<std::string> scenes;
  for (const MethodResult& r : results)
    if (std::find(scenes.begin(), scenes.end(), r.scene) == scenes.end()) scenes.push_back(r.scene);
  for (const std::string& scene : scenes) {
    const std::vector<size_t> ids = of_scene(results, scene);
    // Self-intersections and folds break a result outright. It also lost the shape where its rigidity or
    // its volume is both far off in absolute terms and far worse than the edit's best result: an edit may
    // ask for any stretch (a handle pulled 4 times its distance from the fixed part, a scaled handle), and
    // then every method stretches alike. A volume beyond broken_volume_alone times what the handles ask is
    // lost whatever else ran (the ballooned cactus run alone, or beside a torn result, was "best").
    const auto volume_factor =
        [](const MethodResult& r) {  // V'/V as a factor >= 1 either way (1: not judged)
          if (!r.volume_change || r.scaling.mirrors) return 1.0;
          const double ratio = 1 + *r.volume_change;
          return ratio > 0 ? std::max(ratio, 1 / ratio) : INFINITY;
        };
    double least_rigidity = INFINITY, least_volume = INFINITY;
    for (size_t i : ids) {
      const MethodResult& r = results[i];
      if (!r.ok) continue;
      if (r.rigidity.count > 0)
        least_rigidity = std::min(least_rigidity, std::max(r.rigidity.mean, t.rigid_floor));
      least_volume = std::min(least_volume, volume_factor(r));
    }
    // Why a result is broken (empty: it is not).
    auto lost_shape = [&](const MethodResult& r) {
      std::string why;
      const auto add = [&](const std::string& text) { why += (why.empty() ? "" : "; ") + text; };
      if (r.self_intersections > 0)
        add(std::to_string(r.self_intersections) + " self-intersecting triangle pairs" +
            (r.rest_self_intersections > 0
                 ? " besides the input's own " + std::to_string(r.rest_self_intersections)
                 : std::string()));
      if (r.folded_faces > 0)
        add(std::to_string(r.folded_faces) + (r.folded_faces == 1 ? " triangle" : " triangles") +
            " folded over the base");
      if (r.rigidity.count > 0 && r.rigidity.mean > t.broken_rigidity &&
          r.rigidity.mean > t.broken_rigidity_ratio * least_rigidity)
        add("rigidity " + fmt("%.3g", r.rigidity.mean) + ", " +
            fmt("%.0f", r.rigidity.mean / least_rigidity) +
            "× the edit's most rigid result (the shape is lost)");
      const double f = volume_factor(r);
      const bool beyond_asked =
          f > 1 && (1 + *r.volume_change > t.broken_volume_alone * r.scaling.volume_high ||
                    (1 + *r.volume_change) * t.broken_volume_alone < r.scaling.volume_low);
      if ((f > t.broken_volume && f > t.broken_volume * least_volume) || beyond_asked)
        add("volume changed by " + fmt("%+.3g", 100 * *r.volume_change) + " % (the shape is lost)");
      return why;
    };
    auto broken = [&](const MethodResult& r) { return !lost_shape(r).empty(); };
    double best_rigidity = INFINITY;
    bool best_counted = true;  // the most rigid result had its self-intersections counted (else: not known unbroken)
    for (size_t i : ids)
      if (results[i].ok && !broken(results[i]) && results[i].rigidity.count > 0 &&
          results[i].rigidity.mean < best_rigidity) {
        best_rigidity = results[i].rigidity.mean;
        best_counted = results[i].self_intersections >= 0;
      }
    const std::string most_rigid = best_counted ? "most rigid unbroken result" : "most rigid result";
    for (size_t i : ids) {
      const MethodResult& r = results[i];
      Assessment& a = out[i];
      if (!r.ok) {
        a = {Verdict::Failed, shortened(r.error), false};
        continue;
      }
      if (broken(r)) {
        a.verdict = Verdict::Broken;
        a.reason = lost_shape(r);
        continue;
      }
      // Without a self-intersection count, nothing says the result is unbroken: at most fair, and said so.
      const bool intersections_counted = r.self_intersections >= 0;
      std::vector<std::string> poor, fair, good;
      if (r.rigidity.count > 0 && std::isfinite(best_rigidity)) {
        const double ratio = r.rigidity.mean / std::max(best_rigidity, t.rigid_floor);
        const std::string times = fmt(ratio < 10 ? "%.2g" : "%.0f", ratio);
        // Relative to the unbroken results only: a broken one may well be more rigid (ARAP through itself).
        const std::string text =
            "rigidity " + times + "× the edit's " + most_rigid + " (the shape shears or stretches)";
        if (ratio > t.poor_rigidity) poor.push_back(text);
        else if (ratio > t.fair_rigidity) fair.push_back(text);
        else
          good.push_back(r.rigidity.mean <= t.rigid_floor ? "rigid (rigidity error " + fmt("%.2g", r.rigidity.mean) + ")"
                         : ratio <= 1 ? "the " + (intersections_counted ? most_rigid : "most rigid result")
                                  : "rigid (" + fmt("%.2g", ratio) + "× the " + most_rigid + ")");
      }
      // Heights are measured against the rest's: handles that scale by s ask the details to change by up to
      // |s − 1| of their height, which is allowed; beyond scale_tolerance the measure says little (every
      // result of a cylinder scaled by 3 read "poor: details changed by 650–910 %") and is not judged.
      const double scaled = std::max(r.scaling.growth, r.scaling.shrink) - 1;
      const bool judge_details = r.distortion.count > 0 && !(scaled > t.scale_tolerance);
      if (judge_details) {
        const double d = std::max(0.0, r.distortion.mean - std::max(0.0, scaled));  // beyond what is asked
        const std::string measured = fmt("%.2g", 100 * r.distortion.mean) + " %";
        const std::string text = "details changed by " + measured + " of their height";
        if (d > t.poor_distortion) poor.push_back(text);
        else if (d > t.fair_distortion) fair.push_back(text);
        else
          good.push_back("details kept (" + measured + ")");
      }
      // The volume changes as much as the handles' scales ask (EditScaling), up to the shape's give (ARAP
      // loses 13 % on the survey cylinder's 120° bend); a mirrored handle turns its sign (not judged).
      if (r.volume_change && !r.scaling.mirrors) {
        const double v = r.scaling.volume_excess(1 + *r.volume_change);
        const std::string text = "volume changed by " + fmt("%+.2g", 100 * *r.volume_change) + " %";
        if (v > t.poor_volume)
          poor.push_back(text);
        else if (v > t.fair_volume)
          fair.push_back(text);
      }
      if (r.rigidity.count == 0 && !judge_details) {
        a.verdict = Verdict::NotJudged;
        a.reason = "no rigidity or detail measure for this input" +
                   (r.not_measured.empty() ? std::string() : " (" + shortened(r.not_measured) + ")");
      } else {
        const std::vector<std::string>& why = !poor.empty() ? poor : !fair.empty() ? fair : good;
        a.verdict = !poor.empty() ? Verdict::Poor : !fair.empty() ? Verdict::Fair : Verdict::Good;
        for (const std::string& w : why) a.reason += (a.reason.empty() ? "" : "; ") + w;
        if ((!r.warning.empty() || !intersections_counted) && a.verdict == Verdict::Good) a.verdict = Verdict::Fair;
        if (!intersections_counted) a.reason += "; self-intersections not counted";
      }
      if (r.distortion.count > 0 && !judge_details)
        a.reason += "; detail change not judged (the handles scale the shape, and its details with it)";
      if (!r.warning.empty()) a.reason += "; warning: " + shortened(r.warning);
    }
    // Best: the most rigid unbroken result of the best verdict present, then the least distortion.
    long best = -1;
    for (size_t i : ids) {
      const Assessment& a = out[i];
      if (a.verdict == Verdict::Failed || a.verdict == Verdict::Broken || a.verdict == Verdict::NotJudged) continue;
      if (best < 0) {
        best = static_cast<long>(i);
        continue;
      }
      const auto key = [&](size_t k) {
        const MethodResult& r = results[k];
        return std::make_tuple(static_cast<int>(out[k].verdict), r.rigidity.count > 0 ? r.rigidity.mean : INFINITY,
                               r.distortion.count > 0 ? r.distortion.mean : INFINITY);
      };
      if (key(i) < key(static_cast<size_t>(best))) best = static_cast<long>(i);
    }
    if (best >= 0) out[best].best = true;
  }
  return out;
}

std::string verdict_summary(const std::vector<MethodResult>& results, const std::vector<Assessment>& assessments) {
  std::ostringstream s;
  std::vector<std::string> scenes;
  for (const MethodResult& r : results)
    if (std::find(scenes.begin(), scenes.end(), r.scene) == scenes.end()) scenes.push_back(r.scene);
  for (const std::string& scene : scenes) {
    const std::vector<size_t> ids = of_scene(results, scene);
    s << scene << ":";
    bool any_best = false;
    for (size_t i : ids)
      if (assessments[i].best) {  // the verdict too: the best of an edit can be fair or poor
        s << " best " << results[i].method << " (" << to_string(assessments[i].verdict) << ": "
          << assessments[i].reason << "; " << fmt("%.3g", results[i].frame_ms) << " ms per frame)";
        any_best = true;
      }
    const bool any_unjudged = std::any_of(ids.begin(), ids.end(),
                                          [&](size_t i) { return assessments[i].verdict == Verdict::NotJudged; });
    const bool none_ran =
        std::all_of(ids.begin(), ids.end(), [&](size_t i) { return results[i].refused_input; });
    if (!any_best)
      s << (none_ran ? " no method could run: the input is not a surface (space methods take it: lattice, "
                       "cage-mvc, cage-harmonic, rbf)"
            : any_unjudged
                ? " no result could be judged (see not-judged below: no quality measure for this input)"
                : " no usable result (every method failed or broke)");
    s << "\n";
    for (Verdict v :
         {Verdict::Good, Verdict::Fair, Verdict::Poor, Verdict::Broken, Verdict::NotJudged, Verdict::Failed}) {
      std::string names, refused;
      for (size_t i : ids)
        if (assessments[i].verdict == v) {
          std::string& list = results[i].refused_input ? refused : names;
          list += (list.empty() ? "" : ", ") + results[i].method;
        }
      if (!names.empty()) s << "  " << to_string(v) << ": " << names << "\n";
      if (!refused.empty())
        s << "  not run (surface methods; the input is not a surface): " << refused << "\n";
    }
  }
  return s.str();
}

std::string edit_charts_svg(const std::vector<MethodResult>& results, const std::vector<Assessment>& assessments,
                            const std::string& scene) {
  const std::vector<size_t> ids = of_scene(results, scene);
  if (ids.empty()) return "";
  struct Panel {
    const char* title;
    bool log;
    std::function<double(const MethodResult&)> value;  // < 0: not measured
  };
  const Panel panels[] = {
      {"rigidity (mean)", false, [](const MethodResult& r) { return r.rigidity.count > 0 ? r.rigidity.mean : -1; }},
      {"detail change (mean)", false,
       [](const MethodResult& r) { return r.distortion.count > 0 ? r.distortion.mean : -1; }},
      {"self-intersecting pairs", false,
       [](const MethodResult& r) { return r.self_intersections < 0 ? -1.0 : double(r.self_intersections); }},
      {"frame time [ms], log", true, [](const MethodResult& r) { return r.frame_ms > 0 ? r.frame_ms : -1; }},
  };
  const int label_w = 150, panel_w = 170, row_h = 17, top = 34;
  // 20 pixels past the last panel: its value labels (e.g. "2.04e+03" at a full bar) stay inside the picture.
  const int width = label_w + 4 * panel_w + 20, height = top + row_h * static_cast<int>(ids.size()) + 8;
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" font-family=\"sans-serif\" font-size=\"11\">\n";
  for (size_t row = 0; row < ids.size(); ++row) {
    const MethodResult& r = results[ids[row]];
    const int y = top + row_h * static_cast<int>(row);
    s << "<text x=\"" << label_w - 6 << "\" y=\"" << y + 12 << "\" text-anchor=\"end\">"
      << (assessments[ids[row]].best ? "★ " : "") << html_escape(r.method) << "</text>\n";
  }
  for (int p = 0; p < 4; ++p) {
    const Panel& panel = panels[p];
    const int x0 = label_w + p * panel_w + 4, bar_w = panel_w - 56;
    double hi = 0, lo = INFINITY;
    for (size_t i : ids)
      if (results[i].ok && panel.value(results[i]) >= 0)
        hi = std::max(hi, panel.value(results[i])), lo = std::min(lo, panel.value(results[i]));
    s << "<text x=\"" << x0 << "\" y=\"14\" font-weight=\"bold\">" << panel.title << "</text>\n";
    const double log_lo = std::log10(std::max(1e-4, std::isfinite(lo) ? lo : 1e-3)) - 0.5;
    const double log_hi = std::log10(std::max(hi, 1e-4)) + 0.1;
    for (size_t row = 0; row < ids.size(); ++row) {
      const MethodResult& r = results[ids[row]];
      const int y = top + row_h * static_cast<int>(row);
      if (!r.ok) {
        s << "<text x=\"" << x0 << "\" y=\"" << y + 12 << "\" fill=\"#a00\">failed</text>\n";
        continue;
      }
      const double v = panel.value(r);
      if (v < 0) {
        s << "<text x=\"" << x0 << "\" y=\"" << y + 12 << "\" fill=\"#777\">n/a</text>\n";
        continue;
      }
      double f = hi > 0 ? v / hi : 0;
      if (panel.log) f = (std::log10(std::max(v, 1e-4)) - log_lo) / (log_hi - log_lo);
      const int w = std::max(1, static_cast<int>(std::lround(std::clamp(f, 0.0, 1.0) * bar_w)));
      s << "<rect x=\"" << x0 << "\" y=\"" << y + 2 << "\" width=\"" << w << "\" height=\"" << row_h - 4
        << "\" fill=\"" << colour(assessments[ids[row]].verdict) << "\"/>";
      s << "<text x=\"" << x0 + w + 3 << "\" y=\"" << y + 12 << "\">" << fmt("%.3g", v) << "</text>\n";
    }
  }
  s << "</svg>\n";
  // Quality against speed: rigidity (up is worse) over frame time (log).
  const int W = 460, H = 260, L = 50, B = 30;
  double tmin = INFINITY, tmax = 0, rmax = 0;
  for (size_t i : ids)
    if (results[i].ok && results[i].frame_ms > 0 && results[i].rigidity.count > 0) {
      tmin = std::min(tmin, results[i].frame_ms), tmax = std::max(tmax, results[i].frame_ms);
      rmax = std::max(rmax, results[i].rigidity.mean);
    }
  if (rmax > 0) {
    const double a = std::floor(std::log10(tmin)), b = std::ceil(std::log10(tmax) + 1e-9);
    auto px = [&](double t) { return L + (std::log10(t) - a) / std::max(b - a, 1.0) * (W - L - 20); };
    auto py = [&](double q) { return H - B - q / rmax * (H - B - 20); };
    s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
      << "\" font-family=\"sans-serif\" font-size=\"11\">\n"
      << "<line x1=\"" << L << "\" y1=\"" << H - B << "\" x2=\"" << W - 10 << "\" y2=\"" << H - B << "\" stroke=\"#444\"/>"
      << "<line x1=\"" << L << "\" y1=\"" << H - B << "\" x2=\"" << L << "\" y2=\"10\" stroke=\"#444\"/>\n"
      << "<text x=\"" << (W + L) / 2 << "\" y=\"" << H - 4 << "\" text-anchor=\"middle\">frame time [ms], log</text>"
      << "<text x=\"12\" y=\"" << H / 2 << "\" transform=\"rotate(-90 12 " << H / 2
      << ")\" text-anchor=\"middle\">rigidity (lower is better)</text>\n";
    for (double e = a; e <= b; ++e)
      s << "<text x=\"" << px(std::pow(10, e)) << "\" y=\"" << H - B + 13 << "\" text-anchor=\"middle\">"
        << fmt("%g", std::pow(10, e)) << "</text>";
    s << "<text x=\"" << L - 4 << "\" y=\"18\" text-anchor=\"end\">" << fmt("%.2g", rmax) << "</text>\n";
    for (size_t i : ids) {
      const MethodResult& r = results[i];
      if (!r.ok || r.frame_ms <= 0 || r.rigidity.count == 0) continue;
      const double x = px(r.frame_ms), y = py(r.rigidity.mean);
      s << "<circle cx=\"" << x << "\" cy=\"" << y << "\" r=\"4\" fill=\"" << colour(assessments[i].verdict)
        << "\" stroke=\"#333\"/>";
      // The name right of its point, or left of it near the right edge (so it is not cut off).
      if (x > W - 110)
        s << "<text x=\"" << x - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">";
      else
        s << "<text x=\"" << x + 6 << "\" y=\"" << y + 4 << "\">";
      s << html_escape(r.method) << "</text>\n";
    }
    s << "</svg>\n";
  }
  return s.str();
}

}  // namespace msd
