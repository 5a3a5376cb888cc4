#include "deformation/deformer.h"

#include <cmath>

#include "core/errors.h"

namespace msd {

void check_affine(const std::vector<Mat4>& transforms, const char* who) {
  for (size_t k = 0; k < transforms.size(); ++k) {
    if (!transforms[k].allFinite())
      throw InvalidInput(std::string(who) + ": transform of handle " + std::to_string(k) + " has a non-finite entry");
    if ((transforms[k].row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-12)
      throw InvalidInput(std::string(who) + ": transform of handle " + std::to_string(k) +
                         " is not affine (last row must be 0 0 0 1)");
  }
}

void Deformer::prepare(const Mesh& mesh, const Region& region) {
  prepared_ = false;
  region.validate(mesh);
  if (region.num_handles() == 0)
    throw InvalidInput(name() + ": the region has no handle vertex (selection code 2 or higher); nothing to move");
  do_prepare(mesh, region);
  num_handles_ = region.num_handles();
  num_vertices_ = region.num_vertices();
  prepared_ = true;
}

void Deformer::deform(const std::vector<Mat4>& transforms, Positions& out) {
  if (!prepared_) throw UsageError(name() + ": deform() called before prepare()");
  if (static_cast<int>(transforms.size()) != num_handles_)
    throw UsageError(name() + ": " + std::to_string(transforms.size()) + " handle transforms given, the region has " +
                     std::to_string(num_handles_) + " handle(s)");
  check_affine(transforms, name().c_str());
  if (out.rows() != num_vertices_) out.resize(num_vertices_, 3);
  do_deform(transforms, out);
  if (!out.allFinite())
    for (Eigen::Index v = 0; v < out.rows(); ++v)
      if (!out.row(v).allFinite())
        throw SolverError(name() + ": the frame gave vertex " + std::to_string(v) + " a non-finite position",
                          static_cast<int>(v));
}

Positions Deformer::deform(const std::vector<Mat4>& transforms) {
  Positions out;
  deform(transforms, out);
  return out;
}

}  // namespace msd
