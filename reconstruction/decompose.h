#pragma once
//! \file The decomposition S → B of the multi-scale framework (seed 9.3, Fig. 9.7) in one call: the base
//! B of one of four kinds, the mesh the base deformer edits with the region on it, and the checks of the
//! details against the base. `msdeform decompose` and MultiscaleDeformer both use decompose().

#include <functional>
#include <memory>
#include <string>

#include "msdeform/core/region.h"
#include "msdeform/core/subdivision.h"
#include "msdeform/decomposition/detail_check.h"
#include "msdeform/decomposition/fairing.h"
#include "msdeform/decomposition/low_pass.h"
#include "msdeform/decomposition/subdivision_hierarchy.h"

namespace msd {

//! How the base B is computed from S.
enum class DecompositionKind {
  LowPass,      //!< low-pass of all of S at a detail scale (low_pass.h): keeps the shape, removes the details
  Fairing,      //!< the free region faired (fairing.h): only for free regions small next to the shape
  //! the low-pass base remeshed isotropically (remesh.h, end of 9.3.2): well-shaped triangles whatever S's
  //! look like; needs an encoding that allows other connectivity (normal, volumes, transfer)
  Remeshed,
  //! the Loop subdivision surface of a control mesh that S refines (Zorin et al. 1997): the base deformer
  //! edits the few control points and a precomputed stencil gives B' per frame
  Subdivision,
};
//! "low-pass", "fairing", "remeshed", "subdivision".
const char* to_string(DecompositionKind kind);
//! \throw InvalidInput for an unknown name, listing the known ones.
DecompositionKind decomposition_kind(const std::string& name);
//! Whether a base of this kind reads the low-pass detail scale (DecompositionOptions::low_pass): the
//! low-pass base and the remeshed one (a low-pass base remeshed), not the fairing or subdivision base.
inline bool reads_detail_scale(DecompositionKind kind) {
  return kind == DecompositionKind::LowPass || kind == DecompositionKind::Remeshed;
}

struct DecompositionOptions {
  DecompositionKind kind = DecompositionKind::LowPass;
  LowPassOptions low_pass;                         //!< LowPass and Remeshed: the detail scale and its search
  FairingOrder fairing = FairingOrder::ThinPlate;  //!< Fairing: the order of Δᵏ b = 0
  //! Remeshed: target edge length in mesh units; 0 takes the mean edge length of S.
  double remesh_edge_length = 0;
  //! Subdivision: the control mesh whose refinement S is (faces equal). Required for that kind.
  std::shared_ptr<const ControlMesh> control;
  //! LowPass, Remeshed: where the low-pass base is kept for the next decompose() of the same mesh with the
  //! same low_pass options, e.g. with another region (null: computed each time). Options copied from
  //! these share it.
  std::shared_ptr<LowPassCache> low_pass_cache;
  //! \throw InvalidInput naming `who` and the first option out of range (the low-pass options, the
  //! remeshing edge length); decompose() and MultiscaleDeformer's constructor call it.
  void validate(const std::string& who) const;
};

//! What decompose() found.
struct DecompositionReport {
  DecompositionKind kind = DecompositionKind::LowPass;
  LowPassReport low_pass;  //!< LowPass, Remeshed: the scale used and the candidates tried
  DetailCheck check;       //!< details against the base's curvature radii (on S's connectivity)
  //! Area of B over the area of S on the triangles that touch a free vertex; below 0.5 the base lost the
  //! shape (a faired cylinder: 0.05) and decompose() refuses it.
  double area_ratio = 1;
  int remeshed_vertices = 0;  //!< Remeshed: vertices of the new base
  double remesh_edge_length = 0;  //!< Remeshed: the edge length used
  int control_vertices = 0;   //!< Subdivision: vertices of the control mesh
  //! Non-empty when a few vertices' details fold at rest (at most 0.1 % of them: mesh defects) or the
  //! details stand taller than LowPassOptions::max_fold_ratio of the base's curvature radius: the edit
  //! may fold them; says what to change.
  std::string warning;
};

//! The decomposition and the mesh the base deformer edits.
struct Decomposition {
  Positions base;  //!< B, #Vb by 3
  Faces base_faces;  //!< B's triangles: S's, except for Remeshed
  //! What the base deformer edits: B itself with S's region (LowPass, Fairing), the remeshed B with the
  //! roles moved onto it (Remeshed: every corner of the base triangle that holds the closest point of a
  //! fixed or handle vertex of S takes that vertex's role), or the control mesh with the region of its
  //! vertex-children (Subdivision).
  Positions edit;
  Faces edit_faces;
  Region edit_region;
  //! Subdivision: B = hierarchy->refine(edit); null for the other kinds (B = edit).
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
  //! No detail layer was found (LowPass without a plateau): B = S and the details are empty.
  bool base_is_input = false;
  DecompositionReport report;
};

//! S: #V by 3 with faces F; region: #V codes (the fixed and handle vertices keep their roles on the
//! base; LowPass, Remeshed and Subdivision need no handles, Fairing needs constrained vertices).
//! \throw InvalidInput for bad arrays or options, a Subdivision without a control mesh or with other
//! faces, a remeshed base farther from S than twice the detail height (or 1 % of the diagonal);
//! TopologyError when the base lost the shape (area_ratio < 0.5) or the details fold at rest on more than
//! 0.1 % of the vertices, naming a vertex, the height, the radius and a remedy; as low_pass_base(),
//! fair_region(), remesh_isotropic() and SubdivisionHierarchy::build().
//! progress, when given, receives the low-pass base's line per candidate of its automatic scale.
Decomposition decompose(const Positions& S, const Faces& F, const Region& region, const DecompositionOptions& options = {},
                        const std::function<void(const std::string&)>& progress = {});

}  // namespace msd
