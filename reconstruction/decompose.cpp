#include "msdeform/reconstruction/decompose.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"
#include "msdeform/decomposition/remesh.h"
#include "msdeform/detail/closest_point.h"

namespace msd {

namespace {

constexpr DecompositionKind kKinds[] = {DecompositionKind::LowPass, DecompositionKind::Fairing,
                                        DecompositionKind::Remeshed, DecompositionKind::Subdivision};

// What to change when the decomposition is refused or warned about: the base lost the shape (lost_shape), or
// the details fold or come close to folding over it.
std::string remedy(const DecompositionReport& r, bool lost_shape) {
  if (r.kind == DecompositionKind::Fairing)  // (third break test: a fold warning said the shape was lost)
    return std::string(lost_shape
                           ? "fairing the free region removed the shape with the details (the free region "
                             "is large or tube-like next to the shape)"
                           : "the faired base curves tightly there for details of that height") +
           "; use the low-pass base (--base low-pass, the default), which keeps the shape, or a smaller free "
           "region";
  if (r.kind == DecompositionKind::Subdivision)
    return "the control mesh is too coarse for this shape; use the low-pass base (--base low-pass)";
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
std::string check_decomposition(const DecompositionReport& r, const DecompositionOptions& o, long num_vertices) {
  if (r.area_ratio < kMinBaseAreaRatio) {
    char text[200];
    std::snprintf(text, sizeof text, "decompose: the base lost the shape (its area over the triangles with a free vertex is %.3g "
                  "of the input's; the details would be the shape itself): ", r.area_ratio);
    throw TopologyError(text + remedy(r, true));
  }
  const DetailCheck& c = r.check;
  const bool folds = c.folding_vertices > 0, tall = c.fold_ratio_p999 > o.low_pass.max_fold_ratio;
  if (!folds && !tall) return {};
  char where[200];
  std::snprintf(where, sizeof where, "near vertex %d the detail height %.3g is %.3g times the base's curvature radius %.3g",
                c.worst_vertex, c.worst_height, c.max_fold_ratio, c.worst_radius);
  const std::string vertices =
      std::to_string(c.folding_vertices) + (c.folding_vertices == 1 ? " vertex" : " vertices");
  if (c.folding_vertices > static_cast<long>(1e-3 * static_cast<double>(num_vertices)))
    throw TopologyError("decompose: the details fold over at rest (" + vertices +
                        " with a height above the base's curvature radius; " + where +
                        "): " + remedy(r, false));
  if (folds)
    return "decompose: the details of " + vertices + " fold over at rest (" + where +
           "): " + remedy(r, false);
  return std::string("decompose: the details come close to folding over the base (") + where +
         "); an edit that bends the base further may fold them: " + remedy(r, false);
}

// Empty, or a warning naming a connected piece of S whose base lost its shape (area below half of the
// piece's) while the whole kept it: a small part's details are then its whole shape, and fold or stretch
// under an edit (an icosahedron of radius 0.01 beside the bunny, at detail scale 0.1).
std::string collapsed_piece_warning(const Positions& S, const Positions& B, const Faces& F) {
  const std::vector<int> piece = vertex_components(F, static_cast<int>(S.rows()));
  const int pieces = 1 + *std::max_element(piece.begin(), piece.end());
  if (pieces < 2) return {};
  std::vector<double> before(pieces, 0), after(pieces, 0);
  const Eigen::VectorXd a = face_areas(S, F), b = face_areas(B, F);
  for (Eigen::Index f = 0; f < F.rows(); ++f) before[piece[F(f, 0)]] += a[f], after[piece[F(f, 0)]] += b[f];
  for (int k = 0; k < pieces; ++k)
    if (before[k] > 0 && after[k] < kMinBaseAreaRatio * before[k]) {
      const int v = static_cast<int>(std::find(piece.begin(), piece.end(), k) - piece.begin());
      char text[320];
      std::snprintf(
          text, sizeof text,
          "decompose: the base lost the shape of one piece of the mesh (the piece of "
          "vertex %d: its base has %.3g of its area), so its details are its whole shape and fold or "
          "stretch under an edit; a smaller detail scale keeps it",
          v, after[k] / before[k]);
      return text;
    }
  return {};
}

// Remeshes B (the low-pass base) and moves the roles onto it. A remeshed base must stay as close to S as
// B is (up to 1 % of the diagonal): an edge length beyond the base's curvature radius cuts the shape
// (measured: edge 2 on the survey cylinder of radius 1 folds 765 triangles).
void remesh_base(const Positions& S, const Region& region, double edge, double diagonal, Decomposition& d) {
  RemeshResult r = remesh_isotropic(d.base, d.base_faces, edge);
  const std::vector<ClosestPoint> feet = ClosestPointQuery(r.P, r.F).query_all(S);  // S onto the new base
  DecompositionReport& report = d.report;
  report.remeshed_vertices = static_cast<int>(r.P.rows());
  report.remesh_edge_length = edge;
  // Vertices of S that no face uses have no surface to lie on: they take no part (CGAL's cube-ouvert.off has
  // one 1 unit off its surface, and every edge length was refused as lying 1 from the input).
  std::vector<char> used(S.rows(), 0);
  for (Eigen::Index f = 0; f < d.base_faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) used[d.base_faces(f, k)] = 1;
  double far = 0;
  long far_vertex = -1;
  bool free_used = false;
  for (long v = 0; v < S.rows(); ++v) {
    if (!used[v]) continue;
    free_used = free_used || region.is_free(static_cast<int>(v));
    if (const double distance = std::sqrt(feet[v].squared_distance); !(distance <= far))
      far = distance, far_vertex = v;
  }
  const double allowed = std::max(2 * report.check.max_height, 0.01 * diagonal);
  const int nb = static_cast<int>(r.P.rows());
  if (!(far <= allowed)) {
    char text[360];
    std::snprintf(text, sizeof text,
                  "decompose: the base remeshed to edge length %g (%d vertices) lies up to %.3g "
                  "from the input (at vertex %ld), more than %.3g (twice the detail height, or 1 %% of the "
                  "diagonal): the edges are too long for the shape; use a smaller --remesh-base",
                  edge, report.remeshed_vertices, far, far_vertex, allowed);
    throw InvalidInput(text);
  }
  // Every triangle that holds the closest point of a fixed or handle vertex of S gets that vertex's role on
  // all its corners, so those base points move exactly with their handle (or stay); the rest are free.
  std::vector<int> codes(r.P.rows(), Region::kFree);
  for (int v : region.constrained_vertices())
    if (used[v])
      for (int k = 0; k < 3; ++k) codes[r.F(feet[v].face, k)] = region.code(v);
  if (std::find(codes.begin(), codes.end(), Region::kFree) == codes.end() && free_used) {
    char text[300];  // measured: edge 0.9 of the diagonal on a 400-vertex grid: 5 base vertices, all placed
    std::snprintf(
        text, sizeof text,
        "decompose: the base remeshed to edge length %g has no free vertex (its %d vertices all lie "
        "under fixed or handle parts of S), so nothing deforms between them: the edges are too "
        "long for the region; use a smaller --remesh-base",
        edge, nb);
    throw InvalidInput(text);
  }
  d.edit_region = Region::from_codes(std::move(codes));
  d.base = std::move(r.P);
  d.base_faces = std::move(r.F);
}

}  // namespace

const char* to_string(DecompositionKind kind) {
  switch (kind) {
    case DecompositionKind::LowPass:
      return "low-pass";
    case DecompositionKind::Fairing:
      return "fairing";
    case DecompositionKind::Remeshed:
      return "remeshed";
    case DecompositionKind::Subdivision:
      return "subdivision";
  }
  return "invalid";
}

DecompositionKind decomposition_kind(const std::string& name) {
  for (DecompositionKind k : kKinds)
    if (name == to_string(k)) return k;
  throw InvalidInput("unknown decomposition '" + name + "' (known: low-pass, fairing, remeshed, subdivision)");
}

void DecompositionOptions::validate(const std::string& who) const {
  low_pass.validate(who);
  if (!(remesh_edge_length >= 0) || !std::isfinite(remesh_edge_length))
    throw InvalidInput(who +
                       ": the remeshing edge length must be finite and >= 0 (0 = the mean edge length)");
}

Decomposition decompose(const Positions& S, const Faces& F, const Region& region, const DecompositionOptions& o,
                        const std::function<void(const std::string&)>& progress) {
  check_mesh_arrays(S, F, "decompose");
  check_extent(S, "decompose");
  if (region.num_vertices() != S.rows())
    throw InvalidInput("decompose: the region has " + std::to_string(region.num_vertices()) +
                       " vertex labels but the mesh has " + std::to_string(S.rows()) + " vertices");
  o.validate("decompose");
  const double diagonal = bounding_box_diagonal(S);
  if (o.kind == DecompositionKind::Remeshed && o.remesh_edge_length > 0) {  // before the low-pass's work
    if (!(o.remesh_edge_length < diagonal)) {
      char text[300];
      std::snprintf(text, sizeof text,
                    "decompose: the remeshing edge length %.6g is not shorter than the mesh's "
                    "bounding-box diagonal %.6g: the base would lose the shape; use a smaller --remesh-base "
                    "(0: the mean edge length)",
                    o.remesh_edge_length, diagonal);
      throw InvalidInput(text);
    }
    check_remesh_size(S, F, o.remesh_edge_length, "decompose: --remesh-base");  // S's area is about B's
  }
  Decomposition d;
  DecompositionReport& report = d.report;
  report.kind = o.kind;
  d.base_faces = F;
  d.edit_region = region;
  switch (o.kind) {
    case DecompositionKind::LowPass:
    case DecompositionKind::Remeshed:
      d.base = o.low_pass_cache ? o.low_pass_cache->base(S, F, o.low_pass, &report.low_pass, progress)
                                : low_pass_base(S, F, o.low_pass, &report.low_pass, progress);  // S → B
      report.check = report.low_pass.check;
      break;
    case DecompositionKind::Fairing: {
      FairingOptions fairing;
      fairing.order = o.fairing;
      d.base = fair_region(S, F, region, fairing);
      report.check = check_details(S, d.base, F);
      break;
    }
    case DecompositionKind::Subdivision: {
      if (!o.control)
        throw InvalidInput("decompose: a subdivision base needs the control mesh that the input refines (the "
                           "built-in scenes carry one); use the low-pass base for other meshes");
      if (F.rows() != o.control->refinement.faces.rows() || F != o.control->refinement.faces)
        throw InvalidInput("decompose: the mesh is not the Loop refinement of the control mesh (its faces differ); "
                           "use the low-pass base for general meshes");
      auto hierarchy = std::make_shared<SubdivisionHierarchy>();
      hierarchy->build(S, F, o.control->P, o.control->F, o.control->refinement);  // B = Loop(control points)
      d.base = hierarchy->base();
      d.edit = hierarchy->control_points();
      d.edit_faces = o.control->F;
      d.edit_region = hierarchy->coarse_region(region);
      report.control_vertices = static_cast<int>(d.edit.rows());
      report.check = check_details(S, d.base, F);
      d.hierarchy = std::move(hierarchy);
      break;
    }
    default:
      throw InvalidInput("decompose: invalid DecompositionKind " + std::to_string(static_cast<int>(o.kind)));
  }
  report.area_ratio = free_area_ratio(S, d.base, F, region);
  report.warning = check_decomposition(report, o, S.rows());
  if (o.kind == DecompositionKind::LowPass && !report.low_pass.no_layer_reason.empty())
    report.warning =
        "decompose: no separate detail layer (" + report.low_pass.no_layer_reason +
        "), so the base is the mesh itself and there are no details: an edit is the base method's alone" +
        (report.low_pass.all_boundary ? "" : std::string("; ") + report.low_pass.no_layer_remedy());
  else if (report.warning.empty())
    report.warning = collapsed_piece_warning(S, d.base, F);
  if (o.kind == DecompositionKind::Remeshed)
    remesh_base(S, region, o.remesh_edge_length > 0 ? o.remesh_edge_length : mean_edge_length(S, F), diagonal,
                d);
  // Without a detail layer (B = S, see low_pass_base) every encoding would give S' = B'.
  d.base_is_input = o.kind == DecompositionKind::LowPass && d.base == S;
  if (!d.hierarchy) d.edit = d.base, d.edit_faces = d.base_faces;
  return d;
}

}  // namespace msd
