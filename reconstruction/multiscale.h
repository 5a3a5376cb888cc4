#pragma once
//! \file The multi-scale deformer (seed 9.3, Fig. 9.7): decompose S into a smooth base B and details
//! D = S ⊖ B once; per frame deform B with the shell operator (precomputed basis) and reconstruct
//! S' = B' ⊕ D. The base is a low-pass of S at a detail scale (decomposition/low_pass.h) by default, or
//! the faired free region (decomposition/fairing.h). Before any frame the details are checked against the
//! base's curvature (decomposition/detail_check.h); every frame counts the triangles that folded.

#include <memory>
#include <string>
#include <vector>

#include "decomposition/detail_check.h"
#include "decomposition/fairing.h"
#include "decomposition/low_pass.h"
#include "deformation/shell.h"
#include "detail/encoding.h"
#include "detail/fold_check.h"

namespace msd {

//! How the base B is computed from S.
enum class BaseKind {
  LowPass,  //!< low-pass of all of S at a detail scale (low_pass.h); keeps the shape, removes the details
  Fairing,  //!< the free region faired (fairing.h); only for free regions small next to the shape
};
const char* to_string(BaseKind kind);

struct MultiscaleOptions {
  BaseKind base = BaseKind::LowPass;
  //! BaseKind::LowPass: the detail scale (0 = automatic from the fold check) and its search.
  LowPassOptions low_pass;
  //! BaseKind::Fairing: order of the fairing of the free region (the base B keeps S on fixed and handle
  //! vertices and is Δᵏ-fair inside).
  FairingOrder fairing = FairingOrder::ThinPlate;
  //! Detail encoding by name: see encoding_names().
  std::string encoding = "normal";
  //! The editing operator applied to the base.
  ShellOptions shell;
  //! > 0: remesh the base isotropically to this edge length before encoding (end of 9.3.2), for a
  //! well-shaped base whatever the triangles of S look like. Needs an encoding that allows different
  //! connectivity (normal, volumes, transfer). On the remeshed base, the corners of every triangle that
  //! holds the closest point of a fixed or handle vertex of S take that vertex's role; the rest are free.
  double remesh_base_edge_length = 0;
};

//! What prepare() found about the decomposition.
struct DecompositionReport {
  BaseKind base = BaseKind::LowPass;
  LowPassReport low_pass;  //!< BaseKind::LowPass: the scale used and the candidates tried
  DetailCheck check;       //!< details against the base's curvature radii (S's connectivity)
  //! Area of B over the area of S on the triangles that touch a free vertex; below 0.5 the base lost the
  //! shape (a faired cylinder: 0.05) and prepare() refuses it.
  double area_ratio = 1;
  int remeshed_vertices = 0;  //!< vertices of the remeshed base (MultiscaleOptions::remesh_base_edge_length > 0)
  //! Non-empty when a few vertices' details fold at rest (at most 0.1 % of them: mesh defects) or the
  //! details stand taller than LowPassOptions::max_fold_ratio of the base's curvature radius: the
  //! edit may fold them; says what to change.
  std::string warning;
};

//! Detail encodings available to the multi-scale deformer: "vectors" (local-frame displacement
//! vectors, 9.3.1), "normal" (normal displacements, 9.3.2), "volumes" (displacement volumes, 9.3.3),
//! "transfer" (deformation transfer, 9.3.3).
std::vector<std::string> encoding_names();
//! A new encoding by name. \throw InvalidInput for an unknown name, listing the known ones.
std::unique_ptr<DetailEncoding> make_encoding(const std::string& name);

//! prepare(): B from S (options().base), the fold check, the shell operator on B, D = S ⊖ B.
//! \throw TopologyError when the base lost the shape (DecompositionReport::area_ratio < 0.5) or the
//! details fold at rest on more than 0.1 % of the vertices (fold ratio ≥ 1:
//! displacements taller than the base's curvature radius), naming a vertex, the height, the radius and a
//! remedy; SolverError from the
//! shell operator is reported as a fault of the base B, not of the input.
//! InvalidInput when a remeshed base lies farther from S than twice the detail height (or 1 % of the
//! diagonal): its edges are too long for the shape.
//! deform(): B' from the shell, S' = B' ⊕ D, then every fixed and handle vertex of S is placed exactly at
//! p or T_k p (whatever the encoding, and whether or not it has a base point); frame_report().folded_faces
//! counts the triangles of S' whose normal turned against B''s.
class MultiscaleDeformer : public Deformer {
 public:
  //! \throw InvalidInput for an unknown encoding or invalid shell stiffnesses.
  explicit MultiscaleDeformer(MultiscaleOptions options = {});
  const std::string& name() const override { return name_; }
  DeformerTraits traits() const override;
  const MultiscaleOptions& options() const { return options_; }

  const Positions& base() const { return base_; }                    //!< B, #Vb by 3
  const Faces& base_faces() const { return base_faces_; }            //!< B's triangles (S's unless remeshed)
  const Positions& deformed_base() const { return base_deformed_; }  //!< B' of the last frame
  //! The encoding; not encoded when the base is S itself (no detail layer found: S' = B').
  const DetailEncoding& encoding() const { return *encoding_; }
  const DecompositionReport& decomposition_report() const { return decomposition_; }

 protected:
  void do_prepare(const Positions& S, const Faces& F, const Region& region) override;
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) override;

 private:
  MultiscaleOptions options_;
  std::string name_;
  ShellDeformer shell_;
  std::unique_ptr<DetailEncoding> encoding_;
  Positions base_, base_deformed_;
  Faces base_faces_;
  DecompositionReport decomposition_;
  Positions rest_;                           // S, for placing the constrained vertices
  std::vector<std::pair<int, int>> placed_;  // (vertex of S, handle or -1 for fixed) placed exactly
  bool base_is_input_ = false;                // B = S: no details, S' = B'
  FoldCheck fold_check_;                     // folded triangles of S' against B', per frame
};

}  // namespace msd
