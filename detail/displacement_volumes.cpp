#include "msdeform/detail/displacement_volumes.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>

#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/detail/phong.h"

namespace msd {
namespace {

// The sizes (bounding-box diagonals) the encoding takes: its volumes and their squares stay in range.
constexpr double kMinSize = 1e-50, kMaxSize = 1e50;
// A base triangle below this fraction of the mean S-triangle area makes a degenerate prism.
constexpr double kDegenerateBaseArea = 1e-10;
// Weights of a corner's kite in the blended prism: V_t,i = m · (22 d_i + 7 d_j + 7 d_k) / 216.
constexpr double kOwnWeight = 22.0 / 216, kOtherWeight = 7.0 / 216;
// Levenberg damping of the per-vertex Gauss–Newton step, relative to ∂W_i/∂h_i on a flat base.
constexpr double kDamping = 0.1;
// Floor of the volume window of max_volume_change, relative to the vertex's volume scale (for cells
// whose normal-displacement volume is about 0).
constexpr double kVolumeFloor = 1e-3;
// Diagonal dominance γ that the adaptive regulariser keeps every row at (see sweep()).
constexpr double kDominance = 1.2;
// Spectral radius of the l1-Jacobi iteration at ω = 1.4 on a flat base (max |1 − 1.4 λ|, λ ∈ [15/36, 1]).
constexpr double kChebyshevRadius = 0.42;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Index in DisplacementVolumes::corner_ of the volume of corner 3t + l (derivative +3, coupling +6).
inline long corner_slot(int corner) { return 9L * (corner / 3) + corner % 3; }

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Kite volumes V_t,k (k = 0, 1, 2) of the blended prism with bottom b_k and top b_k + h_k n_k and, with
// kDerivatives, their derivatives ∂V_t,k/∂h_k and couplings Σ_{l≠k} |∂V_t,k/∂h_l|. With d_k = h_k n_k,
// S = d_0 + d_1 + d_2, α = 22/216, β = 7/216: V_t,k = m·D_k, D_k = (α − β) d_k + β S, so
//   V_t,k = (α − β) h_k (m·n_k) + β m·S,
//   ∂V_t,k/∂h_l = (α − β) h_k (∂m/∂h_l · n_k) + β ∂m/∂h_l · S + w_kl m·n_l   (w_kk = α, else β),
//   ∂m/∂h_0 = −n_0 × (u − w)/6,  ∂m/∂h_1 = n_1 × u / 6,  ∂m/∂h_2 = w × n_2 / 6,
// u = e2 + 2 f2, w = e1 + 2 f1 (from ∂f1 = n1 dh1 − n0 dh0, ∂f2 = n2 dh2 − n0 dh0); ∂m/∂h_k · n_k = 0.
template <bool kDerivatives>
inline void kite_volumes(const double* x0, const double* x1, const double* x2, const double h[3],
                         double volume[3], double derivative[3], double coupling[3]) {
  constexpr double alpha = kOwnWeight, beta = kOtherWeight;
  const Vec3 b0(x0[0], x0[1], x0[2]), b1(x1[0], x1[1], x1[2]), b2(x2[0], x2[1], x2[2]);
  const Vec3 n[3] = {Vec3(x0[3], x0[4], x0[5]), Vec3(x1[3], x1[4], x1[5]), Vec3(x2[3], x2[4], x2[5])};
  const Vec3 d0 = h[0] * n[0], d1 = h[1] * n[1], d2 = h[2] * n[2];
  const Vec3 e1 = b1 - b0, e2 = b2 - b0;
  const Vec3 f1 = e1 + d1 - d0, f2 = e2 + d2 - d0;
  const Vec3 m = (2 * e1.cross(e2) + e1.cross(f2) + f1.cross(e2) + 2 * f1.cross(f2)) / 6;
  const Vec3 S = d0 + d1 + d2;
  const double mn[3] = {m.dot(n[0]), m.dot(n[1]), m.dot(n[2])};
  const double mS = m.dot(S);
  for (int k = 0; k < 3; ++k) volume[k] = (alpha - beta) * h[k] * mn[k] + beta * mS;
  if constexpr (kDerivatives) {
    const Vec3 u = e2 + 2 * f2, w = e1 + 2 * f1;
    const Vec3 dm[3] = {-n[0].cross(u - w) / 6, n[1].cross(u) / 6, w.cross(n[2]) / 6};
    for (int k = 0; k < 3; ++k) derivative[k] = beta * dm[k].dot(S) + alpha * mn[k];
    for (int k = 0; k < 3; ++k) {
      double sum = 0;
      for (int l = 0; l < 3; ++l)
        if (l != k)
          sum += std::abs((alpha - beta) * h[k] * dm[l].dot(n[k]) + beta * dm[l].dot(S) + beta * mn[l]);
      coupling[k] = sum;
    }
  }
}

}  // namespace

double prism_volume(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& c0, const Vec3& c1,
                    const Vec3& c2) {
  const Vec3 e1 = a1 - a0, e2 = a2 - a0, f1 = c1 - c0, f2 = c2 - c0;
  const Vec3 m = (2 * e1.cross(e2) + e1.cross(f2) + f1.cross(e2) + 2 * f1.cross(f2)) / 6;
  return m.dot((c0 - a0) + (c1 - a1) + (c2 - a2)) / 6;
}

void DisplacementVolumeOptions::validate() const {
  const std::string who = "DisplacementVolumeOptions::";
  const auto refuse = [&](const char* name, const char* range, double value) {
    throw InvalidInput(who + name + " must be " + range + ", got " + format_number(value));
  };
  if (max_iterations < 0) refuse("max_iterations", ">= 0", max_iterations);
  if (!(volume_tolerance >= 0) || !std::isfinite(volume_tolerance))
    refuse("volume_tolerance", "finite and >= 0", volume_tolerance);
  if (!(regularization >= 0) || !std::isfinite(regularization))
    refuse("regularization", "finite and >= 0", regularization);
  if (!(focal_fraction > 0))
    refuse("focal_fraction", "> 0 (infinity disables the fold guard)", focal_fraction);
  if (!(max_height_change > 0)) refuse("max_height_change", "> 0 (infinity disables it)", max_height_change);
  if (!(max_volume_change > 0)) refuse("max_volume_change", "> 0 (infinity disables it)", max_volume_change);
  if (!(relaxation > 0 && relaxation < 2)) refuse("relaxation", "in (0, 2)", relaxation);
}

DisplacementVolumes::DisplacementVolumes(const DisplacementVolumeOptions& options,
                                         const NormalDisplacementOptions& normal_options)
    : options_(options), normal_(normal_options) {
  options_.validate();  // here, not in encode(): a bad value fails before the caller loaded a mesh
}

void DisplacementVolumes::base_frames(const Positions& B) {
  normal_.base_points(B, b_);
  base_normals_.compute(B, vertex_normals_);
  const Eigen::VectorXi& face = normal_.base_faces();
  const Eigen::MatrixX3d& bary = normal_.barycentrics();
  const long ns = static_cast<long>(face.size());
  if (frame_.rows() != ns) frame_.resize(ns, 6);
  parallel_for_chunks(ns, [&](long begin, long end) {
    for (long i = begin; i < end; ++i) {
      const Vec3 n = phong::direction(phong::Columns(B), phong::Columns(vertex_normals_),
                                      &base_faces_(face[i], 0), bary.row(i));
      frame_.row(i) << b_(i, 0), b_(i, 1), b_(i, 2), n.x(), n.y(), n.z();
    }
  });
}

void DisplacementVolumes::bounds() {
  const double kappa = options_.focal_fraction;
  const long ns = static_cast<long>(encoded_height_.size());
  parallel_for_chunks(ns, [&](long begin, long end) {
    for (long i = begin; i < end; ++i) {
      double up = std::numeric_limits<double>::infinity(), down = up;
      if (!std::isinf(kappa)) {
        const Vec3 bi = frame_.row(i).head<3>(), ni = frame_.row(i).tail<3>();
        for (int c = incidence_offsets_[i]; c < incidence_offsets_[i + 1]; ++c) {
          const int t = incidence_corners_[c] / 3, l = incidence_corners_[c] % 3;
          for (int k = 0; k < 3; ++k) {
            const int j = faces_(t, k);
            if (k == l || j == i) continue;
            const Vec3 e = Vec3(frame_.row(j).head<3>()) - bi;
            const double length = e.norm();
            if (!(length > 0)) continue;  // coinciding base points: no direction to cross in
            // Along ê the lines b_i + s n_i and b_j + s n_j meet at s = ‖e‖ / ((n_i − n_j)·ê).
            const double converge = (ni - Vec3(frame_.row(j).tail<3>())).dot(e) / length;
            if (converge > 0)
              up = std::min(up, length / converge);
            else if (converge < 0)
              down = std::min(down, -length / converge);
          }
        }
      }
      focal_up_[i] = kappa * up;
      focal_down_[i] = kappa * down;
    }
  });
  // Each vertex takes the tightest focal bound of its closed one-ring: neighbours near a fold then share
  // about the same cap instead of one being held low while the next rises to make up its volume.
  parallel_for_chunks(ns, [&](long begin, long end) {
    for (long i = begin; i < end; ++i) {
      double up = focal_up_[i], down = focal_down_[i];
      for (int c = incidence_offsets_[i]; c < incidence_offsets_[i + 1]; ++c)
        for (int k = 0; k < 3; ++k) {
          const int j = faces_(incidence_corners_[c] / 3, k);
          up = std::min(up, focal_up_[j]);
          down = std::min(down, focal_down_[j]);
        }
      // The trust window around h within the focal bounds [−down, up] (which contain 0). Where the two miss
      // each other the focal bound nearest the window wins on either side, so flipping the orientation
      // (h, up, down → −h, down, up) mirrors the bounds (the lower one used to yield to the upper one).
      const double h = encoded_height_[i];
      upper_[i] = std::min(up, h + trust_[i]);
      lower_[i] = std::max(-down, h - trust_[i]);
      if (lower_[i] > upper_[i]) upper_[i] = lower_[i] = h - trust_[i] > up ? up : -down;
    }
  });
}

void DisplacementVolumes::corner_pass(const Eigen::VectorXd& h, bool derivatives) {
  const long nf = static_cast<long>(faces_.rows());
  const double* frame = frame_.data();
  parallel_for_chunks(nf, [&](long begin, long end) {
    for (long t = begin; t < end; ++t) {
      // Per triangle: the 3 kite volumes, then the 3 derivatives, then the 3 couplings (one cache line
      // or two for the vertex pass's gather).
      double* volume = corner_.data() + 9 * t;
      double* derivative = volume + 3;
      double* coupling = volume + 6;
      if (!active_[t]) {
        std::fill(volume, volume + 9, 0.0);
        continue;
      }
      const int i0 = faces_(t, 0), i1 = faces_(t, 1), i2 = faces_(t, 2);
      const double ht[3] = {h[i0], h[i1], h[i2]};
      if (derivatives)
        kite_volumes<true>(frame + 6 * i0, frame + 6 * i1, frame + 6 * i2, ht, volume, derivative, coupling);
      else
        kite_volumes<false>(frame + 6 * i0, frame + 6 * i1, frame + 6 * i2, ht, volume, derivative, coupling);
    }
  });
}

void DisplacementVolumes::gather_volumes(Eigen::VectorXd& volume) const {
  const long ns = static_cast<long>(volume.size());
  parallel_for_chunks(ns, [&](long begin, long end) {
    for (long i = begin; i < end; ++i) {
      double sum = 0;
      for (int c = incidence_offsets_[i]; c < incidence_offsets_[i + 1]; ++c)
        sum += corner_[corner_slot(incidence_corners_[c])];
      volume[i] = sum;
    }
  });
}

void DisplacementVolumes::sweep(const Eigen::VectorXd& h, Eigen::VectorXd& next, double& max_error,
                                double& rms_error) {
  corner_pass(h, true);
  const long ns = static_cast<long>(h.size());
  std::mutex mutex;
  double max_all = 0, sum_all = 0;
  long count_all = 0;
  const double omega = options_.relaxation;
  parallel_for_chunks(ns, [&](long begin, long end) {
    double max_chunk = 0, sum_chunk = 0;
    long count_chunk = 0;
    for (long i = begin; i < end; ++i) {
      next[i] = h[i];
      held_[i] = 0;
      regularised_[i] = 0;
      if (anchored_[i] || !(volume_scale_[i] > 0)) continue;
      double volume = 0, derivative = 0, coupling = 0;
      for (int c = incidence_offsets_[i]; c < incidence_offsets_[i + 1]; ++c) {
        const int corner = incidence_corners_[c];
        const double* x = corner_.data() + corner_slot(corner);
        volume += x[0];
        derivative += x[3];
        coupling += x[6];
      }
      // Regulariser towards the encoded height, per vertex and only as strong as needed to keep the row
      // diagonally dominant: J_ii + λ_i ≥ γ Σ_j |J_ij| (see the class comment). 0 on healthy cells.
      // Within a frame λ_i only grows, so that the equations settle instead of switching on and off.
      adaptive_[i] = std::max(adaptive_[i], kDominance * coupling - derivative);
      const double lambda = tikhonov_[i] + adaptive_[i];
      regularised_[i] = adaptive_[i] > 0;
      const double residual = volume - frame_target_[i] + lambda * (h[i] - encoded_height_[i]);
      derivative += lambda;  // > 0 unless the vertex has no coupling and a non-positive derivative
      // l1-Jacobi step, −ω r_i / (|J_ii| + Σ_j |J_ij|), in Gauss–Newton form with Levenberg damping so
      // that it shrinks to zero rather than flipping sign where the derivative vanishes.
      const double row = std::abs(derivative) + coupling;
      const double step = -omega * residual * derivative / (std::abs(derivative) * row + damping_[i]);
      const double e = std::abs(residual) / volume_scale_[i];
      if (e > options_.volume_tolerance &&
          ((h[i] >= upper_[i] && step > 0) || (h[i] <= lower_[i] && step < 0))) {
        held_[i] = 1;  // at its bound and pushed outwards: the equation cannot be met inside the bounds
        continue;
      }
      next[i] = std::clamp(h[i] + step, lower_[i], upper_[i]);
      max_chunk = std::max(max_chunk, e);
      sum_chunk += e * e;
      ++count_chunk;
    }
    std::lock_guard<std::mutex> lock(mutex);
    max_all = std::max(max_all, max_chunk);
    sum_all += sum_chunk;
    count_all += count_chunk;
  });
  max_error = max_all;
  rms_error = count_all > 0 ? std::sqrt(sum_all / count_all) : 0.0;
  if (!std::isfinite(max_error) || !std::isfinite(rms_error)) max_error = rms_error = kInfinity;
}

void DisplacementVolumes::encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) {
  const char* where = "DisplacementVolumes::encode";
  const auto& o = options_;
  check_faces(Fs, S.rows(), where, "S");
  check_faces(Fb, B.rows(), where, "B");
  check_finite(S, where, "S");
  check_finite(B, where, "B");
  // Prism volumes go as size³ and the relaxation squares them: beyond 1e±50 they leave double's range (the
  // knight scaled by 1e65 came out 3 % of its diagonal off, with folds, and exit 0).
  if (const double size = bounding_box_diagonal(S); !(size >= kMinSize && size <= kMaxSize))
    throw InvalidInput(
        std::string(where) + ": S's bounding-box diagonal is " + format_number(size) +
        "; the displacement volumes (size³) work with diagonals from 1e-50 to 1e50: scale the mesh, "
        "or use the normal, vectors or transfer encoding");

  encoded_ = false;  // stays so if anything below throws
  have_previous_ = false;
  const long ns = static_cast<long>(S.rows()), nf = static_cast<long>(Fs.rows());
  anchored_.assign(ns, 0);
  for (int v : anchors_) {
    if (v < 0 || v >= ns)
      throw InvalidInput(std::string(where) + ": anchor vertex " + std::to_string(v) + " out of range [0, " +
                         std::to_string(ns) + ")");
    anchored_[v] = 1;
  }
  placed_row_ = placed_mask(ns, where);
  normal_.encode(S, Fs, B, Fb);
  faces_ = Fs;
  base_faces_ = Fb;
  base_ = B;
  base_normals_ = VertexNormals(Fb, static_cast<int>(B.rows()));
  base_frames(B);
  encoded_height_ = normal_.heights();
  height_ = encoded_height_;
  trial_height_.resize(ns);
  focal_up_.resize(ns);
  focal_down_.resize(ns);
  adaptive_.setZero(ns);
  previous_height_.resize(ns);

  // Incidence of S: the corners 3t + l around each vertex.
  incidence_offsets_.assign(ns + 1, 0);
  for (long t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k) ++incidence_offsets_[Fs(t, k) + 1];
  for (long i = 0; i < ns; ++i) incidence_offsets_[i + 1] += incidence_offsets_[i];
  incidence_corners_.resize(3 * nf);
  std::vector<int> fill(incidence_offsets_.begin(), incidence_offsets_.end() - 1);
  for (long t = 0; t < nf; ++t)
    for (int l = 0; l < 3; ++l) incidence_corners_[fill[Fs(t, l)]++] = static_cast<int>(3 * t + l);

  // Prisms: degenerate base triangles are skipped; dual-cell areas Ā_i of the rest.
  double mean_area = 0;
  for (long t = 0; t < nf; ++t) {
    const Vec3 p0 = S.row(Fs(t, 0));
    mean_area += 0.5 * (Vec3(S.row(Fs(t, 1))) - p0).cross(Vec3(S.row(Fs(t, 2))) - p0).norm();
  }
  mean_area /= std::max<long>(nf, 1);
  prism_volume_.resize(nf);
  active_.assign(nf, 0);
  Eigen::VectorXd base_area(nf);
  int skipped = 0;
  for (long t = 0; t < nf; ++t) {
    const Vec3 b0 = b_.row(Fs(t, 0)), b1 = b_.row(Fs(t, 1)), b2 = b_.row(Fs(t, 2));
    base_area[t] = 0.5 * (b1 - b0).cross(b2 - b0).norm();
    active_[t] = base_area[t] > kDegenerateBaseArea * mean_area;
    skipped += !active_[t];
    Vec3 top[3];
    for (int k = 0; k < 3; ++k)
      top[k] = Vec3(b_.row(Fs(t, k))) + encoded_height_[Fs(t, k)] * Vec3(frame_.row(Fs(t, k)).tail<3>());
    prism_volume_[t] = active_[t] ? prism_volume(b0, b1, b2, top[0], top[1], top[2]) : 0.0;
  }

  // Targets W_i, scales, Tikhonov weights and trust bounds per vertex.
  corner_.resize(9 * nf);
  lower_.setConstant(ns, -kInfinity);
  upper_.setConstant(ns, kInfinity);
  held_.assign(ns, 0);
  regularised_.assign(ns, 0);
  target_.resize(ns);
  volume_scale_.resize(ns);
  tikhonov_.resize(ns);
  damping_.resize(ns);
  trust_.resize(ns);
  const double h_floor = 1e-9 * std::max(bounding_box_diagonal(S), 1e-300);
  const double h_ref = std::max(std::sqrt(encoded_height_.squaredNorm() / std::max<long>(ns, 1)), h_floor);
  frame_target_.resize(ns);
  cold_volume_.resize(ns);
  corner_pass(encoded_height_, false);  // the kite volumes of the encoding
  // η_i: the largest |h| within two rings of i (one ring gives the heights i's kites see; the second
  // lets i follow its neighbours, whose own rings may reach detail that i's does not).
  Eigen::VectorXd ring_max(ns);
  auto ring_maximum = [&](const Eigen::VectorXd& x, Eigen::VectorXd& result) {
    for (long i = 0; i < ns; ++i) {
      double m = x[i];
      for (int c = incidence_offsets_[i]; c < incidence_offsets_[i + 1]; ++c)
        for (int k = 0; k < 3; ++k) m = std::max(m, x[Fs(incidence_corners_[c] / 3, k)]);
      result[i] = m;
    }
  };
  Eigen::VectorXd eta(ns);
  ring_maximum(encoded_height_.cwiseAbs(), ring_max);
  ring_maximum(ring_max, eta);
  for (long i = 0; i < ns; ++i) {
    double volume = 0, area = 0;
    for (int c = incidence_offsets_[i]; c < incidence_offsets_[i + 1]; ++c) {
      const int corner = incidence_corners_[c];
      volume += corner_[corner_slot(corner)];
      if (active_[corner / 3]) area += base_area[corner / 3] / 3;
    }
    target_[i] = volume;
    volume_scale_[i] = area > 0 ? std::max(std::abs(volume), area * h_ref) : 0.0;
    tikhonov_[i] = o.regularization * area;
    damping_[i] = std::pow(kDamping * kOwnWeight * 6 * area, 2);  // relative to the flat ∂W_i/∂h_i
    trust_[i] = o.max_height_change * eta[i];  // infinite for an infinite max_height_change (and η > 0)
    if (std::isnan(trust_[i])) trust_[i] = 0;  // ∞ · 0: no detail around i to change
  }

  report_ = Report();
  report_.skipped_prisms = skipped;
  report_.converged = report_.volumes_within_tolerance = true;
  encoded_ = true;
}

void DisplacementVolumes::reconstruct(const Positions& B_deformed, Positions& out) {
  const auto t0 = std::chrono::steady_clock::now();
  const char* where = "DisplacementVolumes::reconstruct";
  if (!encoded_) throw UsageError(std::string(where) + ": called before encode()");
  check_not_aliased(B_deformed, out, where);
  if (B_deformed.rows() != base_.rows())
    throw UsageError(std::string(where) + ": deformed base has " + std::to_string(B_deformed.rows()) +
                     " vertices, the encoded base had " + std::to_string(base_.rows()));
  check_finite(B_deformed, where, "the deformed base");

  base_frames(B_deformed);
  Report report;
  report.skipped_prisms = report_.skipped_prisms;
  const long ns = static_cast<long>(height_.size());
  const double tolerance = options_.volume_tolerance;
  if (B_deformed == base_) {
    // The encoded heights meet every volume on B by construction (and drop a stale warm start).
    height_ = encoded_height_;
    have_previous_ = false;
    report.converged = report.volumes_within_tolerance = true;
  } else {
    bounds();
    adaptive_.setZero();
    // Normal-displacement volumes N_i = W_i(h) on B', and the frame's targets: W_i, limited to within a
    // factor (1 + ρ) of N_i (both ways) where B' changes the cells too much for the volume to be kept.
    corner_pass(encoded_height_, false);
    gather_volumes(cold_volume_);
    const double rho = options_.max_volume_change;
    double cold_error = 0;
    for (long i = 0; i < ns; ++i) {
      // Within a factor (1 + ρ) of N_i in magnitude, the sign's side mirrored (the same window for the
      // opposite orientation, where every volume changes sign).
      const double n = cold_volume_[i], reach = std::max(std::abs(n), kVolumeFloor * volume_scale_[i]);
      const double grow = rho * reach, shrink = rho / (1 + rho) * reach;
      const double t =
          n < 0 ? std::clamp(target_[i], n - grow, n + shrink) : std::clamp(target_[i], n - shrink, n + grow);
      report.limited_volumes += !anchored_[i] && t != target_[i];
      frame_target_[i] = t;
      if (!anchored_[i] && volume_scale_[i] > 0)
        cold_error = std::max(cold_error, std::abs(n - t) / volume_scale_[i]);
    }
    // Clips h into the bounds (anchors excepted); true if anything moved.
    auto clip = [&](Eigen::VectorXd& h) {
      bool moved = false;
      for (long i = 0; i < ns; ++i) {
        if (anchored_[i]) continue;
        const double c = std::clamp(h[i], lower_[i], upper_[i]);
        moved = moved || c != h[i];
        h[i] = c;
      }
      return moved;
    };
    // The residuals at height_ and the next Jacobi iterate in trial_height_.
    double error = 0, rms = 0;
    auto evaluate = [&] { sweep(height_, trial_height_, error, rms); };
    bool cold = true;
    if (options_.warm_start && have_previous_) {
      clip(height_);
      evaluate();
      cold = !(error <= cold_error);  // the encoded heights may be closer (a rigid motion after a bend)
    }
    if (cold) {
      height_ = encoded_height_;
      adaptive_.setZero();
      // Unclipped, the encoded heights are exact for rigid motions; a start that must iterate is clipped.
      if (cold_error > tolerance) clip(height_);
      evaluate();
    }
    report.warm_started = !cold;
    report.initial_max_relative_error = error;
    report.initial_rms_relative_error = rms;
    // Chebyshev semi-iteration over the Jacobi sweeps (Wang 2015, "A Chebyshev semi-iterative approach
    // for accelerating projective and position-based dynamics"): x_{k+1} = ω_{k+1} (x̂_{k+1} − x_{k−1}) +
    // x_{k−1}, x̂ the sweep's iterate, ω_2 = 2 / (2 − ρ²), ω_{k+1} = 4 / (4 − ρ² ω_k), ρ the spectral
    // radius of the sweep's iteration matrix (0.42 on a flat base, see relaxation); projected into the
    // bounds. Held heights (next = current) stay put.
    const double rho2 = options_.chebyshev ? kChebyshevRadius * kChebyshevRadius : 0.0;
    double omega = 1;
    while (error > tolerance && report.iterations < options_.max_iterations && std::isfinite(error)) {
      ++report.iterations;
      if (report.iterations == 1 || rho2 == 0) {
        previous_height_ = height_;
        height_.swap(trial_height_);
      } else {
        omega = report.iterations == 2 ? 2 / (2 - rho2) : 4 / (4 - rho2 * omega);
        for (long i = 0; i < ns; ++i) {
          const double x = previous_height_[i] + omega * (trial_height_[i] - previous_height_[i]);
          previous_height_[i] = height_[i];
          height_[i] = trial_height_[i] == height_[i] ? height_[i] : std::clamp(x, lower_[i], upper_[i]);
        }
      }
      evaluate();
    }
    report.max_relative_error = error;
    report.rms_relative_error = rms;
    report.converged = error <= tolerance;
    for (long i = 0; i < ns; ++i) {
      report.bounded_heights += held_[i];
      report.regularised_heights += regularised_[i];
    }
    report.volumes_within_tolerance =
        report.converged && report.bounded_heights == 0 && report.limited_volumes == 0;
    have_previous_ = true;
  }

  size_output(out, ns, where);
  bool finite = true;
  for (long i = 0; i < ns; ++i) {
    if (placed_row_[i]) continue;  // written by the caller
    out.row(i) = frame_.row(i).head<3>() + height_[i] * frame_.row(i).tail<3>();
    finite = finite && out.row(i).allFinite();
  }
  if (!finite) throw InvalidInput(std::string(where) + ": non-finite result from a finite base (overflow?)");
  report.seconds = seconds_since(t0);
  report_ = report;
}

}  // namespace msd
