#include "detail/displacement_volumes.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "core/errors.h"
#include "core/parallel.h"
#include "detail/phong.h"

namespace msd {
namespace {

// A base triangle below this fraction of the mean S-triangle area makes a degenerate prism.
constexpr double kDegenerateBaseArea = 1e-10;
// Tiny Tikhonov floor, relative to Ā², that keeps H positive definite when regularization = 0.
constexpr double kDiagonalFloor = 1e-14;
constexpr double kMaxDamping = 1e16;
constexpr double kMinDamping = 1e-14;

// The displacement direction of NormalDisplacements at barycentrics w of base face f: the normalised
// Phong normal, else the unit face normal, else zero.
// Volume of the blended prism with bottom a_k = b_k and top c_k = b_k + h_k n_k, and its gradient with
// respect to (h0, h1, h2). See prism_volume() for the formula; ∂d_k/∂h_k = n_k, ∂f1 = n1 dh1 − n0 dh0,
// ∂f2 = n2 dh2 − n0 dh0, ∂m = (∂f1 × (e2 + 2 f2) + (e1 + 2 f1) × ∂f2) / 6.
double prism_volume_and_gradient(const Vec3 b[3], const Vec3 n[3], const double h[3], Vec3& gradient) {
  const Vec3 d0 = h[0] * n[0], d1 = h[1] * n[1], d2 = h[2] * n[2];
  const Vec3 e1 = b[1] - b[0], e2 = b[2] - b[0];
  const Vec3 f1 = e1 + d1 - d0, f2 = e2 + d2 - d0;
  const Vec3 m = (2 * e1.cross(e2) + e1.cross(f2) + f1.cross(e2) + 2 * f1.cross(f2)) / 6;
  const Vec3 D = d0 + d1 + d2;
  const Vec3 u = e2 + 2 * f2, w = e1 + 2 * f1;
  // ∂m·D / 6 for each height, with (x × y)·D = x · (y × D) to share the cross products.
  const Vec3 uD = u.cross(D), Dw = D.cross(w);  // (δf1 × u)·D = δf1·(u × D);  (w × δf2)·D = δf2·(D × w)
  const double g1 = n[1].dot(uD) / 36, g2 = n[2].dot(Dw) / 36;
  const double g0 = -(n[0].dot(uD) + n[0].dot(Dw)) / 36;
  gradient = Vec3(g0 + m.dot(n[0]) / 6, g1 + m.dot(n[1]) / 6, g2 + m.dot(n[2]) / 6);
  return m.dot(D) / 6;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

double prism_volume(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& c0, const Vec3& c1,
                    const Vec3& c2) {
  const Vec3 e1 = a1 - a0, e2 = a2 - a0, f1 = c1 - c0, f2 = c2 - c0;
  const Vec3 m = (2 * e1.cross(e2) + e1.cross(f2) + f1.cross(e2) + 2 * f1.cross(f2)) / 6;
  return m.dot((c0 - a0) + (c1 - a1) + (c2 - a2)) / 6;
}

DisplacementVolumes::DisplacementVolumes(const DisplacementVolumeOptions& options,
                                         const NormalDisplacementOptions& normal_options)
    : options_(options), normal_(normal_options) {}

void DisplacementVolumes::base_frames(const Positions& B) {
  normal_.base_points(B, b_);
  base_normals_.compute(B, vertex_normals_);
  const Eigen::VectorXi& face = normal_.base_faces();
  const Eigen::MatrixX3d& bary = normal_.barycentrics();
  const long ns = static_cast<long>(face.size());
  if (n_.rows() != ns) n_.resize(ns, 3);
  parallel_for_chunks(ns, [&](long begin, long end) {
    for (long i = begin; i < end; ++i)
      n_.row(i) = phong::direction(phong::Columns(B), phong::Columns(vertex_normals_),
                                   &base_faces_(face[i], 0), bary.row(i));
  });
}

void DisplacementVolumes::focal_bounds() {
  const long ns = static_cast<long>(height_.size());
  if (lower_.size() != ns) {
    lower_.resize(ns);
    upper_.resize(ns);
  }
  const double kappa = options_.focal_fraction;
  const double trust = options_.max_height_change * height_scale_;  // may be infinite
  if (std::isinf(kappa)) {
    lower_ = encoded_height_.array() - trust;
    upper_ = encoded_height_.array() + trust;
    return;
  }
  parallel_for_chunks(ns, [&](long begin, long end) {
    for (long i = begin; i < end; ++i) {
      const Vec3 bi = b_.row(i), ni = n_.row(i);
      double up = std::numeric_limits<double>::infinity(), down = up;
      for (int c = incidence_offsets_[i]; c < incidence_offsets_[i + 1]; ++c) {
        const int t = incidence_faces_[c] / 3, l = incidence_faces_[c] % 3;
        for (int k = 0; k < 3; ++k) {
          const int j = faces_(t, k);
          if (k == l || j == i) continue;
          const Vec3 e = Vec3(b_.row(j)) - bi;
          const double length = e.norm();
          if (!(length > 0)) continue;  // coinciding base points: no direction to cross in
          // Along ê the lines b_i + s n_i and b_j + s n_j meet at s = ‖e‖ / ((n_i − n_j)·ê).
          const double converge = (ni - Vec3(n_.row(j))).dot(e) / length;
          if (converge > 0)
            up = std::min(up, length / converge);
          else if (converge < 0)
            down = std::min(down, -length / converge);
        }
      }
      upper_[i] = std::min(kappa * up, encoded_height_[i] + trust);
      lower_[i] = std::min(std::max(-kappa * down, encoded_height_[i] - trust), upper_[i]);
    }
  });
}

double DisplacementVolumes::evaluate(const Eigen::VectorXd& h, Eigen::VectorXd& r,
                                     Eigen::MatrixX3d& J) const {
  const long nf = static_cast<long>(faces_.rows());
  if (r.size() != nf) r.resize(nf);
  if (J.rows() != nf) J.resize(nf, 3);
  parallel_for_chunks(nf, [&](long begin, long end) {
    for (long t = begin; t < end; ++t) {
      if (!active_[t]) {
        r[t] = 0;
        J.row(t).setZero();
        continue;
      }
      Vec3 b[3], n[3], gradient;
      double ht[3];
      for (int k = 0; k < 3; ++k) {
        const int i = faces_(t, k);
        b[k] = b_.row(i);
        n[k] = n_.row(i);
        ht[k] = h[i];
      }
      r[t] = prism_volume_and_gradient(b, n, ht, gradient) - volume_[t];
      J.row(t) = gradient;
    }
  });
  double roughness = 0;  // Σ_t Σ_edges ½ (δ_i − δ_j)²
  if (smoothness_ > 0)
    for (long t = 0; t < nf; ++t)
      for (int k = 0; k < 3; ++k) {
        const int i = faces_(t, k), j = faces_(t, (k + 1) % 3);
        const double d = (h[i] - encoded_height_[i]) - (h[j] - encoded_height_[j]);
        roughness += 0.5 * d * d;
      }
  return 0.5 * (r.squaredNorm() + tikhonov_ * (h - encoded_height_).squaredNorm() + smoothness_ * roughness);
}

void DisplacementVolumes::relative_errors(const Eigen::VectorXd& r, double& max_error,
                                          double& rms_error) const {
  max_error = 0;
  double sum = 0;
  long count = 0;
  for (Eigen::Index t = 0; t < r.size(); ++t) {
    if (!active_[t] || !(volume_scale_[t] > 0)) continue;
    const double e = std::abs(r[t]) / volume_scale_[t];
    max_error = std::max(max_error, e);
    sum += e * e;
    ++count;
  }
  rms_error = count > 0 ? std::sqrt(sum / count) : 0.0;
}

void DisplacementVolumes::assemble(const Eigen::MatrixX3d& J, const Eigen::VectorXd& r) {
  double* values = H_.valuePtr();
  const int* column_start = H_.outerIndexPtr();
  const long ns = static_cast<long>(diagonal_slot_.size());
  parallel_for_chunks(ns, [&](long begin, long end) {
    for (long j = begin; j < end; ++j) {
      std::fill(values + column_start[j], values + column_start[j + 1], 0.0);
      double g = 0;
      const double dj = height_[j] - encoded_height_[j];
      for (int c = incidence_offsets_[j]; c < incidence_offsets_[j + 1]; ++c) {
        const int t = incidence_faces_[c] / 3, l = incidence_faces_[c] % 3;
        const double jl = J(t, l);
        g += jl * r[t];
        for (int k = 0; k < 3; ++k) {
          const int slot = incidence_slots_[3 * c + k];
          if (slot >= 0) values[slot] += J(t, k) * jl;
          if (k == l || smoothness_ == 0) continue;
          // Smoothness: each triangle edge (j, i) adds ½σ'(δ_j − δ_i)² → Hessian ½σ' on the diagonal,
          // −½σ' off it, gradient ½σ'(δ_j − δ_i).
          const int i = faces_(t, k);
          g += 0.5 * smoothness_ * (dj - (height_[i] - encoded_height_[i]));
          values[diagonal_slot_[j]] += 0.5 * smoothness_;
          if (slot >= 0) values[slot] -= 0.5 * smoothness_;
        }
      }
      hessian_diagonal_[j] = values[diagonal_slot_[j]] + tikhonov_;
      // Right-hand side −g of the step equations, g = Jᵀr + (λĀ)² (h − h_encoded).
      gradient_(j, 0) = -(g + tikhonov_ * (height_[j] - encoded_height_[j]));
    }
  });
}

void DisplacementVolumes::encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) {
  const char* where = "DisplacementVolumes::encode";
  const auto& o = options_;
  auto bad = [](double x) { return !(x >= 0) || !std::isfinite(x); };
  if (o.max_iterations < 0 || bad(o.volume_tolerance) || bad(o.stationary_tolerance) ||
      bad(o.regularization) || bad(o.damping) || bad(o.smoothness) || !(o.focal_fraction > 0) ||
      !(o.max_height_change > 0))
    throw InvalidInput(std::string(where) +
                       ": options need max_iterations >= 0, finite, non-negative volume_tolerance, "
                       "stationary_tolerance, regularization, smoothness and damping, and focal_fraction, "
                       "max_height_change > 0");
  check_faces(Fs, S.rows(), where, "S");
  check_faces(Fb, B.rows(), where, "B");
  check_finite(S, where, "S");
  check_finite(B, where, "B");

  encoded_ = false;  // stays so if anything below throws
  anchored_.assign(S.rows(), 0);
  for (int v : anchors_) {
    if (v < 0 || v >= S.rows())
      throw InvalidInput(std::string(where) + ": anchor vertex " + std::to_string(v) + " out of range [0, " +
                         std::to_string(S.rows()) + ")");
    anchored_[v] = 1;
  }
  normal_.encode(S, Fs, B, Fb);
  faces_ = Fs;
  base_faces_ = Fb;
  num_base_vertices_ = static_cast<int>(B.rows());
  base_normals_ = VertexNormals(Fb, num_base_vertices_);
  base_frames(B);
  encoded_height_ = normal_.heights();
  height_scale_ = encoded_height_.size() ? encoded_height_.cwiseAbs().maxCoeff() : 0.0;
  height_ = encoded_height_;
  trial_height_.resize(height_.size());

  const long ns = static_cast<long>(S.rows()), nf = static_cast<long>(Fs.rows());
  double mean_area = 0;
  for (long t = 0; t < nf; ++t) {
    const Vec3 p0 = S.row(Fs(t, 0));
    mean_area += 0.5 * (Vec3(S.row(Fs(t, 1))) - p0).cross(Vec3(S.row(Fs(t, 2))) - p0).norm();
  }
  mean_area /= nf;
  const double h_floor = 1e-9 * std::max(bounding_box_diagonal(S), 1e-300);
  const double h_ref = std::max(std::sqrt(encoded_height_.squaredNorm() / std::max<long>(ns, 1)), h_floor);

  volume_.resize(nf);
  volume_scale_.resize(nf);
  active_.assign(nf, 0);
  Eigen::VectorXd base_area(nf);
  parallel_for_chunks(nf, [&](long begin, long end) {
    for (long t = begin; t < end; ++t) {
      Vec3 b[3], n[3], gradient;
      double ht[3];
      for (int k = 0; k < 3; ++k) {
        const int i = Fs(t, k);
        b[k] = b_.row(i);
        n[k] = n_.row(i);
        ht[k] = encoded_height_[i];
      }
      base_area[t] = 0.5 * (b[1] - b[0]).cross(b[2] - b[0]).norm();
      active_[t] = base_area[t] > kDegenerateBaseArea * mean_area;
      volume_[t] = active_[t] ? prism_volume_and_gradient(b, n, ht, gradient) : 0.0;
      volume_scale_[t] = active_[t] ? std::max(std::abs(volume_[t]), base_area[t] * h_ref) : 0.0;
    }
  });
  int skipped = 0;
  double active_area = 0;
  for (long t = 0; t < nf; ++t) {
    if (active_[t])
      active_area += base_area[t];
    else
      ++skipped;
  }
  const double mean_base_area =
      skipped < nf ? active_area / (nf - skipped) : (mean_area > 0 ? mean_area : 1.0);
  tikhonov_ = std::pow(o.regularization * mean_base_area, 2);
  smoothness_ = std::pow(o.smoothness * mean_base_area, 2);
  diagonal_floor_ = kDiagonalFloor * mean_base_area * mean_base_area;

  // Pattern of H = JᵀJ: S's vertex adjacency plus the diagonal, lower triangle.
  std::vector<Triplet> pattern;
  pattern.reserve(ns + 6 * nf);
  for (long i = 0; i < ns; ++i) pattern.emplace_back(i, i, 0.0);
  for (long t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l)
        if (Fs(t, k) > Fs(t, l)) pattern.emplace_back(Fs(t, k), Fs(t, l), 0.0);
  H_.resize(ns, ns);
  H_.setFromTriplets(pattern.begin(), pattern.end());
  H_.makeCompressed();
  auto slot_of = [&](int i, int j) {  // value index of H(i, j), i ≥ j
    const int* rows = H_.innerIndexPtr();
    const int* first = rows + H_.outerIndexPtr()[j];
    const int* last = rows + H_.outerIndexPtr()[j + 1];
    return static_cast<int>(std::lower_bound(first, last, i) - rows);
  };
  incidence_offsets_.assign(ns + 1, 0);
  for (long t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k) ++incidence_offsets_[Fs(t, k) + 1];
  for (long i = 0; i < ns; ++i) incidence_offsets_[i + 1] += incidence_offsets_[i];
  incidence_faces_.resize(3 * nf);
  incidence_slots_.resize(9 * nf);
  std::vector<int> fill(incidence_offsets_.begin(), incidence_offsets_.end() - 1);
  for (long t = 0; t < nf; ++t)
    for (int l = 0; l < 3; ++l) {
      const int j = Fs(t, l), c = fill[j]++;
      incidence_faces_[c] = static_cast<int>(3 * t + l);
      for (int k = 0; k < 3; ++k) incidence_slots_[3 * c + k] = Fs(t, k) >= j ? slot_of(Fs(t, k), j) : -1;
    }
  diagonal_slot_.resize(ns);
  for (long j = 0; j < ns; ++j) diagonal_slot_[j] = slot_of(static_cast<int>(j), static_cast<int>(j));

  // Symbolic analysis (and a first numeric factorisation) of the step equations, here at h' = h on B;
  // reconstruct() only refactors. A unit damping keeps this matrix well conditioned.
  hessian_diagonal_.resize(ns);
  gradient_.resize(ns, 1);
  evaluate(height_, r_, J_);
  assemble(J_, r_);
  for (long j = 0; j < ns; ++j) H_.valuePtr()[diagonal_slot_[j]] = 2 * hessian_diagonal_[j] + diagonal_floor_;
  solver_.factor(H_);

  report_ = Report();
  report_.skipped_prisms = skipped;
  encoded_ = true;
}

void DisplacementVolumes::reconstruct(const Positions& B_deformed, Positions& out) {
  const auto t0 = std::chrono::steady_clock::now();
  const char* where = "DisplacementVolumes::reconstruct";
  if (!encoded_) throw UsageError(std::string(where) + ": called before encode()");
  if (B_deformed.rows() != num_base_vertices_)
    throw UsageError(std::string(where) + ": deformed base has " + std::to_string(B_deformed.rows()) +
                     " vertices, the encoded base had " + std::to_string(num_base_vertices_));
  check_finite(B_deformed, where, "the deformed base");

  base_frames(B_deformed);
  height_ = encoded_height_;
  double cost = evaluate(height_, r_, J_);
  Report report;
  report.skipped_prisms = report_.skipped_prisms;
  relative_errors(r_, report.initial_max_relative_error, report.initial_rms_relative_error);
  report.max_relative_error = report.initial_max_relative_error;
  report.rms_relative_error = report.initial_rms_relative_error;

  double mu = options_.damping;
  double* values = H_.valuePtr();
  const int* rows = H_.innerIndexPtr();
  const int* column_start = H_.outerIndexPtr();
  const long ns = static_cast<long>(height_.size());
  const bool iterate = report.max_relative_error > options_.volume_tolerance && options_.max_iterations > 0;
  if (iterate) {
    // Iterations will follow: clip the start into the fold guard's bounds.
    focal_bounds();
    bool clipped = false;
    for (long i = 0; i < ns; ++i) {
      const double h = anchored_[i] ? height_[i] : std::clamp(height_[i], lower_[i], upper_[i]);
      clipped = clipped || h != height_[i];
      height_[i] = h;
    }
    if (clipped) {
      cost = evaluate(height_, r_, J_);
      relative_errors(r_, report.max_relative_error, report.rms_relative_error);
    }
  }
  held_.assign(ns, 0);
  for (;;) {
    if (report.max_relative_error <= options_.volume_tolerance) {
      report.converged = report.volumes_within_tolerance = true;
      break;
    }
    if (report.factorizations >= options_.max_iterations) break;
    assemble(J_, r_);
    // Projected Newton: an anchor's height, and a height at its bound whose descent direction
    // (gradient_ = −g) points outwards, is held for this step: its row and column of the step equations
    // become the identity.
    bool any_held = false;
    for (long j = 0; j < ns; ++j) {
      held_[j] = anchored_[j] || (height_[j] >= upper_[j] && gradient_(j, 0) > 0) ||
                 (height_[j] <= lower_[j] && gradient_(j, 0) < 0);
      if (held_[j]) {
        gradient_(j, 0) = 0;
        any_held = true;
      }
    }
    if (any_held)
      parallel_for_chunks(ns, [&](long begin, long end) {
        for (long j = begin; j < end; ++j)
          for (int k = column_start[j]; k < column_start[j + 1]; ++k)
            if (rows[k] != j && (held_[j] || held_[rows[k]])) values[k] = 0;
      });
    bool accepted = false, stalled = false;
    double decrease = 0;
    while (report.factorizations < options_.max_iterations) {
      for (long j = 0; j < ns; ++j)
        values[diagonal_slot_[j]] = held_[j] ? 1.0 : hessian_diagonal_[j] * (1 + mu) + diagonal_floor_;
      solver_.refactor(H_);
      ++report.factorizations;
      solver_.solve(gradient_, step_);
      for (long j = 0; j < ns; ++j)
        trial_height_[j] = held_[j] ? height_[j] : std::clamp(height_[j] + step_(j, 0), lower_[j], upper_[j]);
      const double trial_cost = evaluate(trial_height_, trial_r_, trial_J_);
      if (trial_cost < cost) {  // false for NaN
        decrease = cost - trial_cost;
        cost = trial_cost;
        height_.swap(trial_height_);
        r_.swap(trial_r_);
        J_.swap(trial_J_);
        mu = mu / 10 < kMinDamping ? 0.0 : mu / 10;
        accepted = true;
        break;
      }
      mu = std::max(10 * mu, 1e-6);
      if (mu > kMaxDamping) {  // no step lowers the cost any more: numerically stationary
        stalled = true;
        break;
      }
    }
    if (!accepted) {
      report.converged = stalled;
      break;
    }
    ++report.iterations;
    relative_errors(r_, report.max_relative_error, report.rms_relative_error);
    if (decrease <= options_.stationary_tolerance * (cost + decrease)) {
      report.converged = true;
      report.volumes_within_tolerance = report.max_relative_error <= options_.volume_tolerance;
      break;
    }
  }

  if (iterate)
    for (long i = 0; i < ns; ++i)
      report.bounded_heights += !anchored_[i] && (height_[i] <= lower_[i] || height_[i] >= upper_[i]);
  if (out.rows() != ns) out.resize(ns, 3);
  std::atomic<bool> finite{true};
  parallel_for_chunks(ns, [&](long begin, long end) {
    bool chunk_finite = true;
    for (long i = begin; i < end; ++i) {
      out.row(i) = b_.row(i) + height_[i] * n_.row(i);
      chunk_finite = chunk_finite && out.row(i).allFinite();
    }
    if (!chunk_finite) finite = false;
  });
  if (!finite) throw InvalidInput(std::string(where) + ": non-finite result from a finite base (overflow?)");
  report.seconds = seconds_since(t0);
  report_ = report;
}

}  // namespace msd
