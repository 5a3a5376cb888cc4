#include "msdeform/analysis/metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/rotation.h"
#include "msdeform/decomposition/detail_check.h"
#include "msdeform/detail/normal_displacements.h"

namespace msd {
namespace {

void require_same_rows(const Positions& A, const Positions& B, const char* who, const char* a_name,
                       const char* b_name) {
  if (A.rows() != B.rows())
    throw InvalidInput(std::string(who) + ": " + a_name + " has " + std::to_string(A.rows()) +
                       " vertices but " + b_name + " has " + std::to_string(B.rows()));
}

// Local ARAP step for one vertex: the residual of the best rotation and the normaliser Σ w |e|².
// for_each(visit) calls visit(j, w_ij) for every weighted neighbour j of i.
template <class ForEachNeighbour>
double one_ring_residual(const Positions& rest, const Positions& deformed, int i, ForEachNeighbour&& for_each,
                         double& normaliser) {
  Mat3 covariance = Mat3::Zero();
  normaliser = 0;
  const Vec3 p = rest.row(i).transpose(), q = deformed.row(i).transpose();
  for_each([&](int j, double w) {
    const Vec3 e = p - rest.row(j).transpose(), e1 = q - deformed.row(j).transpose();
    covariance += w * e * e1.transpose();
    normaliser += w * e.squaredNorm();
  });
  if (!(normaliser > 0)) return 0;
  const Mat3 R = best_rotation(covariance);  // Kabsch; a rotation, never a reflection
  double residual = 0;
  for_each([&](int j, double w) {
    const Vec3 e = p - rest.row(j).transpose(), e1 = q - deformed.row(j).transpose();
    residual += w * (e1 - R * e).squaredNorm();
  });
  return residual;
}

}  // namespace

Stats summarize(const Eigen::VectorXd& values) {
  std::vector<int> all(values.size());
  for (Eigen::Index i = 0; i < values.size(); ++i) all[i] = static_cast<int>(i);
  return summarize(values, all);
}

Stats summarize(const Eigen::VectorXd& values, const std::vector<int>& subset) {
  Stats s;
  if (subset.empty()) return s;
  std::vector<double> v;
  v.reserve(subset.size());
  for (int i : subset) {
    if (i < 0 || i >= values.size())
      throw InvalidInput("summarize: index " + std::to_string(i) + " is outside the " +
                         std::to_string(values.size()) + " values");
    v.push_back(values[i]);
  }
  double sum = 0;
  for (double x : v) sum += x;
  s.count = static_cast<int>(v.size());
  s.mean = sum / s.count;
  s.max = *std::max_element(v.begin(), v.end());
  // Nearest rank: the smallest value with at least 95% of the values at or below it.
  const size_t rank = static_cast<size_t>(std::ceil(0.95 * static_cast<double>(v.size())));
  const size_t k = std::clamp<size_t>(rank, 1, v.size()) - 1;
  std::nth_element(v.begin(), v.begin() + k, v.end());
  s.p95 = v[k];
  return s;
}

double handle_error(const Positions& rest, const Positions& deformed, const Region& region,
                    const std::vector<Mat4>& transforms) {
  const char* who = "handle_error";
  require_same_rows(rest, deformed, who, "rest", "deformed");
  if (region.num_vertices() != rest.rows())
    throw InvalidInput(std::string(who) + ": region has " + std::to_string(region.num_vertices()) +
                       " vertices but the mesh has " + std::to_string(rest.rows()));
  if (static_cast<int>(transforms.size()) < region.num_handles())
    throw InvalidInput(std::string(who) + ": region has " + std::to_string(region.num_handles()) +
                       " handles but only " + std::to_string(transforms.size()) + " transforms were given");
  double error = 0;
  for (int v = 0; v < region.num_vertices(); ++v) {
    const Vec3 p = rest.row(v).transpose();
    const int h = region.handle_of(v);
    Vec3 target;
    if (h >= 0)
      target = transform_point(transforms[h], p);
    else if (region.is_fixed(v))
      target = p;
    else
      continue;
    error = std::max(error, (deformed.row(v).transpose() - target).norm());
  }
  return error;
}

RigidityMetric::RigidityMetric(const Positions& rest, const Faces& F, const RigidityOptions& options)
    : rest_(rest), options_(options) {
  check_mesh_arrays(rest, F, "rigidity_error");
  const int nv = static_cast<int>(rest.rows());
  rings_ = vertex_adjacency(F, nv);
  if (options.weights == RigidityWeights::Cotan) weights_ = cotan_laplacian(rest, F).W;
  for (int v = 0; v < nv; ++v)
    if (rings_.degree(v) > 0) connected_.push_back(v);
}

RigidityError RigidityMetric::measure(const Positions& deformed) const {
  const char* who = "rigidity_error";
  require_same_rows(rest_, deformed, who, "rest", "deformed");
  check_finite(deformed, who, "deformed");
  const int nv = static_cast<int>(rest_.rows());
  const bool cotan_weights = options_.weights == RigidityWeights::Cotan;

  RigidityError out;
  out.per_vertex = Eigen::VectorXd::Zero(nv);
  parallel_for_chunks(
      nv,
      [&](long begin, long end) {
        for (long v = begin; v < end; ++v) {
          const int i = static_cast<int>(v);
          auto uniform = [&](auto&& visit) {
            for (const int* j = rings_.begin(i); j != rings_.end(i); ++j) visit(*j, 1.0);
          };
          double normaliser = 0, residual = 0;
          if (cotan_weights) {
            // W is symmetric, so column i lists the weights W_ji = W_ij of i's edges.
            auto cotan = [&](auto&& visit) {
              for (SparseMatrix::InnerIterator it(weights_, i); it; ++it)
                if (it.row() != i && it.value() > 0) visit(static_cast<int>(it.row()), it.value());
            };
            residual = one_ring_residual(rest_, deformed, i, cotan, normaliser);
          }
          if (!(normaliser > 0)) residual = one_ring_residual(rest_, deformed, i, uniform, normaliser);
          out.per_vertex[i] = normaliser > 0 ? residual / normaliser : 0.0;
        }
      },
      1024);
  out.stats = summarize(out.per_vertex, connected_);
  return out;
}

RigidityError rigidity_error(const Positions& rest, const Positions& deformed, const Faces& F,
                             const RigidityOptions& options) {
  require_same_rows(rest, deformed, "rigidity_error", "rest", "deformed");
  return RigidityMetric(rest, F, options).measure(deformed);
}

namespace {
// P moved so its bounding box is centred at the origin: heights do not depend on where a surface sits, but
// a fairing solved in absolute coordinates far out did (the lift's detail change read 3 % at the origin,
// 12 % at 1e10 and 22 % at 1e11).
Positions centred(const Positions& P) { return P.rowwise() - bounding_box_centre(P).transpose(); }
}  // namespace

DetailDistortionMetric::DetailDistortionMetric(const Positions& rest, const Faces& F, const Region& region,
                                               const FairingOptions& fairing)
    : F_(F), region_(region), fairing_(fairing) {
  const char* who = "detail_distortion";
  if (region.num_vertices() != rest.rows())
    throw InvalidInput(std::string(who) + ": region has " + std::to_string(region.num_vertices()) +
                       " vertices but the mesh has " + std::to_string(rest.rows()));
  if (F.rows() == 0)  // (fifth break test: the fairing underneath blamed the region)
    throw InvalidInput(std::string(who) + ": there are no faces; the details are measured over the surface");
  free_ = region.free_vertices();
  if (free_.empty())
    throw InvalidInput(std::string(who) + ": the region has no free vertex to measure details on");
  // (Fourth break test: said by the fairing underneath, in its own words.)
  if (free_.size() == static_cast<size_t>(region.num_vertices()))
    throw InvalidInput(std::string(who) + ": the region has no fixed or handle vertex (all " +
                       std::to_string(free_.size()) +
                       " are free); the details are measured over the free region faired between those");
  // Its fairing works within msdeform's sizes (at 1e100 it failed: "no incident face of non-zero area").
  const Positions R = centred(rest);
  check_extent(R, who);

  const Positions B0 = fair_region(R, F, region, fairing);
  // A free region that fairing shrinks to a membrane (a tube bent or twisted over most of its length: the
  // survey's cylinder, bar and cactus) has no details over that base, only its shape; the heights would
  // then jump between base points under rounding (measured on the survey cactus: 191 vertices changed by
  // up to 0.24 between two results 2e-16 apart).
  if (const double kept = free_area_ratio(R, B0, F, region); kept < kMinBaseAreaRatio) {
    char text[300];
    std::snprintf(
        text, sizeof text,
        "%s: the free region faired loses the shape (its area over the triangles with a free vertex is "
        "%.3g of the input's), so heights over it would measure the shape, not the details",
        who, kept);
    throw InvalidInput(text);
  }
  NormalDisplacements before;
  before.encode(R, F, B0, F);
  rest_heights_ = before.heights();
  rest_fallback_ = before.report().fallback;
  double max_height = 0;
  for (int v : free_) max_height = std::max(max_height, std::abs(rest_heights_[v]));
  const double diagonal = bounding_box_diagonal(rest);
  scale_ = max_height > 1e-12 * diagonal ? max_height : diagonal;
  if (!(scale_ > 0)) throw InvalidInput(std::string(who) + ": the rest mesh has zero extent");
}

DetailDistortion DetailDistortionMetric::measure(const Positions& deformed) const {
  if (deformed.rows() != rest_heights_.size())
    throw InvalidInput("detail_distortion: rest has " + std::to_string(rest_heights_.size()) +
                       " vertices but deformed has " + std::to_string(deformed.rows()));
  const Positions D = centred(deformed);
  check_extent(D, "detail_distortion: the deformed surface");  // a collapse or a blow-up, named as such
  const Positions B1 = fair_region(D, F_, region_, fairing_);
  NormalDisplacements after;
  after.encode(D, F_, B1, F_);

  DetailDistortion out;
  out.rest_heights = rest_heights_;
  out.deformed_heights = after.heights();
  out.fallback_vertices = rest_fallback_ + after.report().fallback;
  out.per_vertex = Eigen::VectorXd::Zero(deformed.rows());
  for (int v : free_) out.per_vertex[v] = std::abs(out.deformed_heights[v] - out.rest_heights[v]);
  out.scale = scale_;
  out.stats = summarize(out.per_vertex / out.scale, free_);
  return out;
}

DetailDistortion detail_distortion(const Positions& rest, const Positions& deformed, const Faces& F,
                                   const Region& region, const FairingOptions& fairing) {
  require_same_rows(rest, deformed, "detail_distortion", "rest", "deformed");
  return DetailDistortionMetric(rest, F, region, fairing).measure(deformed);
}

bool is_closed(const Faces& F, int num_vertices) {
  if (F.rows() == 0) return false;
  std::vector<std::pair<int, int>> forward, backward;
  forward.reserve(3 * F.rows());
  backward.reserve(3 * F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      if (a < 0 || a >= num_vertices)
        throw InvalidInput("is_closed: face " + std::to_string(f) + " has vertex index " + std::to_string(a) +
                           " outside [0, " + std::to_string(num_vertices) + ")");
      forward.emplace_back(a, b);
      backward.emplace_back(b, a);
    }
  std::sort(forward.begin(), forward.end());
  std::sort(backward.begin(), backward.end());
  return forward == backward;
}

std::optional<double> volume(const Positions& P, const Faces& F) {
  check_mesh_arrays(P, F, "volume");
  if (!is_closed(F, static_cast<int>(P.rows()))) return std::nullopt;
  return signed_volume(P, F);
}

// Volumes in units of the rest's largest bounding-box side: a ratio of volumes holds at any size, where the
// cubes of coordinates beyond 1e±103 overflowed (NaN) or underflowed (a closed mesh read "not closed").
namespace {
double volume_unit(const Positions& rest) {
  if (rest.rows() == 0) return 1;
  const double d = (rest.colwise().maxCoeff() - rest.colwise().minCoeff()).maxCoeff();  // no squares
  return d > 0 && std::isfinite(d) ? d : 1;
}
}  // namespace

VolumeChangeMetric::VolumeChangeMetric(const Positions& rest, const Faces& F)
    : F_(F), num_vertices_(rest.rows()), unit_(volume_unit(rest)), rest_volume_(volume(rest, F)) {
  if (rest_volume_) unit_rest_volume_ = signed_volume(rest / unit_, F);
}

std::optional<double> VolumeChangeMetric::measure(const Positions& deformed) const {
  if (deformed.rows() != num_vertices_)
    throw InvalidInput("volume_change: rest has " + std::to_string(num_vertices_) + " vertices but deformed has " +
                       std::to_string(deformed.rows()));
  if (!rest_volume_ || unit_rest_volume_ == 0) return std::nullopt;
  check_mesh_arrays(deformed, F_, "volume");  // closed like the rest shape: same faces
  // The deformed volume in its own unit, then the ratio of units cubed: a result 1e103 times the rest's size
  // gave inf − inf = NaN in the rest's unit (now inf, as the ratio is).
  const double unit = volume_unit(deformed), units = unit / unit_;
  const double v = signed_volume(deformed / unit, F_);
  return v == 0 ? -1.0 : v / unit_rest_volume_ * units * units * units - 1.0;
}

std::optional<double> volume_change(const Positions& rest, const Positions& deformed, const Faces& F) {
  require_same_rows(rest, deformed, "volume_change", "rest", "deformed");
  return VolumeChangeMetric(rest, F).measure(deformed);
}

EditMetrics::EditMetrics(const Positions& rest, const Faces& F, const Region& region,
                         const EditMetricsOptions& options)
    : region_(region),
      rigidity_(rest, F, options.rigidity),
      distortion_(rest, F, region, options.fairing),
      volume_(rest, F) {}

double EditMetrics::handle_error(const Positions& deformed, const std::vector<Mat4>& transforms) const {
  return msd::handle_error(rest(), deformed, region_, transforms);
}

EditMeasurement EditMetrics::measure(const Positions& deformed, const std::vector<Mat4>& transforms) const {
  EditMeasurement m;
  m.handle_error = handle_error(deformed, transforms);
  m.rigidity = rigidity(deformed);
  m.distortion = detail_distortion(deformed);
  m.volume_change = volume_change(deformed);
  return m;
}

ReferenceDistance distance_to_reference(const Positions& P, const Faces& F, const Positions& Q,
                                        const Faces& FQ) {
  const char* who = "distance_to_reference";
  require_same_rows(P, Q, who, "the result", "the reference");
  if (F.rows() != FQ.rows())
    throw InvalidInput(std::string(who) + ": the result has " + std::to_string(F.rows()) +
                       " faces but the reference has " + std::to_string(FQ.rows()) +
                       "; both must share one connectivity");
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    if (F.row(f) != FQ.row(f))
      throw InvalidInput(std::string(who) + ": face " + std::to_string(f) +
                         " differs between the result and the reference; both must share one connectivity");
  check_finite(P, who, "the result");
  check_finite(Q, who, "the reference");
  ReferenceDistance out;
  out.diagonal = bounding_box_diagonal(Q);
  if (!(out.diagonal > 0))
    throw InvalidInput(std::string(who) + ": the reference has a zero bounding-box diagonal");
  if (P.rows() == 0) return out;
  const Eigen::VectorXd d = (P - Q).rowwise().norm();
  out.max = d.maxCoeff() / out.diagonal;
  out.mean = d.mean() / out.diagonal;
  return out;
}

ShapeChange shape_change(const Positions& rest, const Positions& deformed, const Faces& F, const Region& region) {
  const char* who = "shape_change";
  if (deformed.rows() != rest.rows() || region.num_vertices() != rest.rows())
    throw InvalidInput(std::string(who) + ": rest, deformed and region differ in their vertex counts");
  check_mesh_arrays(rest, F, who);
  ShapeChange c;
  long stretched = 0;
  const double shortest = 1e-6 * bounding_box_diagonal(rest);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    // Each edge with a free vertex or between vertices placed by different transforms (fixed and a
    // handle, two handles: torn apart by the edit), seen from its triangles: an interior edge is seen twice,
    // which weights the share alike for every edge and leaves the largest factor unchanged.
    for (int k = 0; k < 3; ++k) {
      const int i = F(f, k), j = F(f, (k + 1) % 3);
      if (region.placed_together(i, j)) continue;
      const double l = (rest.row(i) - rest.row(j)).norm(), l1 = (deformed.row(i) - deformed.row(j)).norm();
      if (!(l > shortest)) continue;
      const double growth = l1 / l, shrink = l1 > 0 ? l / l1 : INFINITY, factor = std::max(growth, shrink);
      ++c.edges;
      stretched += factor > 1.5;
      // Named by its free vertex, else by its handle vertex.
      const int named = region.code(i) == Region::kFree || region.code(j) == Region::kFixed ? i : j;
      if (factor > c.largest_factor) c.largest_factor = factor, c.largest_vertex = named;
      if (growth > c.largest_growth) c.largest_growth = growth, c.growth_vertex = named;
      if (shrink > c.largest_shrink) c.largest_shrink = shrink, c.shrink_vertex = named;
    }
  }
  if (c.edges > 0) {
    c.stretched_share = static_cast<double>(stretched) / static_cast<double>(c.edges);
    c.area_ratio = free_area_ratio(rest, deformed, F, region);
  }
  if (F.rows() > 0) c.volume_change = volume_change(rest, deformed, F);
  return c;
}

EditScaling edit_scaling(const std::vector<Mat4>& transforms) {
  EditScaling e;
  for (const Mat4& T : transforms) {
    const Mat3 A = T.topLeftCorner<3, 3>();
    const Vec3 sigma = Eigen::JacobiSVD<Mat3>(A).singularValues();  // descending
    e.growth = std::max(e.growth, sigma(0));
    e.shrink = std::max(e.shrink, sigma(2) > 0 ? 1 / sigma(2) : INFINITY);
    e.area_low = std::min(e.area_low, sigma(1) * sigma(2));
    e.area_high = std::max(e.area_high, sigma(0) * sigma(1));
    const double det = A.determinant();
    e.volume_low = std::min(e.volume_low, std::abs(det));
    e.volume_high = std::max(e.volume_high, std::abs(det));
    e.mirrors = e.mirrors || det < 0;
  }
  return e;
}

double EditScaling::volume_excess(double ratio) const {
  if (ratio > volume_high) return ratio / volume_high - 1;
  if (ratio < volume_low) return 1 - ratio / volume_low;
  return 0;
}

std::string shape_change_warning(const ShapeChange& c, const EditScaling& asked) {
  std::string why;
  auto add = [&](const std::string& text) { why += (why.empty() ? "" : ", ") + text; };
  // " (the handles ask for xLOW to xHIGH)" where they scale visibly.
  auto range = [](double low, double high) {
    char text[96];
    std::snprintf(text, sizeof text, " (the handles ask for x%.4g to x%.4g)", low, high);
    return std::string(text) == " (the handles ask for x1 to x1)" ? std::string() : std::string(text);
  };
  char text[160];
  if (c.largest_growth > 5 * asked.growth) {
    std::snprintf(text, sizeof text, "an edge at vertex %d stretched %.3g times", c.growth_vertex,
                  c.largest_growth);
    add(text);
  }
  if (c.largest_shrink > 5 * asked.shrink) {
    std::snprintf(text, sizeof text, "an edge at vertex %d shrank %.3g times", c.shrink_vertex,
                  c.largest_shrink);
    add(text);
  }
  if (c.area_ratio > 1.5 * asked.area_high || c.area_ratio < 2.0 / 3 * asked.area_low) {
    std::snprintf(text, sizeof text, "the free region's area changed x%.3g", c.area_ratio);
    add(text + range(asked.area_low, asked.area_high));
  }
  if (c.volume_change && !asked.mirrors && asked.volume_excess(1 + *c.volume_change) > 0.3) {
    std::snprintf(text, sizeof text, "the volume changed by %+.3g %%", 100 * *c.volume_change);
    add(text + range(asked.volume_low, asked.volume_high));
  }
  if (why.empty()) return why;
  return "the result does not keep the shape's proportions: " + why +
         " (linear methods shrink or balloon under large rotations, space methods pinch or amplify between "
         "handles close together)";
}

}  // namespace msd
