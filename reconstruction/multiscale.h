#pragma once
//! \file The multi-scale deformer (seed 9.3, Fig. 9.7): decompose S into a faired base B and details
//! D = S ⊖ B once; per frame deform B with the shell operator (precomputed basis) and reconstruct
//! S' = B' ⊕ D.

#include <memory>
#include <string>
#include <vector>

#include "decomposition/fairing.h"
#include "deformation/shell.h"
#include "detail/encoding.h"

namespace msd {

struct MultiscaleOptions {
  //! Decomposition: order of the fairing of the free region (the base B keeps S on fixed and handle
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
  //! The remeshed base only approximates S on the fixed and handle parts, so after reconstruction those
  //! vertices of S are placed exactly (p, or T_k p) as with every other method.
  double remesh_base_edge_length = 0;
};

//! Detail encodings available to the multi-scale deformer: "vectors" (local-frame displacement
//! vectors, 9.3.1), "normal" (normal displacements, 9.3.2), "volumes" (displacement volumes, 9.3.3),
//! "transfer" (deformation transfer, 9.3.3).
std::vector<std::string> encoding_names();
//! A new encoding by name. \throw InvalidInput for an unknown name, listing the known ones.
std::unique_ptr<DetailEncoding> make_encoding(const std::string& name);

class MultiscaleDeformer : public Deformer {
 public:
  //! \throw InvalidInput for an unknown encoding or invalid shell stiffnesses.
  explicit MultiscaleDeformer(MultiscaleOptions options = {});
  std::string name() const override { return "multiscale-" + options_.encoding; }
  const MultiscaleOptions& options() const { return options_; }

  const Positions& base() const { return base_; }                    //!< B, #Vb by 3
  const Faces& base_faces() const { return base_faces_; }            //!< B's triangles (S's unless remeshed)
  const Positions& deformed_base() const { return base_deformed_; }  //!< B' of the last frame
  const DetailEncoding& encoding() const { return *encoding_; }

 protected:
  void do_prepare(const Mesh& mesh, const Region& region) override;
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) override;

 private:
  MultiscaleOptions options_;
  ShellDeformer shell_;
  std::unique_ptr<DetailEncoding> encoding_;
  Positions base_, base_deformed_;
  Faces base_faces_;
  Positions rest_;                           // S, for placing constrained vertices on a remeshed base
  std::vector<std::pair<int, int>> placed_;  // (vertex of S, handle or -1 for fixed) placed exactly
};

}  // namespace msd
