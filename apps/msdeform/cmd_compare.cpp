#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

#include "apps/compare/runner.h"
#include "apps/compare/verdict.h"
#include "apps/msdeform/camera_options.h"
#include "apps/msdeform/commands.h"
#include "apps/msdeform/deformers.h"
#include "apps/msdeform/edit_case.h"
#include "msdeform/analysis/render.h"
#include "msdeform/core/atomic_file.h"
#include "msdeform/core/edit_case.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/scenes.h"

namespace msd::cli {

namespace {

namespace fs = std::filesystem;

std::vector<std::string> default_scenes() {
  return {"lift", "bend120", "twist135", "bar-lift", "bar-bend120", "bar-twist135", "crease120"};
}

// An axis-aligned box, grown point by point.
struct Box {
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  void add(const Vec3& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); }
  void add(const Positions& P) {
    if (P.rows() > 0)
      add(Vec3(P.colwise().minCoeff().transpose())), add(Vec3(P.colwise().maxCoeff().transpose()));
  }
  double across() const { return (hi - lo).norm(); }
};

// What an edit asks for: the rest shape and where the handles take their vertices (a handle scaled by 10
// asks for a larger shape).
Box edit_box(const EditCase& c) {
  Box box;
  box.add(c.P);
  for (int v : c.region.constrained_vertices())
    if (const int k = c.region.handle_of(v); k >= 0) box.add(transform_point(c.transforms[k], c.P.row(v)));
  return box;
}

// A result whose box is more than 1.5 times the edit's across (the input and its handles where the edit
// puts them): it blew up, and framing or colouring the others by it would leave their pictures small or
// empty (Laplacian editing at 1.5e9 times the area; on the survey cactus at 3.2 times the edit's size, on
// the armadillo with its head scaled by 2 at 2.0; every other result of the benchmark within 1.04).
bool exploded(const Box& edit, const MethodResult& r) {
  Box box;
  box.add(r.result);
  return box.across() > 1.5 * edit.across();
}

// One sphere around the edit and every result of a scene that did not blow up, so their pictures share
// one camera.
void framing_sphere(Box box, const std::vector<MethodResult>& results, Vec3& center, double& radius) {
  const Box edit = box;
  for (const auto& r : results)
    if (r.ok && !exploded(edit, r)) box.add(r.result);
  center = 0.5 * (box.lo + box.hi);
  radius = 0.5 * box.across();
}

// Draws text in lines of at most `width` pixels, broken at spaces (a word longer than a line is cut),
// from (x, y) down, as many lines as fit above the image's bottom edge.
void draw_wrapped(Image& image, int x, int y, int width, const std::string& text, const Vec3& colour) {
  std::string line, word;
  std::istringstream words(text);
  const int step = text_height() + 4;
  auto flush = [&] {
    if (!line.empty() && y + text_height() <= image.height) draw_text(image, x, y, line, colour);
    y += step;
    line.clear();
  };
  while (words >> word) {
    const std::string longer = line.empty() ? word : line + " " + word;
    if (text_width(longer) <= width || line.empty()) {
      line = longer;
    } else {
      flush();
      line = word;
    }
  }
  flush();
}

struct SceneOutput {
  std::string name;
  std::vector<std::string> images;    // input first, then one per method
  std::vector<std::string> captions;  // the cell's figures under each picture
};

// The figures of one cell of the matrix (seed Fig. 9.16): rigidity, detail distortion, self-intersecting
// pairs and the distance to the reference method.
std::string caption(const MethodResult& r) {
  if (!r.ok) return "failed";
  char text[200];
  // A summary of no values was not measured (the notes above the metrics say why).
  auto mean = [&](const Stats& s) {
    std::snprintf(text, sizeof text, "%.3g", s.mean);
    return s.count > 0 ? std::string(text) : std::string("n/a");
  };
  std::string out = "rigidity " + mean(r.rigidity) + ", distortion " + mean(r.distortion) + ", pairs " +
                    (r.self_intersections < 0 ? std::string("n/a") : std::to_string(r.self_intersections));
  if (r.reference) {
    std::snprintf(text, sizeof text, ", to reference %.3g (mean %.3g)", r.reference->max, r.reference->mean);
    out += text;
  }
  return out;
}

// The seed's Fig. 9.16: one benchmark's three edits as columns, the method families as rows in the
// seed's order, "shell + multi-scale" as its best encoding on each edit.
struct Figure916 {
  const char* title;
  std::array<const char*, 3> scenes;  // translation, bend, twist
};
constexpr Figure916 kFigure916[] = {
    {"Botsch &amp; Sorkine 2008 benchmark (--survey)", {"plane", "cylinder", "bar"}},
    {"built-in bumpy plane", {"lift", "bend120", "twist135"}},
    {"built-in bumpy bar", {"bar-lift", "bar-bend120", "bar-twist135"}},
};
// Below the seed's rows, the space deformations (9.5, 9.6), which Fig. 9.16 does not show.
constexpr std::array<std::pair<const char*, const char*>, 11> kFigure916Rows = {{
    {"primo", "PriMo (nonlinear reference)"},
    {"arap", "ARAP (nonlinear)"},
    {"multiscale", ""},  // named after the base method
    {"gradient", "gradient-based editing"},
    {"laplacian", "Laplacian editing"},
    {"propagate", "transformation propagation"},
    {"shell", "shell"},
    {"rbf", "triharmonic RBF (space)"},
    {"cage-harmonic", "cage, harmonic coordinates (space)"},
    {"cage-mvc", "cage, mean value coordinates (space)"},
    {"lattice", "lattice FFD (space)"},
}};

// A cell's verdict: its colour class and the reason in words (★ marks the edit's best).
std::string verdict_html(const Assessment& a) {
  return std::string("<div class=\"verdict\"><b>") + (a.best ? "★ best, " : "") + to_string(a.verdict) + "</b>: " +
         html_escape(a.reason) + "</div>";
}

std::string figure916_html(const std::vector<MethodResult>& results, const std::vector<Assessment>& assessments,
                           const std::string& reference, const std::string& base_method) {
  auto assessment = [&](const MethodResult* r) -> const Assessment& { return assessments[r - results.data()]; };
  auto find = [&](const std::string& scene, const std::string& method) -> const MethodResult* {
    if (method == "multiscale") return best_multiscale(results, scene);
    for (const MethodResult& r : results)
      if (r.scene == scene && r.method == method) return &r;
    return nullptr;
  };
  std::ostringstream h;
  for (const Figure916& fig : kFigure916) {
    if (!std::all_of(fig.scenes.begin(), fig.scenes.end(), [&](const char* s) { return find(s, "shell") || find(s, "arap"); }))
      continue;
    h << "<h3>" << fig.title << "</h3>\n<table class=\"grid\"><tr><th></th>";
    const char* edits[] = {"translation", "120° bend", "135° twist"};
    for (int e = 0; e < 3; ++e) h << "<th>" << edits[e] << " (" << fig.scenes[e] << ")</th>";
    h << "</tr>\n";
    for (const auto& [method, label] : kFigure916Rows) {
      std::ostringstream row;
      bool any = false;
      for (const char* scene : fig.scenes) {
        const MethodResult* r = find(scene, method);
        if (r) {
          any = true;
          row << "<td class=\"" << to_string(assessment(r).verdict) << "\">";
          row << "<img src=\"images/" << html_escape(r->scene + "--" + r->method) << ".png\" alt=\"\"><br>";
          row << verdict_html(assessment(r));
          if (std::string(method) == "multiscale") row << html_escape(r->method) << ": ";
          row << "<small>" << html_escape(caption(*r)) << "</small>";
        } else {
          row << "<td>";
        }
        row << "</td>";
      }
      std::string name = label;
      if (std::string(method) == "multiscale") name = base_method + " + multi-scale (best encoding)";
      if (method == reference) name += " = reference";
      if (any) h << "<tr><th>" << html_escape(name) << "</th>" << row.str() << "</tr>\n";
    }
    h << "</table>\n";
  }
  if (h.str().empty()) return "";
  const std::string measure =
      reference.empty()
          ? std::string(
                "no reference method was run (--reference); the multi-scale row shows the "
                "encoding that changed the details least.")
          : "\"to reference\" is the largest (and mean) vertex distance to " + html_escape(reference) +
                "'s result over the bounding-box diagonal; the multi-scale row shows the encoding "
                "closest to it (mean distance).";
  return "<h2>Fig. 9.16: which method suits which edit</h2>\n<p>Rows as in the seed's Fig. 9.16, columns its three "
         "edits; " + measure + "</p>\n" + h.str();
}

// The command-line options of a method: the option groups of `cmd` that configure it (deformers.cpp).
std::string method_options_html(const CLI::App& cmd, const std::string& method) {
  std::vector<std::string> groups;
  if (is_multiscale(method)) groups = {"multiscale", "shell"};
  else if (method == "arap" || method == "primo") groups = {method, "iterative methods"};
  else if (method == "lattice" || method == "rbf" || method.rfind("cage", 0) == 0) groups = {"space"};
  else groups = {method};
  std::ostringstream h;
  for (const std::string& name : groups) {
    const CLI::App* g = nullptr;
    try {
      g = cmd.get_option_group(name);
    } catch (const std::exception&) {
      continue;  // a method without options of its own (gradient)
    }
    h << "<h3>" << html_escape(g->get_description()) << "</h3>\n<table>";
    for (const CLI::Option* o : g->get_options()) {
      if (o->get_name() == "--help" || o->get_name() == "--help-all" || o->get_name().empty()) continue;
      h << "<tr><td>" << html_escape(o->get_name()) << "</td><td>" << html_escape(o->get_description())
        << (o->get_default_str().empty() ? "" : " (default " + html_escape(o->get_default_str()) + ")")
        << "</td></tr>\n";
    }
    h << "</table>\n";
  }
  const std::string options = h.str();
  return options.empty() ? "<p>No options of its own.</p>\n" : options;
}

// One page per method (methods/NAME.html): what it is, its result and verdict on every edit, its options.
std::string method_page_html(const MethodEntry& entry, const std::vector<MethodResult>& results,
                             const std::vector<Assessment>& assessments, const std::string& options) {
  std::ostringstream h;
  h << "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>msdeform: " << html_escape(entry.name)
    << "</title>\n<style>body{font-family:sans-serif;margin:1.5em}table{border-collapse:collapse;font-size:13px}"
       "td,th{border:1px solid #bbb;padding:3px 6px;vertical-align:top}img{width:320px;border:1px solid #ccc}"
       << kVerdictCss << "</style></head><body>\n<p><a href=\"../index.html\">"
       "all methods</a></p>\n<h1>"
    << html_escape(entry.name) << "</h1>\n<p>Seed section " << html_escape(entry.section) << ": "
    << html_escape(entry.summary) << "</p>\n<h2>On the edits of this comparison</h2>\n<table><tr>";
  std::ostringstream cells;
  for (size_t i = 0; i < results.size(); ++i) {
    const MethodResult& r = results[i];
    if (r.method != entry.name) continue;
    h << "<th>" << html_escape(r.scene) << "</th>";
    cells << "<td class=\"" << to_string(assessments[i].verdict) << "\"><img src=\"../images/"
          << html_escape(r.scene + "--" + r.method) << ".png\" alt=\"\"><br>" << verdict_html(assessments[i])
          << "<small>" << html_escape(caption(r));
    if (r.ok) {
      char text[80];
      std::snprintf(text, sizeof text, "; prepare %.3g ms, frame %.3g ms", r.prepare_ms, r.frame_ms);
      cells << text;
    }
    cells << "</small></td>";
  }
  h << "</tr>\n<tr>" << cells.str() << "</tr></table>\n<h2>Options</h2>\n" << options << "</body></html>\n";
  return h.str();
}

// Methods × edits, each cell coloured by its verdict with the reason, then each edit's charts.
std::string verdicts_html(const std::vector<MethodResult>& results, const std::vector<Assessment>& assessments,
                          const std::vector<SceneOutput>& scenes, const std::vector<std::string>& methods) {
  std::ostringstream h;
  const VerdictThresholds t;
  h << "<h2>Verdicts: which method for which edit, and why</h2>\n<p>Each cell is judged on its edit: "
       "<span class=\"good\">good</span>, <span class=\"fair\">fair</span> (rigidity over "
    << t.fair_rigidity << "× the edit's most rigid unbroken result, or details changed by over "
    << 100 * t.fair_distortion << " % of their height), <span class=\"poor\">poor</span> (over "
    << t.poor_rigidity << "×, or " << 100 * t.poor_distortion << " %; a closed mesh's volume changed by over "
    << 100 * t.fair_volume << " % or " << 100 * t.poor_volume
    << " % beyond what the handles' scales ask), <span class=\"broken\">broken</span> (self-intersecting "
       "triangles the edit added, triangles folded over a multi-scale base, or the shape lost: a rigidity "
       "above "
    << t.broken_rigidity << " and " << t.broken_rigidity_ratio
    << "× the edit's most rigid result, or a volume factor above " << t.broken_volume << " and "
    << t.broken_volume
    << "× the edit's smallest), <span class=\"not-judged\">not judged</span> (no rigidity or detail measure, "
       "e.g. a point cloud), <span class=\"failed\">failed</span> (with its message); a method that warned "
       "(e.g. did not converge), or whose self-intersections were not counted, is at most fair, and "
       "says why. "
       "★ marks the best of each edit: of the results with the best verdict there, the most rigid, then the "
       "least detail change (so a good result outranks a more rigid fair one).</p>\n"
       "<table class=\"verdicts\"><tr><th></th>";
  for (const auto& sc : scenes) h << "<th>" << html_escape(sc.name) << "</th>";
  h << "</tr>\n";
  for (const std::string& method : methods) {
    h << "<tr><th><a href=\"methods/" << html_escape(method) << ".html\">" << html_escape(method) << "</a></th>";
    for (const auto& sc : scenes) {
      const auto it = std::find_if(results.begin(), results.end(),
                                   [&](const MethodResult& r) { return r.scene == sc.name && r.method == method; });
      if (it == results.end()) {
        h << "<td></td>";
        continue;
      }
      const Assessment& a = assessments[it - results.begin()];
      h << "<td class=\"" << to_string(a.verdict) << "\">" << verdict_html(a) << "</td>";
    }
    h << "</tr>\n";
  }
  h << "</table>\n";
  return h.str();
}

std::string index_html(const std::vector<MethodResult>& results, const std::vector<Assessment>& assessments,
                       const std::vector<SceneOutput>& scenes, const std::vector<std::string>& methods,
                       const std::string& reference, const std::string& base_method) {
  std::ostringstream h;
  h << "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>msdeform comparison</title>\n"
       "<style>body{font-family:sans-serif;margin:1.5em}table{border-collapse:collapse;font-size:13px}"
       "td,th{border:1px solid #bbb;padding:3px 6px;text-align:right}th{background:#eee}"
       "td:nth-child(-n+2){text-align:left}img{width:320px;border:1px solid #ccc}"
       ".grid td{text-align:center;vertical-align:top;font-size:12px}.verdicts td{text-align:left;font-size:12px;"
       "max-width:16em}.verdict{margin:2px 0}svg{display:block;margin:4px 0}"
    << kVerdictCss << "</style></head><body>\n"
       "<h1>msdeform: methods and detail encodings compared</h1>\n"
       "<p>Pictures: colour is the change of the detail heights (normal displacements over a faired base, seed 9.3) against "
       "the input (plain where it is not measured: see the notes above the metrics); one camera per scene; a point "
       "cloud is drawn as one sphere per point. Files: <a href=\"metrics.csv\">metrics.csv</a>, "
       "<a href=\"metrics.md\">metrics.md</a>, <a href=\"contact_sheet.png\">contact_sheet.png</a>, meshes/.</p>\n";
  h << verdicts_html(results, assessments, scenes, methods);
  h << figure916_html(results, assessments, reference, base_method);
  h << "<h2>Measured, per edit</h2>\n<p>Bars coloured by verdict; frame time on a log axis; the scatter puts "
       "rigidity (lower is better) against frame time.</p>\n";
  for (const auto& sc : scenes)
    h << "<h3>" << html_escape(sc.name) << "</h3>\n" << edit_charts_svg(results, assessments, sc.name);
  h << "<h2>All pictures</h2>\n<table class=\"grid\"><tr><th></th>";
  for (const auto& s : scenes) h << "<th>" << html_escape(s.name) << "</th>";
  h << "</tr>\n";
  std::vector<std::string> rows = {"input"};
  rows.insert(rows.end(), methods.begin(), methods.end());
  for (size_t r = 0; r < rows.size(); ++r) {
    h << "<tr><th>" << html_escape(rows[r]) << "</th>";
    for (const auto& s : scenes)
      h << "<td><img src=\"" << html_escape(s.images[r]) << "\" alt=\"\"><br>" << html_escape(s.captions[r]) << "</td>";
    h << "</tr>\n";
  }
  h << "</table>\n<h2>Metrics</h2>\n";
  // Why cells read n/a (a point cloud has no faces, a soup no manifold surface for CGAL), above the table.
  const std::vector<std::string> notes = measurement_notes(results);
  if (!notes.empty()) {
    h << "<p>Cells read n/a where the input does not allow the metric:</p>\n<ul>\n";
    for (const std::string& note : notes) h << "<li>" << html_escape(note) << "</li>\n";
    h << "</ul>\n";
  }
  // One table per edit, without the columns that say nothing there: the same text in every row (n/a,
  // empty, the vertex count, the scene's name). The full table is metrics.csv.
  const auto table = metrics_table(results);
  for (const auto& sc : scenes) {
    std::vector<size_t> rows;
    for (size_t r = 1; r < table.size(); ++r)
      if (results[r - 1].scene == sc.name) rows.push_back(r);
    std::vector<size_t> cols;
    for (size_t c = 0; c < table[0].size(); ++c) {
      bool varies = table[0][c] == "method";
      for (size_t r : rows) varies = varies || table[r][c] != table[rows[0]][c];
      if (varies) cols.push_back(c);
    }
    h << "<h3>" << html_escape(sc.name) << " (" << html_escape(table[rows.empty() ? 0 : rows[0]][2])
      << " vertices)</h3>\n<table><tr>";
    for (size_t c : cols) h << "<th>" << html_escape(table[0][c]) << "</th>";
    h << "</tr>\n";
    for (size_t r : rows) {
      h << "<tr class=\"" << to_string(assessments[r - 1].verdict) << "\">";
      for (size_t c : cols) h << "<td>" << html_escape(table[r][c]) << "</td>";
      h << "</tr>\n";
    }
    h << "</table>\n";
  }
  h << "<p>Columns with the same value in every row of an edit are left out (all are in metrics.csv). rigidity: one-ring rotation residual (0 = locally rigid); distortion: |Δh| / max detail "
       "height; self_intersections: intersecting face pairs (CGAL) the edit added, rest_self_intersections: the input's own; reference_max / reference_mean: vertex distance to "
       "the reference method's result over its bounding-box diagonal.</p>\n</body></html>\n";
  return h.str();
}

}  // namespace

void add_compare_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "compare",
      "Run every method and detail encoding on the benchmark edits; write metrics, meshes, pictures and index.html");
  struct Args {
    std::vector<std::string> methods, scenes;
    std::string resolution = "10k", output = "compare-out", survey, reference;
    bool no_self_intersections = false, quiet = false;
    DeformerOptions method;
    EditCaseOptions mesh;  // --mesh with --sel / --def or the region and transform options
    CameraOptions camera;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--methods", a->methods, "Methods to run (default: all but primo, which takes minutes per edit "
                                           "at 10k vertices; name it to run it): " + [] {
    std::string s;
    for (const auto& n : builtin_methods().names()) s += (s.empty() ? "" : ",") + n;
    return s + "; multiscale names every multiscale-* encoding";
  }())->delimiter(',');
  cmd->add_option("--scenes", a->scenes, "Built-in scenes (default: lift,bend120,twist135,bar-lift,bar-bend120,bar-twist135,crease120; "
                                         "none when --mesh is given)")
      ->delimiter(',');
  cmd->add_option("--resolution", a->resolution, "Approximate vertex count of the built-in scenes")->capture_default_str();
  cmd->add_option("--mesh", a->mesh.mesh, "Also run a mesh file of your own (with --sel and --def, or --fixed / "
                                         "--handle and --translate / --rotate / --scale), e.g. CGAL's cactus");
  cmd->add_option("--sel", a->mesh.sel, "Region of --mesh (.sel or .dmat)");
  cmd->add_option("--def", a->mesh.def, "Handle transforms of --mesh (.def)");
  a->mesh.region.add_to(*cmd);
  a->camera.add_to(*cmd);
  cmd->add_option("--survey", a->survey,
                  "Run the Botsch-Sorkine benchmark edits from this folder (with the built-in scenes only when --scenes names them) (seed Fig. 9.16): plane (translation), "
                  "cylinder (120 degree bend), bar (135 degree twist) and cactus, each NAME.off/.sel/.def");
  cmd->add_option("--reference", a->reference,
                  "Method whose result the others are measured against (distance columns; default: the first of "
                  "primo, arap among the methods run, else none)");
  cmd->add_option("-o,--output", a->output, "Output folder (created; finished files are replaced atomically)")
      ->capture_default_str();
  cmd->add_flag("--no-self-intersections", a->no_self_intersections, "Skip the CGAL self-intersection count");
  cmd->add_flag("-q,--quiet", a->quiet, "No progress lines on stderr");
  a->method.add_settings(*cmd);
  cmd->callback([a, cmd] {
    const auto start = std::chrono::steady_clock::now();
    ComparisonOptions options;
    if (!a->methods.empty()) {  // "multiscale" (as deform's --method takes it) stands for every encoding
      std::vector<std::string> encodings;
      for (const std::string& name : builtin_methods().names())
        if (is_multiscale(name)) encodings.push_back(name);
      options.methods.clear();
      for (const std::string& m : a->methods)
        for (const std::string& name : m == "multiscale" ? encodings : std::vector<std::string>{m})
          if (std::find(options.methods.begin(), options.methods.end(), name) == options.methods.end())
            options.methods.push_back(name);
    } else
      options.methods.erase(std::remove(options.methods.begin(), options.methods.end(), "primo"), options.methods.end());
    options.self_intersections = !a->no_self_intersections;
    // One line per finished run: its place in all runs and, from the mean time per run so far, the time left.
    auto started = std::make_shared<std::chrono::steady_clock::time_point>();  // set when the runs begin
    auto done = std::make_shared<int>(0);
    auto total = std::make_shared<int>(0);
    const bool quiet = a->quiet;
    options.progress = [=](const std::string& line) {
      ++*done;
      if (quiet) return;
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - *started).count();
      const double left = *total > *done ? elapsed / *done * (*total - *done) : 0;
      std::fprintf(stderr, "  [%d/%d, %.0f s, about %.0f s left] %s\n", *done, *total, elapsed, left, line.c_str());
    };
    const RegionOptions& r = a->mesh.region;
    if (a->mesh.mesh.empty() && (r.builds_region() || r.builds_transforms() || !a->mesh.sel.empty() ||
                                 !a->mesh.def.empty() || !r.write_sel.empty() || !r.write_def.empty()))
      throw InvalidInput("compare: --sel, --def, --fixed, --handle, the transforms and --write-sel / --write-def apply "
                         "to a --mesh");
    options.reference = a->reference;
    if (options.reference.empty())
      for (const char* candidate : {"primo", "arap"})
        if (options.reference.empty() &&
            std::find(options.methods.begin(), options.methods.end(), candidate) != options.methods.end())
          options.reference = candidate;
    check_comparison(options);  // fail fast, before any scene is built or folder made
    a->method.check_used_by(options.methods, "--methods");  // an option none of them reads would be ignored
    // Build every case first, so a bad name or file fails before anything is written.
    std::vector<std::string> scenes = a->scenes;
    if (scenes.empty() && a->mesh.mesh.empty() && a->survey.empty()) scenes = default_scenes();
    const int resolution = parse_resolution(a->resolution);
    {
      std::error_code ec;  // an -o that is a file fails here, not after the scenes are built
      if (fs::exists(a->output, ec) && !fs::is_directory(a->output, ec))
        throw InvalidInput("-o " + a->output + " is a file; compare writes a folder (pages, images, meshes) there");
    }
    std::vector<EditCase> cases;
    for (const auto& s : scenes) {
      if (!a->quiet) std::fprintf(stderr, "building scene %s (%s vertices)\n", s.c_str(), a->resolution.c_str());
      cases.push_back(scene_case(s, resolution));
    }
    const size_t mesh_case = cases.size();  // the --mesh edit's index in cases, when given
    if (!a->mesh.mesh.empty()) cases.push_back(a->mesh.load());
    if (!a->survey.empty())
      for (const char* name : {"plane", "cylinder", "bar", "cactus"}) {
        const std::string base = (fs::path(a->survey) / name).string();
        cases.push_back(file_case(base + ".off", base + ".sel", base + ".def"));
        note_faces_changed(cases.back(), base + ".off");
      }
    // Edits are told apart by name (rows, pictures, mesh files): a --mesh or survey file named like a
    // built-in scene or like another file gets a suffix (they were merged, and one's files overwritten).
    for (size_t i = 0; i < cases.size(); ++i) {
      const auto taken = [&](const std::string& name) {
        return std::any_of(cases.begin(), cases.begin() + i,
                           [&](const EditCase& c) { return c.name == name; });
      };
      if (!taken(cases[i].name)) continue;
      int k = 2;
      while (taken(cases[i].name + "-" + std::to_string(k))) ++k;
      const std::string renamed = cases[i].name + "-" + std::to_string(k);
      const char* which = i < mesh_case                             ? "repeated scene"
                          : i == mesh_case && !a->mesh.mesh.empty() ? "--mesh"
                                                                    : "--survey";
      std::fprintf(stderr, "note: two edits are named %s; the %s is called %s here\n", cases[i].name.c_str(),
                   which, renamed.c_str());
      cases[i].name = renamed;
    }
    if (!a->method.cage_file.empty() && cases.size() != 1)
      throw InvalidInput("--cage encloses one input: give it with --mesh alone (no --scenes or --survey), or leave "
                         "it out to generate a cage around each edit");
    *total = static_cast<int>(cases.size() * options.methods.size());
    *started = std::chrono::steady_clock::now();
    std::vector<MethodSettings> settings;  // per case (a subdivision base takes the case's control mesh)
    for (const auto& c : cases) settings.push_back(a->method.method_settings(c));
    const fs::path out(a->output);
    std::error_code ec;
    for (const char* sub : {"images", "meshes", "methods"}) fs::create_directories(out / sub, ec);
    if (ec) throw InvalidInput("compare: cannot create " + (out / "images").string() + ": " + ec.message());
    check_writable((out / "index.html").string(), "-o");  // before any work

    std::vector<MethodResult> all;
    std::vector<SceneOutput> scene_outputs;
    std::vector<Image> tiles;
    std::vector<std::string> tile_labels;
    std::vector<std::vector<Image>> tiles_by_scene;
    for (size_t i = 0; i < cases.size(); ++i) {
      const EditCase& c = cases[i];
      if (!a->quiet)
        std::fprintf(stderr, "%s: %zu vertices, %zu methods\n", c.name.c_str(), size_t(c.P.rows()), options.methods.size());
      options.settings = settings[i];
      std::vector<MethodResult> results = compare_methods(c, options);
      if (const auto it = std::find_if(results.begin(), results.end(), [](const MethodResult& r) { return r.rest_self_intersections > 0; });
          it != results.end())
        std::fprintf(stderr, "note: %s: the input itself has %d self-intersecting triangle pairs; each result counts the pairs "
                     "its edit added\n", c.name.c_str(), it->rest_self_intersections);
      for (const MethodResult& r : results)  // on the page too; printed even with --quiet, as deform does
        if (r.ok && !r.warning.empty())
          std::fprintf(stderr, "warning: %s / %s: %s\n", r.scene.c_str(), r.method.c_str(), r.warning.c_str());
      const Positions& rest = c.P;
      const Faces& F = c.F;
      RenderOptions view;
      view.width = 640;
      view.height = 480;
      view.framing = Framing::BoundingSphere;
      const Box edit = edit_box(c);
      framing_sphere(edit, results, view.sphere_center, view.sphere_radius);
      a->camera.apply(rest, c.region, view);  // up and view direction; --focus handle frames the handles
      const bool point_cloud = F.rows() == 0;
      if (point_cloud) view.point_radius = default_point_radius(rest);  // the rest's spacing in every picture
      // Colour by detail change where it was measured (#V values; empty when not measured).
      auto has_distortion = [&](const MethodResult& r) { return r.ok && r.distortion_per_vertex.size() == rest.rows(); };
      double scalar_max = 0;
      for (const auto& r : results)
        if (has_distortion(r) && !exploded(edit, r))
          scalar_max = std::max(scalar_max, robust_scalar_range(r.distortion_per_vertex).second);
      SceneOutput so{c.name, {}, {}};
      std::vector<Image> column;
      const std::string input_png = "images/" + c.name + "--input.png";
      Image input = render(rest, F, view);
      write_png(input, (out / input_png).string());
      so.images.push_back(input_png);
      so.captions.push_back(std::to_string(rest.rows()) + (point_cloud ? " points (no faces)" : " vertices"));
      column.push_back(std::move(input));
      for (const auto& r : results) {
        const std::string png = "images/" + c.name + "--" + r.method + ".png";
        if (r.ok) {
          RenderOptions ro = view;
          SaveOptions save;
          if (has_distortion(r)) {
            ro.vertex_scalar = &r.distortion_per_vertex;
            ro.scalar_label = "detail change";
            ro.scalar_min = 0;
            ro.scalar_max = scalar_max > 0 ? scalar_max : 1e-12;
            save.vertex_scalar = &r.distortion_per_vertex;
            save.scalar_name = "detail_change";
          }
          ro.highlighted_faces = &r.self_intersecting_faces;  // in red over the detail colours
          // A result that blew up, drawn with the others' camera, shows a close-up from inside it.
          const bool own_frame = exploded(edit, r);
          Box own;
          if (own_frame) {
            own.add(r.result);
            ro.framing = Framing::BoundingSphere;
            ro.sphere_center = 0.5 * (own.lo + own.hi);
            ro.sphere_radius = 0.5 * own.across();
          }
          Image img = render(r.result, F, ro);
          if (own_frame) {
            char text[120];
            std::snprintf(text, sizeof text, "exploded: %.3g times the edit's size, drawn at its own scale",
                          own.across() / edit.across());
            draw_wrapped(img, 10, 10, view.width - 20, text, Vec3(0.6, 0, 0));
          }
          write_png(img, (out / png).string());
          save_mesh(r.result, F, (out / "meshes" / (c.name + "--" + r.method + ".ply")).string(), save);
          column.push_back(std::move(img));
        } else {
          Image failed(view.width, view.height, Vec3(0.9, 0.85, 0.85));
          draw_wrapped(failed, 20, view.height / 3, view.width - 40, "failed: " + r.error, Vec3(0.5, 0, 0));
          write_png(failed, (out / png).string());
          column.push_back(std::move(failed));
        }
        so.images.push_back(png);
        so.captions.push_back(caption(r));
      }
      if (!a->quiet) std::fprintf(stderr, "  rendered %zu pictures\n", column.size());
      scene_outputs.push_back(so);
      tiles_by_scene.push_back(std::move(column));
      all.insert(all.end(), std::make_move_iterator(results.begin()), std::make_move_iterator(results.end()));
    }
    // Contact sheet like Fig. 9.16: one column per scene, one row per method (the input first).
    const size_t rows = options.methods.size() + 1;
    for (size_t r = 0; r < rows; ++r)
      for (size_t s = 0; s < scene_outputs.size(); ++s) {
        tiles.push_back(std::move(tiles_by_scene[s][r]));
        tile_labels.push_back(scene_outputs[s].name + " / " + (r == 0 ? std::string("input") : options.methods[r - 1]));
      }
    // One edit (--mesh) would make a single tall column: its pictures then fill rows of four.
    const int columns = scene_outputs.size() == 1 ? 4 : static_cast<int>(scene_outputs.size());
    write_png(tile_images(tiles, columns, tile_labels), (out / "contact_sheet.png").string());
    write_file_atomically((out / "metrics.csv").string(), metrics_csv(all));
    write_file_atomically((out / "metrics.md").string(), metrics_markdown(all));
    const std::vector<Assessment> assessments = assess(all);
    for (const std::string& method : options.methods)
      write_file_atomically((out / "methods" / (method + ".html")).string(),
                            method_page_html(builtin_methods().find(method), all, assessments,
                                             method_options_html(*cmd, method)));
    write_file_atomically((out / "index.html").string(), index_html(all, assessments, scene_outputs, options.methods,
                                                                    options.reference, a->method.settings.base_method));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    int failed = 0, refused = 0;
    for (const auto& r : all) (r.refused_input ? refused : failed) += !r.ok;
    std::printf("%s", verdict_summary(all, assessments).c_str());  // the whole table is in metrics.md
    if (!a->mesh.mesh.empty()) a->mesh.write_built(cases[mesh_case].region, cases[mesh_case].transforms);
    std::printf(
        "\nwrote %s/index.html (%zu results, %d failed%s) in %.1f s\n", a->output.c_str(), all.size(), failed,
        refused > 0
            ? (", " + std::to_string(refused) + (refused == 1 ? " surface method" : " surface methods") +
               " not run: the input is not a surface")
                  .c_str()
            : "",
        seconds);
    // The pages are written, but the exit status says not everything ran (surface methods refusing a point
    // cloud or a soup are what the input asks for: they do not fail the comparison).
    if (refused > 0 && refused == static_cast<int>(all.size()))
      throw Error(
          "compare: no method ran: the input is not a surface, and only space methods take it "
          "(--methods lattice,cage-mvc,cage-harmonic,rbf)");
    if (failed > 0)
      throw Error("compare: " + std::to_string(failed) + " of " + std::to_string(all.size()) +
                  " runs failed (their rows in metrics.md and their pictures say why)");
  });
}

}  // namespace msd::cli
