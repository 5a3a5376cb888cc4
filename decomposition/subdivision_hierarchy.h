#pragma once
//! \file Subdivision-based multi-scale hierarchy (Zorin et al. 1997, "Interactive multiresolution mesh
//! editing"; seed 9.3): for a surface S with Loop subdivision connectivity the base B is the Loop
//! refinement of a smooth coarse control mesh. Edits run on the few coarse control points; every frame
//! maps them to full resolution with the precomputed #fine × #coarse stencil matrix, and the details
//! D = S ⊖ B are added back on the fine level.

#include <cstdint>
#include <vector>

#include "msdeform/core/region.h"
#include "msdeform/core/subdivision.h"

namespace msd {

//! How the coarse control points c (B = loop · c) are chosen.
enum class ControlPointFit {
  //! c = the given coarse positions. B is then the limit-like surface of the original control mesh,
  //! which for the generated scenes is the flat or cylindrical surface below the bumps.
  Given,
  //! c minimises ‖loop · c − S‖² (normal equations loopᵀloop c = loopᵀ S, SparseSPDSolver): B is the
  //! closest Loop surface to S, so the global displacements S − B are as short as possible (short
  //! displacements are the stable ones, seed 9.3.2) and B passes through the middle of the details.
  LeastSquares,
};

struct SubdivisionHierarchyOptions {
  ControlPointFit control_points = ControlPointFit::LeastSquares;
};

//! The hierarchy S → (coarse control points c, base B = loop · c, details S − B). refine() is the
//! per-frame path: one pass over the fine vertices, parallel (parallel_for_chunks), allocation-free once
//! the output has #fine rows. The stencil matrix is stored compressed: rows whose weights and column
//! offsets (relative to their first column) coincide bit for bit share one stored pattern, which on the
//! regular parts of a uniform refinement cuts the bytes streamed per frame about five-fold; the result
//! equals loop · c to rounding (the same products, summed in the same order).
class SubdivisionHierarchy {
 public:
  //! fine_S: #fine by 3 detailed surface with faces fine_F, which must be refinement.faces; coarse:
  //! #coarse by 3 control mesh with faces coarse_F, the mesh `refinement` was made from
  //! (loop_refine(coarse_F, #coarse, levels)); refinement.loop and .linear are #fine by #coarse.
  //! \throw InvalidInput for mismatched sizes or connectivity (naming the first differing face), an index
  //! out of range, or a non-finite position; SolverError when the least-squares system is singular.
  void build(const Positions& fine_S, const Faces& fine_F, const Positions& coarse, const Faces& coarse_F,
             const LoopRefinement& refinement, const SubdivisionHierarchyOptions& options = {});
  bool built() const { return num_fine_ > 0; }

  int num_fine_vertices() const { return static_cast<int>(num_fine_); }
  int num_coarse_vertices() const { return static_cast<int>(control_.rows()); }
  //! #coarse by 3 control points c of the base (see ControlPointFit): the rest shape of the coarse edit.
  const Positions& control_points() const { return control_; }
  const Faces& coarse_faces() const { return coarse_F_; }
  const Faces& fine_faces() const { return fine_F_; }
  //! #fine by 3 base surface B = loop · c.
  const Positions& base() const { return base_; }
  //! #fine by 3 global-coordinate details S − B (the fallback encoding; detail/ has the real ones).
  const Positions& details() const { return details_; }

  //! B' = loop · coarse_deformed: coarse_deformed #coarse by 3, fine_out #fine by 3 (resized only when
  //! its shape differs; must not alias coarse_deformed). \throw UsageError before build() or for a
  //! wrong row count; InvalidInput for a non-finite coarse position.
  void refine(const Positions& coarse_deformed, Positions& fine_out) const;
  Positions refine(const Positions& coarse_deformed) const;

  //! Fallback reconstruction with global details: fine_out = loop · coarse_deformed + (S − B); returns S
  //! for the unedited control points. \throw as refine().
  void reconstruct_global(const Positions& coarse_deformed, Positions& fine_out) const;

  //! The region on the coarse mesh: coarse vertex i gets the label of its fine vertex-child
  //! coarse_to_fine()[i]. \throw UsageError before build(); InvalidInput for a region of the wrong size
  //! or a handle that has no vertex left on the coarse mesh.
  Region coarse_region(const Region& fine_region) const;
  //! For each coarse vertex, the fine vertex at the same place (its vertex-child of every level).
  const std::vector<int>& coarse_to_fine() const { return coarse_to_fine_; }

  //! Stencil storage statistics: distinct row patterns, and stored weights (vs. nnz of the matrix).
  long num_stencil_patterns() const { return static_cast<long>(pattern_start_.size()) - 1; }
  long num_stored_weights() const { return static_cast<long>(pattern_weight_.size()); }

 private:
  void compress_stencils(const SparseMatrix& loop);

  long num_fine_ = 0;
  Positions control_, base_, details_;
  Faces coarse_F_, fine_F_;
  std::vector<int> coarse_to_fine_;
  // Compressed stencils: fine row i = Σ_q pattern_weight_[s+q] · c(row_base_[i] + pattern_offset_[s+q]),
  // s = pattern_start_[row_pattern_[i]].
  std::vector<std::int32_t> row_pattern_, row_base_, pattern_offset_;
  std::vector<std::int64_t> pattern_start_;
  std::vector<double> pattern_weight_;
};

//! For each coarse vertex the fine vertex whose linear-refinement stencil row is exactly e_i (its
//! vertex-child): #coarse indices into the fine vertices.
//! \throw InvalidInput if some coarse vertex has none (the refinement is not uniform from that mesh).
std::vector<int> coarse_to_fine_vertices(const LoopRefinement& refinement);

//! A fine region mapped to the coarse mesh of `refinement` (see SubdivisionHierarchy::coarse_region).
//! \throw InvalidInput for a region of the wrong size or a handle without coarse vertex.
Region coarse_region(const Region& fine_region, const LoopRefinement& refinement);

}  // namespace msd
