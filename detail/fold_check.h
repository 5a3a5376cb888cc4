#pragma once
//! \file The per-frame fold check of the multi-scale framework (seed 9.3.3, Fig. 9.10): where the
//! deformed base B' curves more than 1/h, neighbouring displacements of height h cross and triangles of
//! the reconstructed S' turn over. Each triangle of S is compared with the base triangle under it: it
//! folded when the sign of n_S' · n_B' is the opposite of the sign of n_S · n_B at rest (a triangle that
//! collapsed to zero area has no normal and is not counted).

#include <vector>

#include "msdeform/core/region.h"
#include "msdeform/core/types.h"

namespace msd {

class FoldCheck {
 public:
  //! S: #Vs by 3 with faces Fs; B: #Vb by 3 with faces Fb. With identical connectivity triangle t of S is
  //! compared with triangle t of B; otherwise with the base triangle closest to its centroid (Embree).
  //! Triangles of S or B of zero area at rest (below 1e-14 of their squared longest edge, as in
  //! cotan_laplacian: their orientation is rounding noise) are not counted, nor needles of S (a corner's
  //! |cot| above 1e5, as cotan_laplacian clamps them: they turn over at the slightest move of a corner).
  //! \throw InvalidInput for an index out of range.
  void prepare(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb);
  //! Lets count() skip the triangles the edit moves rigidly with their base. `s_region` (#Vs codes) and
  //! `b_region` (#Vb codes) say where the edit places each vertex of S' and B' itself: a triangle of S whose
  //! three corners, and the three corners of its base triangle, are all fixed or all in one handle k turns
  //! with B' by one map x ↦ A x + t. Where that map is a similarity (AᵀA = s²I, s > 0, to 1e-6 relative:
  //! rotations, reflections, uniform scales, translations, as written with 6 or more digits; fixed
  //! vertices: the identity), cof(A) scales every normal by s² and turns it by one orthogonal map, so
  //! n_S' · n_B' = s⁴ n_S · n_B keeps its rest sign and the triangle cannot fold. Triangles whose rest
  //! normals are within 1e-3 (cosine) of perpendicular are always counted (the 1e-6 could decide there).
  //! The count is then that of every triangle, except where the rounding of T_k p itself turns a skipped
  //! triangle (coordinates some 1e13 times its size): counting it would report that noise as a fold, the
  //! skip reports the rigid motion's answer, none. Valid only if the placed vertices of S' and B' sit
  //! exactly (to rounding) at T_k p, as the multi-scale deformer and exact-constraint base deformers put
  //! them. Call after prepare(); a new prepare() counts every triangle again. \throw UsageError before
  //! prepare() or for regions of the wrong size.
  void set_placements(const Region& s_region, const Region& b_region);

  //! Triangles of S' (#Vs by 3) whose orientation against B' (#Vb by 3) differs from the rest pose, right at
  //! any finite size. `transforms`: the frame's handle transforms (4×4 affine, handle k's at k), for the
  //! skipping set_placements() allows; empty: every triangle is counted. O(#Fs), parallel, allocation-free (a
  //! second, serial pass only in a frame with a collapsed triangle or sizes beyond 1e±77). \throw UsageError
  //! before prepare() or for wrong row counts.
  int count(const Positions& S_deformed, const Positions& B_deformed,
            const std::vector<Mat4>& transforms = {}) const;

  //! Triangles count() would skip under these transforms (the rigidly moved ones).
  long skipped(const std::vector<Mat4>& transforms) const;

 private:
  // One run of consecutive triangles (in the stored order) with one placement code (Region codes; kFree:
  // not rigidly placed, always counted).
  struct Group {
    int code;
    long begin, end;
  };
  bool counted(const Group& g, const std::vector<Mat4>& transforms) const;

  Faces faces_, base_faces_;                // base_faces_ and reference_ are empty when shared_
  long num_vertices_ = -1, num_base_vertices_ = -1;
  bool shared_ = false;                     // S and B share connectivity: triangle t lies over triangle t
  Eigen::VectorXi reference_;               // per triangle of S: its base triangle
  std::vector<signed char> rest_sign_;      // sign of n_S · n_B at rest (0: not counted)
  // Triangles are stored grouped by placement code (set_placements), each group in S's order; before
  // that, one group of every triangle. order_[i]: the triangle of S stored at i.
  std::vector<Group> groups_;
  std::vector<int> order_;
  std::vector<char> near_perpendicular_;  // per triangle of S: rest normals within 1e-6 of perpendicular
};

}  // namespace msd
