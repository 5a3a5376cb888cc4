#include "msdeform/reconstruction/multiscale.h"

#include <algorithm>
#include <atomic>
#include <cstring>

#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/parallel.h"
#include "msdeform/deformation/shell.h"

namespace msd {

MultiscaleDeformer::MultiscaleDeformer(MultiscaleOptions options, std::unique_ptr<Deformer> base_deformer,
                                       std::string name)
    : options_(std::move(options)),
      name_(name.empty() ? std::string("multiscale-") + to_string(options_.encoding.kind) : std::move(name)),
      base_deformer_(base_deformer ? std::move(base_deformer) : std::make_unique<ShellDeformer>()),
      encoding_(make_encoding(options_.encoding)) {
  options_.decomposition.validate(name_);  // a bad value fails here, not after the caller loaded a mesh
  if (dynamic_cast<const MultiscaleDeformer*>(base_deformer_.get()))
    throw InvalidInput(name_ + ": the base deformer is itself multi-scale; give it a single-scale method (shell, "
                               "propagate, ...)");
  if (options_.decomposition.kind == DecompositionKind::Remeshed && encoding_->needs_same_connectivity())
    throw InvalidInput(name_ + ": the " + encoding_->name() + " encoding needs S and B to share connectivity; a "
                       "remeshed base needs the normal, volumes or transfer encoding");
}

DeformerTraits MultiscaleDeformer::traits() const {
  const DeformerTraits base = base_deformer_->traits();
  DeformerTraits t;
  t.solve = encoding_->iterative() || base.solve == DeformerSolve::Iterative ? DeformerSolve::Iterative
                                                                           : DeformerSolve::Linear;
  t.reproduces_rigid_motions = base.reproduces_rigid_motions;
  return t;
}

void MultiscaleDeformer::do_prepare(const Positions& S, const Faces& F, const Region& region) {
  progress(name_ + ": decomposing S into a base and details (" + to_string(options_.decomposition.kind) + " base)");
  std::function<void(const std::string&)> said;
  if (progress_wanted()) said = [this](const std::string& line) { progress(name_ + ": " + line); };
  decomposition_ = decompose(S, F, region, options_.decomposition, said);
  const Decomposition& d = decomposition_;
  if (d.report.low_pass.reused)
    progress(name_ + ": the low-pass base is the one computed before for this mesh and detail scale");
  if (!d.report.warning.empty()) prepare_warnings_.push_back(d.report.warning);
  progress(name_ + ": preparing the base deformer (" + base_deformer_->name() + ") on " +
           std::to_string(d.edit.rows()) + " base vertices");
  base_deformer_->set_progress(progress_callback());
  // A remeshed base or a control mesh numbers its own vertices: the base deformer's messages say so (a
  // remeshed base's warning named base vertices 30 and 37, which the user looked for in S).
  const bool own_numbering =
      options_.decomposition.kind == DecompositionKind::Remeshed || d.edit.rows() != S.rows();
  const std::string numbering = own_numbering ? "(vertex numbers of the base's own mesh) " : "";
  try {
    base_deformer_->prepare(d.edit, d.edit_faces, d.edit_region);
  } catch (const InvalidInput& e) {  // a refusal of the mesh's structure (a fan too large to factor): S's too
    throw InvalidInput(name_ + ": the base deformer " + base_deformer_->name() + " on the base B: " + e.what());
  } catch (const Error& e) {  // a numerical or topological failure: of B, or of S that B inherited
    if (std::string(e.what()).find("out of memory") != std::string::npos)  // not the mesh's fault
      throw SolverError(name_ + ": the base deformer " + base_deformer_->name() +
                        " ran out of memory on the base B (" + std::to_string(d.edit.rows()) +
                        " vertices): " + e.what());
    const char* cause =
        d.base_is_input
            ? "the input mesh (the base is the mesh itself here); it is degenerate there, repair it: "
        : options_.decomposition.kind == DecompositionKind::Remeshed
            ? "the remeshed base B; a smaller --remesh-base may help: "
            : "the base B. Where the input mesh is degenerate too (the method alone fails on it), "
              "repair the input; otherwise the base is, and a smaller detail scale may help: ";
    throw SolverError(name_ + ": the base deformer " + base_deformer_->name() + " failed on " + cause +
                      numbering + e.what());
  }
  // B has S's outliers and S's region: Deformer::prepare has warned about their outliers, torn edges,
  // zero-area cuts and needles on S already.
  for (const std::string& w : base_deformer_->prepare_warnings()) {
    const auto said = [&](const char* what) {
      return w.find(what) != std::string::npos &&
             std::any_of(prepare_warnings_.begin(), prepare_warnings_.end(),
                         [&](const std::string& v) { return v.find(what) != std::string::npos; });
    };
    if (!said(kOutlierWarning) && !said(kTornEdgesWarning) && !said(kZeroAreaCutWarning) &&
        !said(kNeedleWarning))
      prepare_warnings_.push_back(own_numbering ? "on the base B " + numbering + w : w);
  }
  encoding_->set_anchor_vertices(region.constrained_vertices());
  encoding_->set_placed_vertices(region.constrained_vertices());  // do_deform places them itself
  if (!d.base_is_input) {
    progress(name_ + ": encoding the details (" + encoding_->name() + ")");
    encoding_->encode(S, F, d.base, d.base_faces);  // D = S ⊖ B
    for (std::string w : encoding_->encode_warnings()) {
      // Where decompose warned that the details fold over the base (too tall for its curvature), a larger
      // detail scale makes them taller still: its own remedy, said with that warning, applies (fourth break
      // test: the two lines advised a smaller and a larger scale).
      if (const size_t at = w.find(kNewtonFallbackRemedy);
          at != std::string::npos && d.report.check.folding_vertices > 0)
        w.replace(at, std::strlen(kNewtonFallbackRemedy),
                  "they lie where the details fold over the base, as decompose warned: its remedy applies");
      prepare_warnings_.push_back(name_ + ": " + w);
    }
  }
  edit_deformed_ = d.edit;
  base_deformed_ = d.base;
  rest_ = S;
  placed_.clear();
  for (int v : region.constrained_vertices()) placed_.emplace_back(v, region.handle_of(v));
  fold_check_.prepare(S, F, d.base, d.base_faces);
  // Triangles the edit moves rigidly with their base cannot fold (FoldCheck::set_placements): where the
  // base deformer puts B's constrained vertices at T_k p itself (not a refined control mesh).
  if (!d.hierarchy && base_deformer_->traits().exact_constraints)
    fold_check_.set_placements(region, d.edit_region);
}

void MultiscaleDeformer::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  const Decomposition& d = decomposition_;
  base_deformer_->set_progress(progress_callback());  // the caller's, as it is now (none: allocates nothing)
  if (d.hierarchy) {
    base_deformer_->deform(transforms, edit_deformed_);  // the edit, on the control mesh
    d.hierarchy->refine(edit_deformed_, base_deformed_);  // B' = stencil · control'
  } else {
    base_deformer_->deform(transforms, base_deformed_);  // B → B'
  }
  if (d.base_is_input)
    out = base_deformed_;  // no detail layer: S' = B'
  else if (out.rows() != rest_.rows() || out.cols() != 3)
    out.resize(rest_.rows(), 3);
  // Fixed and handle vertices exactly where the edit puts them (the details reproduce them only to the
  // encoding's accuracy), before the details: the encoding leaves these rows, and deformation transfer
  // ends its solve there. A whole-body handle holds a large share of the vertices, so on both cores.
  // The placed rows are checked finite here, the others by the encoding (it throws on a non-finite row
  // it writes): end_frame() need not read S' again.
  std::atomic<bool> placed_finite{true};
  parallel_for_chunks(static_cast<long>(placed_.size()), [&](long begin, long end) {
    double check = 0;  // x − x is 0 for a finite x, NaN otherwise
    for (long i = begin; i < end; ++i) {
      const auto [v, k] = placed_[i];
      const Vec3 p = rest_.row(v);
      const Vec3 q = k < 0 ? p : transform_point(transforms[k], p);
      out.row(v) = q;
      check += (q.x() - q.x()) + (q.y() - q.y()) + (q.z() - q.z());
    }
    if (!(check == 0)) placed_finite = false;
  });
  if (!placed_finite)  // before the details: deformation transfer would solve from it
    for (const auto& [v, k] : placed_)
      if (!out.row(v).allFinite())
        throw SolverError(name_ + ": the frame gave vertex " + std::to_string(v) + " a non-finite position (" +
                              (k < 0 ? std::string("a fixed vertex") : "handle " + std::to_string(k) + "'s transform") +
                              " overflowed it)",
                          v);
  if (!d.base_is_input) {
    encoding_->reconstruct(base_deformed_, out);  // S' = B' ⊕ D
    set_output_checked_finite();
  }
  FrameReport& r = frame_report_;
  const FrameReport& base = base_deformer_->frame_report();
  r.iterations = base.iterations;
  r.residual = base.residual;
  r.converged = base.converged;
  if (!d.base_is_input && encoding_->iterative()) {
    r.iterations += encoding_->last_iterations();
    r.residual = std::max(r.residual, encoding_->last_residual());
    r.converged = r.converged && encoding_->last_converged();
  }
  // A non-convergence is said once, for the whole frame (end_frame), and so are the transforms (deform()).
  for (const std::string& w : base.warnings)
    if (w.rfind(base_deformer_->name() + kNotConvergedWarning, 0) != 0 &&
        w.rfind(base_deformer_->name() + kHandleTransformWarning, 0) != 0)
      r.warnings.push_back(w);
  r.folded_faces = fold_check_.count(out, base_deformed_, transforms);
  const auto mirrors = [&] {
    return std::any_of(transforms.begin(), transforms.end(),
                       [](const Mat4& T) { return T.topLeftCorner<3, 3>().determinant() < 0; });
  };
  if (r.folded_faces > 0)
    r.warnings.push_back(
        name_ + ": " + std::to_string(r.folded_faces) + (r.folded_faces == 1 ? " triangle" : " triangles") +
        " folded over the deformed base; " +
        (mirrors()
             ? "a mirroring handle transform folds the surface around it whatever the encoding; elsewhere "
             : "") +
        (d.hierarchy ? "a finer control mesh or the low-pass base keeps them apart"
         : options_.decomposition.kind == DecompositionKind::Remeshed
             ? "another --remesh-base or a smaller detail scale keeps them apart"
         // A faired base has no detail scale (third break test): its free region sets the details.
         : options_.decomposition.kind == DecompositionKind::Fairing
             ? "the low-pass base (--base low-pass) or a smaller free region keeps them apart"
             : "a smaller detail scale keeps them apart (the other encodings fold more or less "
               "depending on the edit: msdeform compare measures them)"));
}

void MultiscaleDeformer::do_reset() {
  base_deformer_->reset();
  encoding_->reset();
}

}  // namespace msd
