#include "msdeform/deformation/deformer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/rotation.h"
#include "msdeform/core/surface_check.h"

namespace msd {
namespace {

std::string role(const Region& region, int v) {
  return region.is_fixed(v) ? "fixed" : "handle " + std::to_string(region.handle_of(v));
}

// Edges whose two vertices the edit places itself, by different transforms (fixed and a handle, or two
// handles): no free vertex lies between them, so no method can keep them from stretching as the handles
// move. Empty when there are none.
std::string torn_edges_warning(const Faces& F, const Region& region, const std::string& who) {
  std::vector<std::pair<int, int>> torn;  // (smaller, larger) vertex, once per triangle that has the edge
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int i = F(f, k), j = F(f, (k + 1) % 3);
      if (region.placed_apart(i, j)) torn.emplace_back(std::min(i, j), std::max(i, j));
    }
  if (torn.empty()) return {};
  std::sort(torn.begin(), torn.end());
  const long edges = std::unique(torn.begin(), torn.end()) - torn.begin();
  const auto [a, b] = torn.front();
  const bool no_free = region.free_vertices().empty();
  return who + ": " + (no_free ? "the region has no free vertex, and " : "") + std::to_string(edges) +
         (edges == 1 ? " edge joins " : " edges join ") + kTornEdgesWarning + " (e.g. vertex " +
         std::to_string(a) + ", " + role(region, a) + ", and vertex " + std::to_string(b) + ", " +
         role(region, b) +
         "): nothing deforms between them, so they stretch or tear as the handles move; leave free vertices "
         "between the fixed part and each handle";
}

}  // namespace

void check_affine(const std::vector<Mat4>& transforms, const std::string& who) {
  for (size_t k = 0; k < transforms.size(); ++k) {
    if (!transforms[k].allFinite())
      throw InvalidInput(who + ": transform of handle " + std::to_string(k) + " has a non-finite entry");
    if ((transforms[k].row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-12)
      throw InvalidInput(who + ": transform of handle " + std::to_string(k) +
                         " is not affine (last row must be 0 0 0 1)");
    if (!(transforms[k].cwiseAbs().maxCoeff() < kMaxExtent))  // its results would overflow the areas
      throw InvalidInput(who + ": transform of handle " + std::to_string(k) + " has an entry of " +
                         format_number(transforms[k].cwiseAbs().maxCoeff()) +
                         "; msdeform works with sizes up to 1e70");
  }
}

void handle_transform_warnings(const std::vector<Mat4>& transforms, const std::string& who,
                               std::vector<std::string>& warnings) {
  for (size_t k = 0; k < transforms.size(); ++k) {
    // The numerical rank (singular values above 1e-12 of the largest, and above 1e-6: a uniform scale by
    // 1e-12 collapses the handle too) decides: below 3 the map keeps as many dimensions of the handle (a
    // plane, a line, a point); at 3 a negative determinant (of A over its largest singular value, which
    // neither underflows nor overflows) is a reflection.
    const Mat3 A = transforms[k].topLeftCorner<3, 3>();
    const Vec3 sigma = Eigen::JacobiSVD<Mat3>(A).singularValues();
    const int rank = static_cast<int>((sigma.array() > std::max(1e-12 * sigma(0), 1e-6)).count());
    const bool reflection = rank == 3 && (A / sigma(0)).determinant() < 0;
    char text[400];
    if (const double turn = rank == 3 && !reflection ? turn_degrees(A) : 0; turn > 179.9) {
      std::snprintf(
          text, sizeof text,
          "%s%s%zu is a half turn (%.6g degrees): which way round the handle turns is not defined, so "
          "methods that blend or iterate rotations (propagate, gradient, arap, primo, and multi-scale "
          "over them) may turn the region either way; give less than 180 degrees",
          who.c_str(), kHandleTransformWarning, k, turn);
      warnings.emplace_back(text);
    }
    if (rank == 3 && !reflection) continue;
    const char* what = reflection  ? "a reflection: it turns the handle inside out"
                       : rank == 2 ? "singular: it flattens the handle onto a plane"
                       : rank == 1 ? "singular: it collapses the handle onto a line"
                                   : "singular: it collapses the handle to a point";
    if (reflection)  // its singular values may all read 1 to 3 digits (-1.001, 1, 1)
      std::snprintf(text, sizeof text, "%s%s%zu is %s (determinant %.6g)", who.c_str(),
                    kHandleTransformWarning, k, what, A.determinant());
    else  // a near-flat mirror (-1e-7, 1, 1) is also said to mirror
      std::snprintf(text, sizeof text, "%s%s%zu is %s (singular values %.3g, %.3g, %.3g%s)", who.c_str(),
                    kHandleTransformWarning, k, what, sigma(0), sigma(1), sigma(2),
                    A.determinant() < 0 ? "; it also mirrors" : "");
    warnings.emplace_back(text);
  }
}

// A direction whose variance is at most this of a handle's total (a spread below 1e-3 of its size) is one its
// vertices do not spread in; the turn fitted to them is pulled towards none as weakly.
constexpr double kUnspread = 1e-6;

std::vector<HandleSpread> handle_spreads(const Positions& P, const Region& region) {
  const int nh = region.num_handles();
  std::vector<Vec3> centroid(nh, Vec3::Zero());
  std::vector<int> count(nh, 0);
  for (int v = 0; v < region.num_vertices(); ++v)
    if (const int h = region.handle_of(v); h >= 0) centroid[h] += P.row(v).transpose(), ++count[h];
  for (int h = 0; h < nh; ++h) centroid[h] /= std::max(count[h], 1);
  std::vector<HandleSpread> spreads(nh);
  for (int v = 0; v < region.num_vertices(); ++v)
    if (const int h = region.handle_of(v); h >= 0) {
      const Vec3 d = P.row(v).transpose() - centroid[h];
      spreads[h].scatter += d * d.transpose() / count[h];
    }
  const double point = 1e-9 * bounding_box_diagonal(P);
  for (HandleSpread& s : spreads) {
    if (!(s.scatter.trace() > point * point)) s.scatter.setZero();
    const double size = s.scatter.trace();
    const Eigen::SelfAdjointEigenSolver<Mat3> axes(s.scatter);
    s.spread = 0;
    for (int i = 0; i < 3; ++i)
      if (size > 0 && axes.eigenvalues()(i) > kUnspread * size)
        ++s.spread;
      else
        s.unspread += axes.eigenvectors().col(i) * axes.eigenvectors().col(i).transpose();
  }
  return spreads;
}

void handle_span_warnings(const std::vector<Mat4>& transforms, const std::vector<HandleSpread>& spreads,
                          const std::string& who, std::vector<std::string>& warnings) {
  for (size_t k = 0; k < spreads.size() && k < transforms.size(); ++k) {
    const HandleSpread& h = spreads[k];
    if (h.spread == 3) continue;  // its vertices show every part of the transform
    const Mat3 A = transforms[k].topLeftCorner<3, 3>(), &C = h.scatter;
    const Vec3 sigma = Eigen::JacobiSVD<Mat3>(A).singularValues();
    // Mirrors, flattening and half turns: handle_transform_warnings says what they do.
    if (!(A.determinant() > 0) || !(sigma(2) > 1e-6 * sigma(0)) || turn_degrees(A) > 179.9) continue;
    const double size = C.trace();  // the mean squared distance of the vertices from their centroid
    // The turn the moved vertices show (Procrustes), the least one where they leave it open.
    Mat3 R = Mat3::Identity();
    if (size > 0) {
      const Eigen::JacobiSVD<Mat3> fit(A * C + kUnspread * size * Mat3::Identity(),
                                       Eigen::ComputeFullU | Eigen::ComputeFullV);
      Mat3 D = Mat3::Identity();
      D(2, 2) = (fit.matrixU() * fit.matrixV().transpose()).determinant() < 0 ? -1 : 1;
      R = fit.matrixU() * D * fit.matrixV().transpose();
    }
    // What the transform does beyond that turn in those directions: placing methods leave it out.
    const Mat3 L = (A - R) * h.unspread;
    const double change = Eigen::JacobiSVD<Mat3>(L).singularValues()(0);  // per unit length
    if (!(change > 0.02)) continue;
    const char* where = h.spread == 0   ? "they all lie at one point"
                        : h.spread == 1 ? "they lie on a line"
                                        : "they lie in a plane";
    // A turn where R^T A is one (equal singular values), else a scale or shear.
    const Mat3 left_out = R.transpose() * A;
    const Vec3 stretch = Eigen::JacobiSVD<Mat3>(left_out).singularValues();
    const double turn = stretch(0) < 1.02 * stretch(2) ? turn_degrees(left_out) : 0;
    char what[200];
    if (turn > 1)
      std::snprintf(what, sizeof what, "a turn of %.3g degrees", turn);
    else
      std::snprintf(what, sizeof what, "a scale or shear (lengths change by up to %.3g %%)", 100 * change);
    char text[800];
    std::snprintf(
        text, sizeof text,
        "%s%s%zu changes it where its vertices do not spread (%s): %s that moves none of them. "
        "Methods that place vertices (shell, arap, primo, laplacian, multi-scale over them, the space "
        "methods) leave that part out, methods that blend transforms (gradient, propagate) apply it to "
        "the free region; select a handle whose vertices spread around that point, line or plane",
        who.c_str(), kHandleTransformWarning, k, where, what);
    warnings.emplace_back(text);
  }
}

void affine_targets(const Positions& rest, const std::vector<int>& constrained, const std::vector<int>& handle_of,
                    const std::vector<Mat4>& transforms, Positions& targets) {
  if (targets.rows() != static_cast<Eigen::Index>(constrained.size())) targets.resize(constrained.size(), 3);
  for (size_t c = 0; c < constrained.size(); ++c) {
    const Vec3 p = rest.row(constrained[c]);
    targets.row(c) = handle_of[c] < 0 ? p : transform_point(transforms[handle_of[c]], p);
  }
}

namespace {

// Warnings where triangles the cotan Laplacian cannot weigh as they are (core/laplacian.h) cut the surface:
// - zero-area triangles, which it leaves out: parts joined only through them move as separate pieces under
//   the methods built on it (a strip of 40 collapsed triangles across a grid: one side stayed at rest while
//   the other followed the handle, exit 0);
// - needles with a free vertex (a corner's cotangent above LaplaceOperator::kMaxCotangent), whose weights
//   it clamps, so that the vertices there are tied to their neighbours by weights that do not match the
//   geometry. Where they cut the surface into pieces joined only through them (and zero-area ones), or are
//   clamped a thousandfold (a cotangent above 1e8), the pieces may be left behind (a one-ring squashed onto
//   a line with its centre 1e-8 off it: the shell left the centre 0.16 behind its neighbours; a one-ring
//   shrunk to 1e-12: explicit Laplacian editing left it at rest; both exit 0). Elsewhere the result near
//   them may be distorted (a crack of 40 needles with cotangents of 2.5e6: implicit Laplacian editing lifted
//   its rim 23 % above the handle), or may not (3 of CGAL's 138 meshes have a few needles, triceratops 2
//   with cotangents up to 3e5: sound results): said more mildly.
void degenerate_triangle_warnings(const Positions& P, const Faces& F, const Region& region,
                                  const std::string& who, std::vector<std::string>& warnings) {
  const int nv = static_cast<int>(P.rows());
  Faces with_area(F.rows(), 3), well_shaped(F.rows(), 3);  // no zero-area faces; no needles either
  Eigen::Index rows = 0, shaped = 0;
  long degenerate = 0, first = -1, needles = 0, first_needle = -1;
  double sharpest = 0;  // the largest |cotangent| of the needles
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const TriangleCotangents t = triangle_cotangents(P.row(F(f, 0)), P.row(F(f, 1)), P.row(F(f, 2)));
    if (t.degenerate) {
      if (degenerate++ == 0) first = f;
      continue;
    }
    with_area.row(rows++) = F.row(f);
    if (t.needle_corners > 0 &&
        (region.code(F(f, 0)) == Region::kFree || region.code(F(f, 1)) == Region::kFree ||
         region.code(F(f, 2)) == Region::kFree)) {
      if (needles++ == 0) first_needle = f;
      sharpest = std::max({sharpest, std::abs(t.cot[0]), std::abs(t.cot[1]), std::abs(t.cot[2])});
    } else {
      well_shaped.row(shaped++) = F.row(f);
    }
  }
  if (degenerate == 0 && needles == 0) return;
  // Pieces: components of the faces kept, and vertices that had faces and lost them all.
  const auto pieces = [nv](const Faces& kept, const std::vector<int>* had) {
    const std::vector<int> component = vertex_components(kept, nv);
    int count = component.empty() ? 0 : 1 + *std::max_element(component.begin(), component.end());
    if (had)
      for (int v = 0; v < nv; ++v) count += component[v] < 0 && (*had)[v] >= 0;
    return count;
  };
  with_area.conservativeResize(rows, 3);
  well_shaped.conservativeResize(shaped, 3);
  const int whole = pieces(F, nullptr), cut = pieces(with_area, nullptr);
  if (cut > whole)
    warnings.push_back(
        who + ": " + std::to_string(degenerate) + " zero-area triangle(s) (the first is face " +
        std::to_string(first) + ") " + kZeroAreaCutWarning + " " + std::to_string(cut) +
        " pieces joined only through them; methods built on the cotangent Laplacian leave such "
        "triangles out and move the pieces apart: repair the mesh there");
  if (needles == 0) return;
  const std::vector<int> had = vertex_components(with_area, nv);
  const int cut_more = pieces(well_shaped, &had);
  const bool severe = cut_more > cut || sharpest > 1e3 * LaplaceOperator::kMaxCotangent;
  char clamped[96];
  std::snprintf(clamped, sizeof clamped, " (cotangents up to %.3g, clamped to %.3g)", sharpest,
                LaplaceOperator::kMaxCotangent);
  warnings.push_back(
      who + ": " + std::to_string(needles) + " needle triangle(s) at free vertices (the first is face " +
      std::to_string(first_needle) + ", vertices " + std::to_string(F(first_needle, 0)) + ", " +
      std::to_string(F(first_needle, 1)) + ", " + std::to_string(F(first_needle, 2)) + ")" +
      (cut_more > cut ? " join " + std::to_string(cut_more) + " pieces only through them and" : "") + " " +
      kNeedleWarning + clamped +
      (severe ? ": methods built on it may leave the vertices there behind their neighbours; repair the mesh "
                "there"
              : ": the result may be distorted next to them (most with implicit Laplacian editing); repair "
                "the mesh there if it is"));
}

}  // namespace

void Deformer::prepare(const Positions& P, const Faces& F, const Region& region) {
  prepared_ = false;
  prepare_failed_ = true;  // until do_prepare() returns
  num_handles_ = num_vertices_ = num_constrained_ = 0;
  frame_report_ = {};
  prepare_warnings_.clear();
  const bool surface = traits().domain == DeformerDomain::Surface;
  check_mesh_arrays(P, F, name().c_str());
  // Finite coordinates can still overflow (or underflow) the squared areas computed from them at sizes
  // around 1e±150; say so rather than let a solver blame degenerate triangles.
  check_extent(P, name());
  if (std::string outliers = extent_outlier_warning(P, F, name()); !outliers.empty())
    prepare_warnings_.push_back(std::move(outliers));
  if (surface && F.rows() == 0)
    throw InvalidInput(name() + ": a surface method needs triangles, and the input has none");
  if (surface) {
    // What load_mesh refuses, refused here too for arrays that did not come through it (0.4 s at 1M faces).
    Faces oriented = F;
    const SurfaceCheck check = check_surface(P, oriented);
    if (const std::string problem = check.problem(); !problem.empty())
      throw TopologyError(name() + ": " + problem + "; a surface method needs a manifold, orientable triangle mesh");
    if (check.flipped_faces > 0)
      prepare_warnings_.push_back(
          name() + ": " + std::to_string(check.flipped_faces) +
          " face(s) wound against their neighbours (normals and detail directions flip "
          "there); orient them first (loading the mesh with load_mesh does)");
  }
  if (surface && traits().cotan_laplacian) {
    // These methods leave degenerate triangles out: a fixed part or handle touching only those holds or
    // moves nothing (second break test: a fixed vertex whose one face had zero area let the surface
    // translate).
    std::vector<char> usable(F.rows());
    parallel_for_chunks(static_cast<long>(F.rows()), [&](long begin, long end) {
      for (long f = begin; f < end; ++f)
        usable[f] = !triangle_cotangents(P.row(F(f, 0)), P.row(F(f, 1)), P.row(F(f, 2))).degenerate;
    });
    region.validate(static_cast<int>(P.rows()), &F, &usable);
  } else {
    region.validate(static_cast<int>(P.rows()), surface ? &F : nullptr);
  }
  if (region.num_handles() == 0)
    throw InvalidInput(name() + ": the region has no handle vertex (selection code 2 or higher); nothing to move");
  if (std::string torn = torn_edges_warning(F, region, name()); !torn.empty())
    prepare_warnings_.push_back(std::move(torn));
  if (surface && traits().cotan_laplacian)
    degenerate_triangle_warnings(P, F, region, name(), prepare_warnings_);
  try {
    do_prepare(P, F, region);
  } catch (const SolverError& e) {
    // A solver blames the neighbourhood where it broke down (a degenerate one, a singular system); a stray
    // vertex far from the rest is the likelier cause, and its warning would not be seen after the error.
    const auto stray =
        std::find_if(prepare_warnings_.begin(), prepare_warnings_.end(),
                     [](const std::string& w) { return w.find(kOutlierWarning) != std::string::npos; });
    if (stray == prepare_warnings_.end() || std::string(e.what()).find(kOutlierWarning) != std::string::npos)
      throw;
    throw SolverError(std::string(e.what()) + ". Note: " + *stray, e.index());
  }
  prepare_failed_ = false;
  num_handles_ = region.num_handles();
  num_vertices_ = region.num_vertices();
  num_constrained_ = static_cast<int>(region.constrained_vertices().size());
  handle_spreads_ = handle_spreads(P, region);
  prepared_ = true;
}

void Deformer::prepare(const Mesh& mesh, const Region& region) { prepare(positions(mesh), faces(mesh), region); }

void Deformer::begin_frame(Positions& out) {
  if (!prepared_)
    throw UsageError(name() + (prepare_failed_
                                   ? ": the last prepare() failed; a frame needs one that succeeded"
                                   : ": a frame was asked for before prepare()"));
  if (out.rows() != num_vertices_) out.resize(num_vertices_, 3);
  frame_report_.iterations = 0;
  frame_report_.residual = -1;
  frame_report_.converged = true;
  frame_report_.folded_faces = -1;
  frame_report_.constraint_error = -1;
  frame_report_.start = nullptr;
  frame_report_.warnings.clear();
  output_checked_finite_ = false;
}

void Deformer::end_frame(const Positions& out) {
  const long v = output_checked_finite_ ? -1 : first_non_finite_row(out);
  if (v >= 0)
    throw SolverError(name() + ": the frame gave vertex " + std::to_string(v) + " a non-finite position",
                      static_cast<int>(v));
  if (!frame_report_.converged)
    frame_report_.warnings.push_back(
        name() + kNotConvergedWarning + std::to_string(frame_report_.iterations) +
        " iterations with relative residual " + format_number(frame_report_.residual) +
        "; raise its iteration limit, or loosen its tolerance");
}

void Deformer::deform(const std::vector<Mat4>& transforms, Positions& out) {
  if (prepared_ && static_cast<int>(transforms.size()) != num_handles_)
    throw UsageError(name() + ": " + std::to_string(transforms.size()) + " handle transforms given, the region has " +
                     std::to_string(num_handles_) + " handle(s)");
  begin_frame(out);
  check_affine(transforms, name());
  do_deform(transforms, out);
  handle_transform_warnings(transforms, name(), frame_report_.warnings);
  handle_span_warnings(transforms, handle_spreads_, name(), frame_report_.warnings);
  end_frame(out);
}

Positions Deformer::deform(const std::vector<Mat4>& transforms) {
  Positions out;
  deform(transforms, out);
  return out;
}

void Deformer::deform_to(const Positions& targets, Positions& out) {
  if (!traits().vertex_targets)
    throw UsageError(name() + " takes one affine transform per handle, not per-vertex targets (traits().vertex_targets "
                              "is false); use deform()");
  if (prepared_ && targets.rows() != num_constrained_)
    throw UsageError(name() + ": " + std::to_string(targets.rows()) + " targets given for " +
                     std::to_string(num_constrained_) + " constrained (fixed and handle) vertices");
  begin_frame(out);
  check_finite(targets, name().c_str(), "the targets");
  if (targets.size() > 0 && !(targets.cwiseAbs().maxCoeff() < kMaxExtent)) {  // as deform()'s transforms
    Eigen::Index row = 0, col = 0;
    targets.cwiseAbs().maxCoeff(&row, &col);
    throw InvalidInput(name() + ": target " + std::to_string(row) + " has a coordinate of " +
                       format_number(targets(row, col)) + "; msdeform works with sizes up to 1e70");
  }
  do_deform_to(targets, out);
  end_frame(out);
}

void Deformer::do_deform_to(const Positions&, Positions&) {
  throw UsageError(name() + ": declares vertex targets but does not implement them");
}

void Deformer::set_initial_guess(const Positions& X) {
  if (!traits().initial_guess)
    throw UsageError(name() + " takes no initial guess (traits().initial_guess is false): " +
                     (traits().solve == DeformerSolve::Linear ? "a linear frame does not depend on one"
                                                              : "it warm-starts from the last frame; reset() restarts it"));
  if (!prepared_) throw UsageError(name() + ": set_initial_guess() called before prepare()");
  if (X.rows() != num_vertices_)
    throw UsageError(name() + ": the initial guess has " + std::to_string(X.rows()) + " rows for " +
                     std::to_string(num_vertices_) + " vertices");
  check_finite(X, name().c_str(), "the initial guess");
  do_set_initial_guess(X);
}

void Deformer::do_set_initial_guess(const Positions&) {
  throw UsageError(name() + ": declares an initial guess but does not implement it");
}

void Deformer::reset() {
  frame_report_ = {};
  if (prepared_) do_reset();
}

void Deformer::evaluate(const Positions& points, Positions& out) const {
  if (traits().domain != DeformerDomain::Space)
    throw UsageError(name() + " is a surface method: it moves the mesh's own vertices and has no map of space to "
                              "evaluate at other points");
  if (!prepared_) throw UsageError(name() + ": evaluate() called before prepare()");
  check_finite(points, name().c_str(), "the points");
  if (out.rows() != points.rows()) out.resize(points.rows(), 3);
  do_evaluate(points, out);
  if (const long i = first_non_finite_row(out); i >= 0)  // e.g. a polynomial map overflowed far away
    throw SolverError(name() + ": the map sends point " + std::to_string(i) + " (" +
                      format_number(points(i, 0)) + ", " + format_number(points(i, 1)) + ", " +
                      format_number(points(i, 2)) +
                      ") to a non-finite position; it lies too far from the handles for this method");
}

void Deformer::do_evaluate(const Positions&, Positions&) const {
  throw UsageError(name() + ": declares itself a space method but cannot evaluate its map");
}

void LocalFrameDeformer::do_prepare(const Positions& P, const Faces& F, const Region& region) {
  local_ = LocalFrame::of(P);
  prepare_local(local_.to_local(P), F, region);
  rest_ = P;
  constrained_ = region.constrained_vertices();
  handle_of_.resize(constrained_.size());
  for (size_t c = 0; c < constrained_.size(); ++c) handle_of_[c] = region.handle_of(constrained_[c]);
  targets_.resize(static_cast<Eigen::Index>(constrained_.size()), 3);
}

void LocalFrameDeformer::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  local_.to_local(transforms, local_transforms_);
  deform_local(local_transforms_, out);
  local_.to_world(out);
  affine_targets(rest_, constrained_, handle_of_, transforms, targets_);
  for (size_t c = 0; c < constrained_.size(); ++c) out.row(constrained_[c]) = targets_.row(static_cast<Eigen::Index>(c));
}

void LocalFrameDeformer::do_set_initial_guess(const Positions& X) { set_initial_guess_local(local_.to_local(X)); }

}  // namespace msd
