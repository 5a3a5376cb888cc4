#pragma once
//! \file A base surface at a detail scale (seed 9.3 decomposition S → B): a low-pass of the whole of S
//! that removes features shorter than a length L and keeps the shape. Fairing the free region
//! (fairing.h) replaces everything inside it by a membrane or thin plate, which is the right base only
//! when the region is small next to the shape; on a cylinder bent over most of its length it shrinks the
//! base to a thread, and on a whole-body edit it collapses it.
//!
//! The base minimises a fidelity term plus a thin-plate term (bi-Laplacian smoothing with a data term,
//! the Tikhonov form of the low-pass filters of Taubin 1995 and Desbrun et al. 1999; the bi-Laplacian
//! penalty as in the multiresolution hierarchies of Kobbelt et al. 1998 and Botsch & Kobbelt 2004):
//!   B = argmin  ‖B − S‖²_M + ℓ⁴ ‖ΔB‖²_M,   i.e.   (M + ℓ⁴ W M̃⁻¹ W) B = M S,
//! with the cotan Laplacian Δ = M⁻¹W of S (core/laplacian.h) and ℓ = L / 2π. On a mode of wavelength λ
//! (eigenvalue (2π/λ)² of −Δ) it is the filter 1 / (1 + (L/λ)⁴): features shorter than L are removed
//! (a bump of wavelength L/2 keeps 6 % of its height), features longer than L kept (2L: 94 %). The
//! system is symmetric positive definite; constants are in the kernel of W, so B moves with S under any
//! rigid motion or uniform scaling (L scales with it). Mesh-boundary vertices keep their place (B = S
//! there, and M̃⁻¹ is zero on them): their Laplacian carries the outline's curvature rather than the
//! surface's, and a free outline curls, so that S's outline vertices found no base point along the normals
//! (measured: 104 of them on the 10k bumpy plane). M̃⁻¹ is also zero on vertices without area.

#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "msdeform/core/types.h"
#include "msdeform/decomposition/detail_check.h"

namespace msd {

//! How the smoothing system (M + ℓ⁴ W M̃⁻¹ W) B = M S is solved.
enum class LowPassSolver {
  //! Conjugate gradients preconditioned with C D⁻¹ C, C = D − ℓ²W (condition number at most 2 on any mesh
  //! and at any scale, 15–17 iterations to 1e-13; low_pass.cpp), factoring only C, which has the
  //! Laplacian's sparsity: less than half the factorisation's memory (1M lift: 1.8 vs 3.7 GB), faster on
  //! large meshes (1M: 7.4 vs 9.1 s), slower on mid-size ones (the 200k lift's automatic scale: 7.5 vs
  //! 5.6 s), and right where the factorisation fails (a closed piece far smaller than the detail scale,
  //! a vertex of valence 8000, scales far beyond the mesh). Needs every unknown to have area; where one
  //! has none, the preconditioner cannot be factored or the iteration does not converge, the system is
  //! factored instead and LowPassReport::solver_fallback says why.
  ConjugateGradients,
  //! A sparse Cholesky factorisation of the system (about 220 entries per unknown on the 1M lift).
  Factorisation,
};

struct LowPassOptions {
  //! L, in mesh units: features shorter than L go into the details. 0 chooses L automatically (below).
  double detail_scale = 0;
  //! Automatic choice: a candidate L whose details come close to folding over their base
  //! (DetailCheck::fold_ratio_p999 above this), or fold at rest on more than 0.1 % of the vertices,
  //! removes shape rather than details: the search stops there. In (0, 1].
  double max_fold_ratio = 0.5;
  //! Automatic choice: the detail layer ends where the removed height stops growing with L: the first
  //! candidate whose rms detail height is less than this factor times the previous candidate's (one
  //! √2 step of L earlier). > 1.
  double plateau_growth = 1.25;
  //! Automatic choice: candidates are L = 4h̄·√2^k (h̄ the mean edge length), k = 0, 1, …, up to this
  //! fraction of the diameter of S (twice the largest distance from the centroid: unlike the bounding
  //! box, it does not change when S turns). > 0.
  double max_scale_fraction = 0.6;
  LowPassSolver solver = LowPassSolver::ConjugateGradients;
  //! \throw InvalidInput naming `who` and the first option out of its range (above); low_pass_base() and
  //! the multi-scale deformers' constructors call it, so a bad value fails before any work.
  void validate(const std::string& who) const;
};

//! One scale the automatic choice evaluated.
struct LowPassCandidate {
  double detail_scale = 0;
  DetailCheck check;
  double area_ratio = 1;  //!< area of the candidate base over the area of S
};

struct LowPassReport {
  //! L used (mesh units), given or chosen; 0 when the automatic choice found no detail layer. A given L
  //! may find none either (has_detail_layer()).
  double detail_scale = 0;
  bool automatic = false;   //!< chosen by the fold check (LowPassOptions::detail_scale was 0)
  double mean_edge_length = 0;
  std::vector<LowPassCandidate> candidates;  //!< what the automatic choice evaluated, in that order
  DetailCheck check;                         //!< of the returned base
  //! Every vertex a face uses lies on the mesh boundary (a strip, one triangle), which the low-pass keeps in
  //! place: B = S, no details.
  bool all_boundary = false;
  //! Why B = S, in words: every vertex on the boundary; the automatic search (detail_scale 0) stopped at
  //! a candidate that removes shape (its details close to folding, folding, or its area lost) before the
  //! detail heights stopped growing, or they grew at every scale tried, or stayed at rounding level; or a
  //! given detail scale (detail_scale > 0) removes nothing beyond rounding (far below the edge length).
  //! Empty when there is a detail layer.
  std::string no_layer_reason;
  //! Whether B differs from S by a detail layer (no_layer_reason empty); false: B = S.
  bool has_detail_layer() const { return no_layer_reason.empty(); }
  //! For a message without a layer: "" (every vertex on the boundary), "--detail-scale sets one" (the
  //! automatic choice found none) or "a larger --detail-scale (or 0, the automatic scale) sets one".
  const char* no_layer_remedy() const {
    return all_boundary ? ""
           : automatic  ? "--detail-scale sets one"
                        : "a larger --detail-scale (or 0, the automatic scale) sets one";
  }
  //! no_layer_reason followed by "; " and no_layer_remedy() where there is one.
  std::string no_layer_explanation() const {
    return all_boundary ? no_layer_reason : no_layer_reason + "; " + no_layer_remedy();
  }
  double seconds = 0;  //!< of the computation (also when the base came from a LowPassCache)
  //! Conjugate-gradient iterations of the last system solved (the returned base's, or the last candidate's
  //! of the automatic choice); 0 where it was factored (LowPassSolver).
  int iterations = 0;
  //! Why conjugate gradients gave way to the factorisation (LowPassSolver); empty when they ran, or when
  //! the factorisation was asked for.
  std::string solver_fallback;
  bool reused = false;  //!< taken from a LowPassCache: computed by an earlier call with the same S, F and options
};

//! S: #V by 3, F: #F by 3. Returns B, #V by 3, with S's connectivity.
//!
//! Automatic scale (detail_scale = 0), from the detail heights each candidate removes: candidates are
//! tried from the smallest up (one solve each: a numeric refactorisation of the same pattern, and with
//! conjugate gradients their iterations). A mesh with a detail
//! layer shows a plateau: the rms height of S − B grows quickly while L passes the details' size and
//! then stops growing (measured on the bumpy plane: ×1.8 per √2 step below the bump size, ×1.13 then
//! ×1.04 above it), because nothing but the shape is left to remove. The first candidate on the plateau
//! is chosen (the survey's bumpy plane: L = 79 on a 100 × 100 plane with bumps of height 10). A mesh
//! without one (a smooth cylinder, a bar, most scans: ×1.4–2.5 at every step) has no
//! detail layer to separate, and B = S (detail_scale 0 in the report): the multi-scale deformer then
//! equals its base deformer. The search stops early where a candidate would remove shape: its details
//! come close to folding (max_fold_ratio) or its area falls below half of S's (a tube smoothed towards
//! its axis, which a plateau would otherwise follow once nothing is left).
//! progress, when given, receives a line per candidate of the automatic choice (its scale, rms detail
//! height and growth, seconds): each costs a factorisation, minutes in all at 1M vertices.
//! \throw InvalidInput for an index out of range, a non-finite position, no faces, or options out of
//! range; SolverError naming the vertex if the system cannot be factored.
Positions low_pass_base(const Positions& S, const Faces& F, const LowPassOptions& options = {},
                        LowPassReport* report = nullptr,
                        const std::function<void(const std::string&)>& progress = {});

//! The last low-pass base computed, for callers that prepare several deformers on one mesh: the viewer
//! preparing again whenever a region is painted, a script trying regions, `compare` running the four
//! encodings. The base depends on S, F and the options only, not on the region, and its automatic scale
//! costs one solve per candidate (CGAL's 37k-vertex bunny: its 8 candidates took 1.7 s with conjugate
//! gradients, 1.2 s factored). Holds
//! copies of S, F and B (#V×3 doubles twice, #F×3 ints); thread-safe (a second caller waits for the
//! first's computation).
class LowPassCache {
 public:
  //! low_pass_base(S, F, options, report), or the stored base when S, F and the options equal the last
  //! computed call's exactly (then report->reused is true). Errors as low_pass_base(); a failed call
  //! leaves the stored base as it was.
  Positions base(const Positions& S, const Faces& F, const LowPassOptions& options = {},
                 LowPassReport* report = nullptr, const std::function<void(const std::string&)>& progress = {});

 private:
  std::mutex mutex_;
  bool valid_ = false;
  Positions S_, B_;
  Faces F_;
  LowPassOptions options_;
  LowPassReport report_;
};

}  // namespace msd
