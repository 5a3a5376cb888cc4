#pragma once
//! \file Multi-scale editing on a subdivision hierarchy (Zorin et al. 1997; seed 9.3): for a mesh with
//! Loop subdivision connectivity the base B is the Loop refinement of a coarse control mesh, the shell
//! edit runs on the coarse mesh, and a precomputed stencil maps it to full resolution each frame.

#include <memory>
#include <string>

#include "core/subdivision.h"
#include "decomposition/subdivision_hierarchy.h"
#include "deformation/shell.h"
#include "detail/encoding.h"

namespace msd {

class SubdivisionMultiscaleDeformer : public Deformer {
 public:
  //! coarse (#Vc by 3) with coarse_faces: the control mesh whose `refinement` has S's connectivity (the
  //! generated scenes carry all three). encoding: a name from encoding_names(); local-frame vectors by
  //! default (S and B share connectivity here, and the vectors reproduce S exactly for any base).
  //! \throw InvalidInput for an unknown encoding or a refinement that does not match the coarse mesh.
  SubdivisionMultiscaleDeformer(Positions coarse, Faces coarse_faces, LoopRefinement refinement,
                                const std::string& encoding = "vectors", ShellOptions shell = {});
  const std::string& name() const override { return name_; }
  DeformerTraits traits() const override { return {}; }

  const SubdivisionHierarchy& hierarchy() const { return hierarchy_; }
  const Region& coarse_region() const { return coarse_region_; }

 protected:
  //! \throw InvalidInput if the mesh is not the refinement (other faces), TopologyError if the region
  //! leaves no fixed or handle vertex on the coarse mesh.
  void do_prepare(const Positions& S, const Faces& F, const Region& region) override;
  //! Shell on the coarse mesh, stencil product to B', then S' = B' ⊕ D: O(#V), allocation-free.
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) override;

 private:
  Positions coarse_;
  Faces coarse_faces_;
  LoopRefinement refinement_;
  std::string encoding_name_, name_;
  ShellDeformer shell_;
  std::unique_ptr<DetailEncoding> encoding_;
  SubdivisionHierarchy hierarchy_;
  Region coarse_region_;
  Positions coarse_deformed_, base_deformed_;
};

}  // namespace msd
