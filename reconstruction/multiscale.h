#pragma once
//! \file The multi-scale deformer (seed 9.3, Fig. 9.7), composed of three parts chosen independently:
//! a decomposition S → B (reconstruction/decompose.h: low-pass, fairing, remeshed, subdivision), any base
//! deformer (a Deformer: the shell operator by default), and a detail encoding D = S ⊖ B with its options
//! (detail/encodings.h). prepare() decomposes, prepares the base deformer on the mesh it edits and
//! encodes; a frame deforms the base (B → B'), reconstructs S' = B' ⊕ D, places every fixed and handle
//! vertex of S exactly, and counts the triangles that folded over B'.

#include <memory>
#include <string>
#include <vector>

#include "msdeform/deformation/deformer.h"
#include "msdeform/detail/encodings.h"
#include "msdeform/detail/fold_check.h"
#include "msdeform/reconstruction/decompose.h"

namespace msd {

struct MultiscaleOptions {
  DecompositionOptions decomposition;
  EncodingOptions encoding;
};

//! prepare(): decompose() (refusing a base that lost the shape or details that fold at rest, see there),
//! the base deformer on Decomposition::edit, D = S ⊖ B (skipped when B = S). SolverError or
//! TopologyError of the base deformer are reported as a fault of the base B, not of the input.
//! deform(): B' from the base deformer (refined by the subdivision stencil for that kind), S' = B' ⊕ D,
//! then every fixed and handle vertex of S is placed exactly at p or T_k p (whatever the encoding, and
//! whether or not it has a base point). frame_report(): folded_faces counts the triangles of S' whose
//! normal turned against B''s (a warning names them); iterations and residual are those of an
//! iterative encoding (volumes) or base deformer.
class MultiscaleDeformer : public Deformer {
 public:
  //! base_deformer: the editing operator of the base; any method that takes affine handle transforms
  //! (null: the shell operator with default stiffnesses). name: reported by name() (default
  //! "multiscale-<encoding>"). \throw InvalidInput for a vectors encoding with a remeshed base (it needs
  //! S's connectivity), or a base deformer that is itself multi-scale.
  explicit MultiscaleDeformer(MultiscaleOptions options = {}, std::unique_ptr<Deformer> base_deformer = nullptr,
                              std::string name = {});
  const std::string& name() const override { return name_; }
  //! Surface, affine handles only, exact constraints; iterative when the encoding or the base deformer
  //! is; reproduces rigid motions when the base deformer does.
  DeformerTraits traits() const override;
  const MultiscaleOptions& options() const { return options_; }

  const Positions& base() const { return decomposition_.base; }              //!< B, #Vb by 3
  const Faces& base_faces() const { return decomposition_.base_faces; }      //!< B's triangles
  const Positions& deformed_base() const { return base_deformed_; }         //!< B' of the last frame
  const Deformer& base_deformer() const { return *base_deformer_; }
  //! The encoding; not encoded when the base is S itself (no detail layer found: S' = B').
  const DetailEncoding& encoding() const { return *encoding_; }
  const DecompositionReport& decomposition_report() const { return decomposition_.report; }

 protected:
  void do_prepare(const Positions& S, const Faces& F, const Region& region) override;
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) override;
  void do_reset() override;

 private:
  MultiscaleOptions options_;
  std::string name_;
  std::unique_ptr<Deformer> base_deformer_;
  std::unique_ptr<DetailEncoding> encoding_;
  Decomposition decomposition_;
  Positions edit_deformed_, base_deformed_;
  Positions rest_;                           // S, for placing the constrained vertices
  std::vector<std::pair<int, int>> placed_;  // (vertex of S, handle or -1 for fixed) placed exactly
  FoldCheck fold_check_;                     // folded triangles of S' against B', per frame
};

}  // namespace msd
