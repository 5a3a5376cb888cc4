#include "reconstruction/multiscale.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

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

// A base with less than this fraction of S's area around the free region has lost the shape.
constexpr double kMinBaseAreaRatio = 0.5;

// Roles on a remeshed base: every triangle that holds the closest point of a fixed or handle vertex of
// S gets that vertex's role on all its corners, so those vertices' base points move exactly with their
// handle (or stay); all other base vertices are free. feet: the closest points of S's vertices.
Region transfer_region(const Region& region, const std::vector<ClosestPoint>& feet, const RemeshResult& base) {
  std::vector<int> codes(base.P.rows(), Region::kFree);
  for (int v : region.constrained_vertices())
    for (int k = 0; k < 3; ++k) codes[base.F(feet[v].face, k)] = region.code(v);
  return Region::from_codes(std::move(codes));
}

// What to change when the decomposition is refused or warned about.
std::string remedy(const DecompositionReport& r) {
  if (r.base == BaseKind::Fairing)
    return "fairing the free region removed the shape with the details (the free region is large or tube-like "
           "next to the shape); use the low-pass base (--base low-pass, the default), which keeps the shape, or a "
           "smaller free region";
  if (!r.low_pass.automatic) {
    char text[160];
    std::snprintf(text, sizeof text, "the detail scale %g is too large for this shape; use a smaller one, or 0 to "
                  "choose it automatically", r.low_pass.detail_scale);
    return text;
  }
  return "the mesh has defects there (slivers or near-duplicate vertices); repair them, or set a smaller detail scale";
}

// Refuses a base that lost the shape (less than half the area of S where S is free to move) or that the
// details fold over at rest (beyond a few defect vertices), naming the cause and a remedy; returns a warning
// when a few vertices fold or the details come close to folding.
std::string check_decomposition(const DecompositionReport& r, const MultiscaleOptions& o, long num_vertices) {
  if (r.area_ratio < kMinBaseAreaRatio) {
    char text[200];
    std::snprintf(text, sizeof text, "multiscale: the base lost the shape (its area around the free region is %.3g "
                  "of the input's; the details would be the shape itself): ", r.area_ratio);
    throw TopologyError(text + remedy(r));
  }
  const DetailCheck& c = r.check;
  const bool folds = c.folding_vertices > 0, tall = c.fold_ratio_p999 > o.low_pass.max_fold_ratio;
  if (!folds && !tall) return {};
  char where[200];
  std::snprintf(where, sizeof where, "near vertex %d the detail height %.3g is %.3g times the base's curvature radius %.3g",
                c.worst_vertex, c.worst_height, c.max_fold_ratio, c.worst_radius);
  if (c.folding_vertices > static_cast<long>(1e-3 * static_cast<double>(num_vertices)))
    throw TopologyError("multiscale: the details fold over at rest (" + std::to_string(c.folding_vertices) +
                        " vertices with a height above the base's curvature radius; " + where + "): " + remedy(r));
  if (folds)
    return "multiscale: the details of " + std::to_string(c.folding_vertices) + " vertices fold over at rest (" +
           where + "): " + remedy(r);
  return std::string("multiscale: the details come close to folding over the base (") + where +
         "); an edit that bends the base further may fold them: " + remedy(r);
}

// A remeshed base must stay as close to S as B is (up to 1 % of the diagonal): an edge length beyond the
// base's curvature radius cuts the shape (measured: edge 2 on the survey cylinder of radius 1 folds 765
// triangles).
void check_remeshed_base(const Positions& S, const std::vector<ClosestPoint>& feet, const RemeshResult& r,
                         DecompositionReport& report, double edge) {
  report.remeshed_vertices = static_cast<int>(r.P.rows());
  double far = 0;
  for (const ClosestPoint& c : feet) far = std::max(far, std::sqrt(c.squared_distance));
  const double allowed = std::max(2 * report.check.max_height, 0.01 * bounding_box_diagonal(S));
  if (!(far <= allowed)) {
    char text[300];
    std::snprintf(text, sizeof text, "multiscale: the base remeshed to edge length %g (%d vertices) lies up to %.3g "
                  "from the input, more than %.3g (twice the detail height, or 1 %% of the diagonal): the edges are "
                  "too long for the shape; use a smaller --remesh-base", edge, report.remeshed_vertices, far, allowed);
    throw InvalidInput(text);
  }
}

// Area of B over the area of S on the triangles with a free vertex (all of them when none is free).
double free_area_ratio(const Positions& S, const Positions& B, const Faces& F, const Region& region) {
  double rest = 0, base = 0;
  const Eigen::VectorXd a = face_areas(S, F), b = face_areas(B, F);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    if (region.code(F(f, 0)) == Region::kFree || region.code(F(f, 1)) == Region::kFree ||
        region.code(F(f, 2)) == Region::kFree)
      rest += a[f], base += b[f];
  return rest > 0 ? base / rest : a.sum() > 0 ? b.sum() / a.sum() : 1.0;
}

}  // namespace

const char* to_string(BaseKind kind) { return kind == BaseKind::LowPass ? "low-pass" : "fairing"; }

MultiscaleDeformer::MultiscaleDeformer(MultiscaleOptions options)
    : options_(std::move(options)),
      name_("multiscale-" + options_.encoding),
      shell_(options_.shell),
      encoding_(make_encoding(options_.encoding)) {
  if (!(options_.remesh_base_edge_length >= 0) || !std::isfinite(options_.remesh_base_edge_length))
    throw InvalidInput("multiscale: the base remeshing edge length must be finite and >= 0 (0 = no remeshing)");
  if (!(options_.low_pass.detail_scale >= 0) || !std::isfinite(options_.low_pass.detail_scale))
    throw InvalidInput("multiscale: the detail scale must be finite and >= 0 (0 = automatic)");
  if (options_.remesh_base_edge_length > 0 && options_.encoding == "vectors")
    throw InvalidInput("multiscale: displacement vectors need S and B to share connectivity; a remeshed base needs "
                       "the normal, volumes or transfer encoding");
}

DeformerTraits MultiscaleDeformer::traits() const {
  DeformerTraits t;
  if (options_.encoding == "volumes") t.solve = DeformerSolve::Iterative;
  return t;
}

void MultiscaleDeformer::do_prepare(const Positions& S, const Faces& F, const Region& region) {
  decomposition_ = {};
  decomposition_.base = options_.base;
  if (options_.base == BaseKind::LowPass) {
    base_ = low_pass_base(S, F, options_.low_pass, &decomposition_.low_pass);  // S → B
    decomposition_.check = decomposition_.low_pass.check;
  } else {
    FairingOptions fairing;
    fairing.order = options_.fairing;
    base_ = fair_region(S, F, region, fairing);
    decomposition_.check = check_details(S, base_, F);
  }
  decomposition_.area_ratio = free_area_ratio(S, base_, F, region);
  decomposition_.warning = check_decomposition(decomposition_, options_, S.rows());
  base_faces_ = F;
  Region base_region = region;
  if (options_.remesh_base_edge_length > 0) {
    RemeshResult r = remesh_isotropic(base_, F, options_.remesh_base_edge_length);
    const std::vector<ClosestPoint> feet = ClosestPointQuery(r.P, r.F).query_all(S);  // S onto the new base
    check_remeshed_base(S, feet, r, decomposition_, options_.remesh_base_edge_length);
    base_region = transfer_region(region, feet, r);
    base_ = std::move(r.P);
    base_faces_ = std::move(r.F);
  }
  try {
    shell_.prepare(base_, base_faces_, base_region);
  } catch (const Error& e) {
    throw SolverError(std::string("multiscale: the shell operator on the base B (not the input mesh) failed; the "
                                  "base is degenerate there, try a smaller detail scale: ") + e.what());
  }
  // Without a detail layer (B = S, see low_pass_base) every encoding would give S' = B': skip it.
  base_is_input_ = options_.remesh_base_edge_length == 0 && base_ == S;
  encoding_->set_anchor_vertices(region.constrained_vertices());
  if (!base_is_input_) encoding_->encode(S, F, base_, base_faces_);  // D = S ⊖ B
  base_deformed_ = base_;

  // Every constrained vertex of S is placed exactly after reconstruction.
  rest_ = S;
  placed_.clear();
  for (int v : region.constrained_vertices()) placed_.emplace_back(v, region.handle_of(v));
  fold_check_.prepare(S, F, base_, base_faces_);
}

void MultiscaleDeformer::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  shell_.deform(transforms, base_deformed_);  // B → B'
  if (base_is_input_)
    out = base_deformed_;  // no detail layer: S' = B'
  else
    encoding_->reconstruct(base_deformed_, out);  // S' = B' ⊕ D
  for (const auto& [v, k] : placed_) {
    const Vec3 p = rest_.row(v);
    out.row(v) = k < 0 ? p : transform_point(transforms[k], p);
  }
  frame_report_.folded_faces = fold_check_.count(out, base_deformed_);
}

}  // namespace msd
