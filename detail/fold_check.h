#pragma once
//! \file The per-frame fold check of the multi-scale framework (seed 9.3.3, Fig. 9.10): where the
//! deformed base B' curves more than 1/h, neighbouring displacements of height h cross and triangles of
//! the reconstructed S' turn over. Each triangle of S is compared with the base triangle under it: it
//! folded when the sign of n_S' · n_B' is the opposite of the sign of n_S · n_B at rest (a triangle that
//! collapsed to zero area has no normal and is not counted).

#include <vector>

#include "msdeform/core/types.h"

namespace msd {

class FoldCheck {
 public:
  //! S: #Vs by 3 with faces Fs; B: #Vb by 3 with faces Fb. With identical connectivity triangle t of S is
  //! compared with triangle t of B; otherwise with the base triangle closest to its centroid (Embree).
  //! Triangles of S or B of zero area at rest (below 1e-14 of their squared longest edge, as in
  //! cotan_laplacian: their orientation is rounding noise) are not counted. \throw InvalidInput for an index
  //! out of range.
  void prepare(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb);
  //! Triangles of S' (#Vs by 3) whose orientation against B' (#Vb by 3) differs from the rest pose, right at
  //! any finite size. O(#Fs), parallel, allocation-free (a second, serial pass only in a frame with a
  //! collapsed triangle or sizes beyond 1e±77). \throw UsageError before prepare() or for wrong row counts.
  int count(const Positions& S_deformed, const Positions& B_deformed) const;

 private:
  Faces faces_, base_faces_;                // base_faces_ and reference_ are empty when shared_
  long num_vertices_ = -1, num_base_vertices_ = -1;
  bool shared_ = false;                     // S and B share connectivity: triangle t lies over triangle t
  Eigen::VectorXi reference_;               // per triangle of S: its base triangle
  std::vector<signed char> rest_sign_;      // sign of n_S · n_B at rest (0: not counted)
};

}  // namespace msd
