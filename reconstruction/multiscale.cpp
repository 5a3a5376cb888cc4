#include "reconstruction/multiscale.h"

#include <cmath>

#include "core/errors.h"
#include "decomposition/remesh.h"
#include "detail/closest_point.h"
#include "detail/deformation_transfer.h"
#include "detail/displacement_vectors.h"
#include "detail/displacement_volumes.h"
#include "detail/normal_displacements.h"

namespace msd {

std::vector<std::string> encoding_names() { return {"vectors", "normal", "volumes", "transfer"}; }

std::unique_ptr<DetailEncoding> make_encoding(const std::string& name) {
  if (name == "vectors") return std::make_unique<DisplacementVectors>();
  if (name == "normal") return std::make_unique<NormalDisplacements>();
  if (name == "volumes") return std::make_unique<DisplacementVolumes>();
  if (name == "transfer") return std::make_unique<DeformationTransfer>();
  std::string known;
  for (const auto& n : encoding_names()) known += (known.empty() ? "" : ", ") + n;
  throw InvalidInput("unknown detail encoding '" + name + "' (known: " + known + ")");
}

namespace {

// Roles on a remeshed base: each vertex takes the role of the original base vertex nearest to it
// (the corner of its closest triangle with the largest barycentric weight).
Region transfer_region(const Positions& B, const Faces& F, const Region& region, const Positions& remeshed) {
  const ClosestPointQuery query(B, F);
  std::vector<int> codes(remeshed.rows());
  for (Eigen::Index i = 0; i < remeshed.rows(); ++i) {
    const ClosestPoint c = query.query(remeshed.row(i).transpose());
    Eigen::Index corner;
    c.barycentric.maxCoeff(&corner);
    codes[i] = region.code(F(c.face, static_cast<int>(corner)));
  }
  return Region::from_codes(std::move(codes));
}

}  // namespace

MultiscaleDeformer::MultiscaleDeformer(MultiscaleOptions options)
    : options_(std::move(options)), shell_(options_.shell), encoding_(make_encoding(options_.encoding)) {
  if (!(options_.remesh_base_edge_length >= 0) || !std::isfinite(options_.remesh_base_edge_length))
    throw InvalidInput("multiscale: the base remeshing edge length must be finite and >= 0 (0 = no remeshing)");
  if (options_.remesh_base_edge_length > 0 && options_.encoding == "vectors")
    throw InvalidInput("multiscale: displacement vectors need S and B to share connectivity; a remeshed base needs "
                       "the normal, volumes or transfer encoding");
}

void MultiscaleDeformer::do_prepare(const Mesh& mesh, const Region& region) {
  const Positions S = positions(mesh);
  const Faces F = faces(mesh);
  FairingOptions fairing;
  fairing.order = options_.fairing;
  base_ = fair_region(mesh, region, fairing);  // S → B
  base_faces_ = F;
  Region base_region = region;
  if (options_.remesh_base_edge_length > 0) {
    RemeshResult r = remesh_isotropic(base_, F, options_.remesh_base_edge_length);
    base_region = transfer_region(base_, F, region, r.P);
    base_ = std::move(r.P);
    base_faces_ = std::move(r.F);
  }
  const Mesh base_mesh = make_mesh(base_, base_faces_);
  shell_.prepare(base_mesh, base_region);
  encoding_->set_anchor_vertices(region.constrained_vertices());
  encoding_->encode(S, F, base_, base_faces_);  // D = S ⊖ B
  base_deformed_ = base_;
}

void MultiscaleDeformer::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  shell_.deform(transforms, base_deformed_);    // B → B'
  encoding_->reconstruct(base_deformed_, out);  // S' = B' ⊕ D
}

}  // namespace msd
