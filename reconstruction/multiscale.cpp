#include "reconstruction/multiscale.h"

#include <cmath>

#include "core/errors.h"
#include "core/laplacian.h"
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

// Roles on a remeshed base: every triangle that holds the closest point of a fixed or handle vertex of
// S gets that vertex's role on all its corners, so those vertices' base points move exactly with their
// handle (or stay); all other base vertices are free.
Region transfer_region(const Positions& S, const Region& region, const Positions& base, const Faces& base_faces) {
  const ClosestPointQuery query(base, base_faces);
  std::vector<int> codes(base.rows(), Region::kFree);
  for (int v : region.constrained_vertices()) {
    const ClosestPoint c = query.query(S.row(v).transpose());
    for (int k = 0; k < 3; ++k) codes[base_faces(c.face, k)] = region.code(v);
  }
  return Region::from_codes(std::move(codes));
}

// Fairing a large or tube-like free region can shrink it to (nearly) nothing; the shell operator on such
// a base is singular. Say so in terms of the decomposition rather than let the solver fail.
void check_base(const Mesh& mesh, const Positions& S, const Positions& B, const Faces& F) {
  const Eigen::VectorXd rest = cotan_laplacian(S, F).mass, base = cotan_laplacian(B, F).mass;
  for (auto v : mesh.vertices()) {
    const int i = v.idx();
    if (rest[i] > 0 && !(base[i] > 1e-6 * rest[i]))
      throw TopologyError("multiscale: fairing the free region collapsed the base near vertex " + std::to_string(i) +
                          " (its area fell to " + std::to_string(base[i] / rest[i]) +
                          " of the input's): the free region is too large or tube-like for a faired base. Use a "
                          "smaller free region, a lower fairing order, or the shell method directly");
  }
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
  check_base(mesh, S, base_, F);
  base_faces_ = F;
  Region base_region = region;
  placed_.clear();
  if (options_.remesh_base_edge_length > 0) {
    rest_ = S;
    for (int v : region.constrained_vertices()) placed_.emplace_back(v, region.handle_of(v));
    RemeshResult r = remesh_isotropic(base_, F, options_.remesh_base_edge_length);
    base_region = transfer_region(S, region, r.P, r.F);
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
  for (const auto& [v, k] : placed_) {
    const Vec3 p = rest_.row(v);
    out.row(v) = k < 0 ? p : transform_point(transforms[k], p);
  }
}

}  // namespace msd
