#include "reconstruction/subdivision_multiscale.h"

#include "core/errors.h"
#include "reconstruction/multiscale.h"

namespace msd {

SubdivisionMultiscaleDeformer::SubdivisionMultiscaleDeformer(Positions coarse, Faces coarse_faces,
                                                             LoopRefinement refinement, const std::string& encoding,
                                                             ShellOptions shell)
    : coarse_(std::move(coarse)),
      coarse_faces_(std::move(coarse_faces)),
      refinement_(std::move(refinement)),
      encoding_name_(encoding),
      name_("multiscale-subdivision-" + encoding),
      shell_(shell),
      encoding_(make_encoding(encoding)) {
  if (refinement_.loop.cols() != coarse_.rows())
    throw InvalidInput("multiscale-subdivision: the refinement has " + std::to_string(refinement_.loop.cols()) +
                       " coarse vertices, the control mesh " + std::to_string(coarse_.rows()));
}

void SubdivisionMultiscaleDeformer::do_prepare(const Positions& S, const Faces& F, const Region& region) {
  if (F.rows() != refinement_.faces.rows() || F != refinement_.faces)
    throw InvalidInput("multiscale-subdivision: the mesh is not the Loop refinement of the control mesh "
                       "(its faces differ); use the multiscale method for general meshes");
  hierarchy_.build(S, F, coarse_, coarse_faces_, refinement_);  // B = Loop(control points), D = S − B
  coarse_region_ = hierarchy_.coarse_region(region);
  shell_.prepare(hierarchy_.control_points(), coarse_faces_, coarse_region_);
  encoding_->set_anchor_vertices(region.constrained_vertices());
  encoding_->encode(S, F, hierarchy_.base(), F);
  coarse_deformed_ = hierarchy_.control_points();
  base_deformed_ = hierarchy_.base();
}

void SubdivisionMultiscaleDeformer::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  shell_.deform(transforms, coarse_deformed_);           // the edit, on the coarse mesh
  hierarchy_.refine(coarse_deformed_, base_deformed_);   // B' = stencil · coarse'
  encoding_->reconstruct(base_deformed_, out);           // S' = B' ⊕ D
}

}  // namespace msd
