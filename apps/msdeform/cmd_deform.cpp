#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>

#include "apps/msdeform/camera_options.h"
#include "apps/msdeform/commands.h"
#include "apps/msdeform/deformers.h"
#include "apps/msdeform/edit_case.h"
#include "apps/msdeform/progress.h"
#include "msdeform/analysis/metrics.h"
#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/deformation/space_deformer.h"
#include "msdeform/reconstruction/multiscale.h"

namespace msd::cli {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
// What to change when a multi-scale frame folded triangles over its base.
std::string fold_remedy(const Deformer& deformer) {
  const auto* ms = dynamic_cast<const MultiscaleDeformer*>(&deformer);
  if (!ms) return "the edit is too strong for this method";
  const DecompositionKind kind = ms->options().decomposition.kind;
  if (kind == DecompositionKind::Fairing || kind == DecompositionKind::Subdivision)
    return "use the low-pass base (--base low-pass, the default)";
  const EncodingKind e = ms->options().encoding.kind;
  const std::string smaller = ms->decomposition_report().low_pass.automatic
                                  ? "set a --detail-scale below the automatic one"
                                  : "use a smaller --detail-scale";
  if (e == EncodingKind::Normal || e == EncodingKind::Vectors) return "try --encoding transfer or volumes, or " + smaller;
  return smaller;
}

// What may keep folds apart; a mirroring handle's own folds no method avoids (the break tests: the advice to
// switch encodings under a mirror led to an encoding that folded too; a small mirrored patch elsewhere
// must not hide the advice for a bend's folds).
std::string fold_advice(const Deformer& deformer, const std::vector<Mat4>& transforms) {
  const std::string advice = fold_remedy(deformer);
  if (!edit_scaling(transforms).mirrors) return advice;
  return "a mirroring handle transform (negative determinant) folds the surface around it whatever the "
         "method or encoding; for folds elsewhere, " +
         advice;
}

}  // namespace

void add_deform_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("deform", "Deform a mesh: prepare a method for a region, apply the handle transforms");
  auto edit = std::make_shared<EditCaseOptions>();
  auto method = std::make_shared<DeformerOptions>();
  auto output = std::make_shared<std::string>();
  edit->add_to(*cmd);
  method->add_to(*cmd);
  cmd->add_option("-o,--output", *output, "Deformed mesh to write (.off .obj .ply .stl); written atomically")->required();
  auto weld = std::make_shared<double>(0);
  CLI::Option* weld_option =
      cmd->add_option(
             "--weld", *weld,
             "Weld seam vertices (boundary vertices on coinciding boundary edges, as info counts them) "
             "within EPS (mesh units; 0: identical coordinates) before deforming, so a mesh split "
             "along seams deforms as one surface; the output keeps the file's vertices and faces")
          ->check(CLI::Validator(
              [](std::string& text) {  // -0 is 0; a word is the parser's to name
                const std::optional<double> x = decimal_number(text);
                return x && *x < 0 ? std::string("a distance must be >= 0, got ") + text : std::string();
              },
              "EPS>=0"));
  auto quiet = std::make_shared<bool>(false);
  cmd->add_flag("-q,--quiet", *quiet, "No progress lines on stderr (warnings still print)");
  auto no_self_intersections = std::make_shared<bool>(false);
  cmd->add_flag("--no-self-intersections", *no_self_intersections,
                "Skip counting the self-intersecting face pairs the edit added (CGAL; counted up to 1000000 "
                "faces, a warning above)");
  auto render_output = std::make_shared<std::string>();
  auto camera = std::make_shared<CameraOptions>();
  cmd->add_option("--render", *render_output, "Also draw the result to this PNG, coloured by the region's roles");
  camera->add_to(*cmd);
  auto controls_output = std::make_shared<std::string>();
  cmd->add_option("--controls-output", *controls_output,
                  "lattice, cage-mvc, cage-harmonic: also write the deformed control points (the lattice's as a point "
                  "cloud, the cage with its faces; .off .obj .ply)");
  cmd->callback([=] {
    const bool welding = weld_option->count() > 0;  // weld_case refuses a negative or non-finite EPS
    // Outputs are checked before any work: a known format, and never one of the inputs or each other.
    edit->check_output(*output, "-o", {method->cage_file});
    if (!controls_output->empty()) {
      edit->check_output(*controls_output, "--controls-output", {method->cage_file});
      if (same_file(*controls_output, *output)) throw InvalidInput("--controls-output and -o name the same file");
    }
    if (!render_output->empty()) check_picture_output(*render_output, "--render");
    EditCase c = edit->load();
    const Region file_region = c.region;  // on the file's vertices, for --write-sel (welding renumbers them)
    if (welding) c = weld_case(std::move(c), *weld);
    if (c.weld)
      std::printf("welded %d vertices into others (within %g)\n", c.weld->merged, *weld);
    if (c.seam_vertices > 0)
      std::fprintf(stderr, "warning: %d boundary vertices lie at the coordinates of another boundary vertex (a mesh "
                           "split along seams): it deforms as separate pieces there; --weld 0 joins them\n",
                   c.seam_vertices);
    if (c.load_report.first_attribute_line > 0)
      std::fprintf(stderr,
                   "warning: %s line %d: its colours, normals, texture coordinates, materials or other data "
                   "are not kept: "
                   "%s holds positions and triangles only\n",
                   c.path.c_str(), c.load_report.first_attribute_line, output->c_str());
    if (c.load_report.first_ignored_line > 0)
      std::fprintf(stderr, "warning: %s holds more than its header declares: data from line %d on was ignored\n",
                   c.path.c_str(), c.load_report.first_ignored_line);
    std::unique_ptr<Deformer> deformer = method->make(c);
    if (deformer->traits().domain == DeformerDomain::Surface) require_surface(c, method->method_name());
    const auto* space = dynamic_cast<const SpaceDeformer*>(deformer.get());
    if (!controls_output->empty() && !(space && space->has_control_points()))
      throw InvalidInput("--controls-output applies to methods with control points (lattice, cage-mvc, cage-harmonic), "
                         "not " + deformer->name());
    if (!controls_output->empty() && file_extension(*controls_output) == ".stl" && deformer->name() == "lattice")
      throw InvalidInput("--controls-output " + *controls_output + ": a lattice's control points have no faces, which "
                         "STL cannot store; use .off, .obj or .ply");
    const Positions& rest = c.P;
    // The method runs on the welded mesh: the vertices its errors and warnings name are renumbered to the file's.
    const auto in_file_numbering = [&](const std::string& text) {
      return c.weld ? c.weld->in_file_numbering(text) : text;
    };
    const auto run = [&](auto&& step) {
      try {
        step();
      } catch (const Error& e) {
        if (!c.weld) throw;
        throw Error(in_file_numbering(e.what()));
      }
    };
    auto printer = std::make_shared<ProgressPrinter>(*quiet);
    deformer->set_progress([printer](const std::string& line) { (*printer)(line); });
    (*printer)(deformer->name() + ": preparing on " + std::to_string(rest.rows()) + " vertices");
    auto t0 = Clock::now();
    run([&] { deformer->prepare(c.P, c.F, c.region); });
    const double prepare_ms = ms_since(t0);
    Positions out(rest.rows(), 3);
    // A linear method's first frame warms caches and buffers; an iterative method's one frame from rest is
    // timed alone (a warm-up would double its run: PriMo's frame takes seconds to minutes).
    if (deformer->traits().solve != DeformerSolve::Iterative) {
      (*printer)(deformer->name() + ": first frame (warms caches and buffers)");
      run([&] { deformer->deform(c.transforms, out); });
      deformer->reset();  // the timed frame starts from rest too
    }
    (*printer)(deformer->name() + ": the timed frame, from rest");
    t0 = Clock::now();
    run([&] { deformer->deform(c.transforms, out); });
    const double frame_ms = ms_since(t0);
    printer->flush();  // the frame's last progress line (ARAP's last iteration) before its warnings
    if (c.weld)
      save_mesh(c.weld->unweld(out), c.file_F, *output);  // the file's vertices and faces
    else
      save_mesh(out, c.F, *output);
    if (!render_output->empty()) {
      RenderOptions view;
      camera->apply(rest, c.region, view);  // the rest shape's axes, so a deformed figure keeps its up
      const Positions colors = region_colors(c.region);
      view.vertex_colors = &colors;
      render_png(out, c.F, *render_output, view);
      std::printf("  drew the result to %s\n", render_output->c_str());
    }
    if (!controls_output->empty()) {
      save_mesh(space->control_points() + space->coefficients(), space->control_faces(), *controls_output);
      std::printf("  wrote the deformed control points (%d) to %s\n", space->num_coefficients(), controls_output->c_str());
    }
    edit->write_built(file_region, c.transforms);
    std::printf("%s on %s: %ld vertices (%zu free, %d handle(s))\n", deformer->name().c_str(), c.name.c_str(),
                long(rest.rows()), c.region.free_vertices().size(), c.region.num_handles());
    std::printf("  prepare %.1f ms, frame %.2f ms, handle error %.3g\n", prepare_ms, frame_ms, handle_error(rest, out, c.region, c.transforms));
    if (const auto* ms = dynamic_cast<const MultiscaleDeformer*>(deformer.get())) {
      const DecompositionReport& d = ms->decomposition_report();
      std::printf("  base deformer: %s\n", ms->base_deformer().name().c_str());
      const bool low_pass = d.kind == DecompositionKind::LowPass || d.kind == DecompositionKind::Remeshed;
      if (low_pass && d.low_pass.has_detail_layer())
        std::printf("  base: low-pass at detail scale %.4g (%s)\n", d.low_pass.detail_scale,
                    d.low_pass.automatic ? "chosen automatically; --detail-scale sets it" : "given");
      else if (low_pass)
        std::printf("  base: %s, no separate detail layer (%s)\n",
                    d.kind == DecompositionKind::Remeshed ? "the mesh remeshed" : "the mesh itself",
                    d.low_pass.no_layer_explanation().c_str());
      else if (d.kind == DecompositionKind::Fairing)
        std::printf("  base: faired free region\n");
      else
        std::printf("  base: Loop subdivision of a control mesh of %d vertices\n", d.control_vertices);
      if (d.kind == DecompositionKind::Remeshed)
        std::printf("  base remeshed to edge length %.4g: %d vertices\n", d.remesh_edge_length, d.remeshed_vertices);
      if (!low_pass || d.low_pass.has_detail_layer())  // without a layer there are no details to measure
        std::printf("  details: max height %.4g, base's smallest curvature radius %.4g, fold ratio %.3g\n",
                    d.check.max_height, d.check.min_curvature_radius, d.check.max_fold_ratio);
    }
    const FrameReport& report = deformer->frame_report();
    if (deformer->traits().solve == DeformerSolve::Iterative) {
      if (report.residual >= 0)
        std::printf("  frame: %d iterations, relative residual %.3g%s\n", report.iterations, report.residual,
                    report.converged ? "" : " (not converged)");
      else  // e.g. multi-scale volumes without a detail layer: S' = B', nothing to iterate
        std::printf("  frame: no iteration was needed\n");
    }
    if (report.constraint_error >= 0) {
      const double diag = bounding_box_diagonal(rest);
      std::printf("  constraints: largest distance of a constrained vertex from its target %.3g", report.constraint_error);
      if (diag > 0) std::printf(" (%.3g of the bounding-box diagonal)", report.constraint_error / diag);
      std::printf("\n");
    }
    if (report.folded_faces >= 0)
      std::printf("  folded triangles (normal turned against the deformed base's): %d\n", report.folded_faces);
    ShapeChange shape = shape_change(rest, out, c.F, c.region);
    const bool has_free = !c.region.free_vertices().empty();
    if (c.weld && shape.largest_vertex >= 0) shape.largest_vertex = c.weld->file_vertex(shape.largest_vertex);
    if (shape.edges > 0) {
      // No vertex when no edge changed length at all (the largest factor is then 1).
      const std::string at =
          shape.largest_vertex >= 0 ? ", at vertex " + std::to_string(shape.largest_vertex) : std::string();
      // Without a free vertex the edges measured are those between differently placed vertices only.
      if (!has_free)
        std::printf("  shape: %.3g %% of the edges between vertices placed by different transforms (no vertex is "
                    "free) changed length beyond 1.5x (the most %.3gx%s)",
                    100 * shape.stretched_share, shape.largest_factor, at.c_str());
      else
        std::printf("  shape: %.3g %% of the free region's edges changed length beyond 1.5x (the most %.3gx%s), "
                    "its area x%.3g",
                    100 * shape.stretched_share, shape.largest_factor, at.c_str(), shape.area_ratio);
      if (shape.volume_change) std::printf(", volume %+.3g %%", 100 * *shape.volume_change);
      std::printf("\n");
    }
    // The self-intersections the edit added, as compare counts them, where the count is cheap next to the
    // run (CGAL: 0.5 s per count at 200k faces, 12 s at 2M).
    std::string intersections;
    if (!*no_self_intersections && c.F.rows() > 0) {
      constexpr long kMostCountedFaces = 1000000;  // counting at rest and after: about 12 s per million faces
      if (c.F.rows() > kMostCountedFaces) {
        std::printf("  self-intersections: not counted (%ld faces, over %ld)\n", long(c.F.rows()),
                    kMostCountedFaces);
        // A check left out is said where the other checks' findings are (third break test: only on stdout).
        intersections =
            "the result was not checked for self-intersections (" + std::to_string(c.F.rows()) +
            " faces, over " + std::to_string(kMostCountedFaces) +
            "); check it with a tool of your own, or give --no-self-intersections when you do not "
            "need it";
      } else {
        try {
          const AddedSelfIntersections added(rest, c.F);
          std::vector<int> faces;
          const int n = added.count(out, &faces);
          std::printf("  self-intersections: %d face pair(s) added by the edit (%d at rest)\n", n,
                      added.rest_pairs());
          if (n > 0)
            // render does not weld: after --weld it would count the seam's contacts too.
            intersections =
                "the result intersects itself: " + std::to_string(n) +
                " face pair(s) the input did not have (the first: faces " + std::to_string(faces[0]) +
                " and " + std::to_string(faces[1]) + ")" +
                (c.weld ? std::string() : "; msdeform render " + *output + " --color selfint shows them");
        } catch (const InvalidInput& e) {  // a soup or a non-manifold input: CGAL's count needs a surface
          std::printf("  self-intersections: not counted (%s)\n", e.what());
        }
      }
    }
    for (const auto* list : {&deformer->prepare_warnings(), &report.warnings})
      for (const std::string& w : *list) std::fprintf(stderr, "warning: %s\n", in_file_numbering(w).c_str());
    if (!intersections.empty()) std::fprintf(stderr, "warning: %s\n", intersections.c_str());
    // Without a free vertex the prepare warning on torn edges says why they stretch. ARAP, alone or under
    // the details, is already the method that keeps proportions best.
    const auto* multiscale = dynamic_cast<const MultiscaleDeformer*>(deformer.get());
    const bool arap = (multiscale ? multiscale->base_deformer().name() : deformer->name()) == "arap";
    if (const std::string w =
            has_free ? shape_change_warning(shape, edit_scaling(c.transforms)) : std::string();
        !w.empty())
      std::fprintf(stderr, "warning: %s%s\n", w.c_str(),
                   arap ? "; more ARAP iterations or a larger fixed region may help"
                        : "; arap keeps the proportions best");
    if (report.folded_faces > 0)
      std::fprintf(stderr, "advice: %s\n", fold_advice(*deformer, c.transforms).c_str());
    std::printf("  wrote %s\n", output->c_str());
  });
}

}  // namespace msd::cli
