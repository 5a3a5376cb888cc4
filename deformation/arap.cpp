#include "msdeform/deformation/arap.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/rotation.h"

namespace msd {
namespace {

constexpr long kGrain = 2048;
// Newton steps of the rotation fit per local step (warm-started from the last local step's rotation, so
// over the iterations the fits converge with the positions); a step of |δ|² below kFitAngle ends them.
constexpr int kFitIterations = 2;
constexpr double kFitAngle = 1e-10;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// tr(Rᵀ A).
double alignment(const Mat3& R, const Mat3& A) { return R.cwiseProduct(A).sum(); }

}  // namespace

const char* to_string(ArapEnergy energy) {
  return energy == ArapEnergy::Spokes ? "spokes" : "spokes-and-rims";
}

void ArapDeformer::set_max_iterations(int max_iterations) {
  if (max_iterations < 1)
    throw InvalidInput("arap: max_iterations must be at least 1 (got " + std::to_string(max_iterations) + ")");
  options_.max_iterations = max_iterations;
}

ArapDeformer::ArapDeformer(ArapOptions options) : options_(options) {
  set_max_iterations(options_.max_iterations);
  if (!(options_.tolerance >= 0 &&
        options_.tolerance <= 1))  // as --tolerance (above 1: one iteration, "converged")
    throw InvalidInput("arap: tolerance must lie in [0, 1], a fraction of the bounding-box diagonal (got " +
                       format_number(options_.tolerance) + ")");
  if (options_.anderson < 0 || options_.anderson > 8)
    throw InvalidInput("arap: anderson must lie in [0, 8] (got " + std::to_string(options_.anderson) + ")");
  if (!(options_.min_weight_ratio > 0 && options_.min_weight_ratio <= 1))
    throw InvalidInput("arap: min_weight_ratio must lie in (0, 1] (got " +
                       format_number(options_.min_weight_ratio) + ")");
}

DeformerTraits ArapDeformer::traits() const {
  DeformerTraits t;
  t.solve = DeformerSolve::Iterative;
  t.vertex_targets = true;
  t.initial_guess = true;
  t.exact_constraints = true;
  t.reproduces_rigid_motions = true;
  return t;
}

void ArapDeformer::do_prepare(const Positions& world, const Faces& F, const Region& region) {
  rest_ = world;
  // The iteration works in the shape's centred, normalised frame: the global step solves for positions, so
  // its rounding grew with their distance from the origin (the survey cactus moved 1e8 of its size away
  // changed by 2e-4 of the diagonal), and the rotation fit's determinant test, cubic in the squared size,
  // overflowed beyond sizes of ~1e50 (each fit fell back to the SVD, 6× slower, and the result moved).
  local_ = LocalFrame::of(world);
  const Positions P = local_.to_local(world);
  nv_ = static_cast<int>(P.rows());
  const long nf = F.rows();
  const bool spokes = options_.energy == ArapEnergy::Spokes;

  // Half cotangents c_k of every face (edge opposite corner k), jointly scaled for needles as
  // cotan_laplacian() does; degenerate faces weigh 0 (then get the floor below).
  std::vector<double> half_cot(3 * nf);
  parallel_for_chunks(nf, [&](long b, long e) {
    for (long f = b; f < e; ++f) {
      const TriangleCotangents t = triangle_cotangents(P.row(F(f, 0)), P.row(F(f, 1)), P.row(F(f, 2)));
      for (int k = 0; k < 3; ++k) half_cot[3 * f + k] = t.degenerate ? 0.0 : 0.5 * t.weight[k];
    }
  });

  // The floor: min_weight_ratio times the median weight magnitude, a continuous function of the weights
  // that a few outliers do not move. The mean of the positive weights jumped where a weight crosses zero
  // (a right angle's exact 0 on the survey cylinder's grid left out, its ±1e-17 counted: a 1e-16 change of
  // the input moved the result by 8e-4 of the diagonal), and any mean followed a needle's cotangent of
  // 1e5 (one edge of the survey cactus split at 1.3e-5 of its length lifted 75 % of the weights to the
  // floor and moved the result by 7e-3 of the diagonal, far from the needle).
  const auto weight_floor = [&](std::vector<double>& magnitudes) {
    if (magnitudes.empty()) return options_.min_weight_ratio;
    const auto middle = magnitudes.begin() + static_cast<long>(magnitudes.size() / 2);
    std::nth_element(magnitudes.begin(), middle, magnitudes.end());
    return options_.min_weight_ratio * (*middle > 0 ? *middle : 1.0);
  };
  std::vector<Triplet> triplets;
  triplets.reserve(6 * nf);
  clamped_weights_ = 0;
  if (spokes) {
    // Edge weights w_ij = Σ over the edge's faces of c; clamped per edge.
    for (long f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = F(f, (k + 1) % 3), b = F(f, (k + 2) % 3);
        triplets.emplace_back(a, b, half_cot[3 * f + k]);
        triplets.emplace_back(b, a, half_cot[3 * f + k]);
      }
    SparseMatrix W(nv_, nv_);
    W.setFromTriplets(triplets.begin(), triplets.end());
    std::vector<double> magnitudes;
    magnitudes.reserve(W.nonZeros());
    for (int j = 0; j < W.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(W, j); it; ++it)
        if (it.row() != j) magnitudes.push_back(std::abs(it.value()));
    const double floor = weight_floor(magnitudes);
    ring_offsets_.assign(nv_ + 1, 0);
    ring_.clear();
    ring_weight_.clear();
    ring_edge_.clear();
    ring_.reserve(W.nonZeros());
    ring_weight_.reserve(W.nonZeros());
    ring_edge_.reserve(3 * W.nonZeros());
    cell_sum_.assign(3 * nv_, 0.0);
    cell_rest_.assign(nv_, 0.0);
    triplets.clear();
    for (int i = 0; i < nv_; ++i) {  // W is symmetric: column i lists the neighbours of i
      double diagonal = 0;
      for (SparseMatrix::InnerIterator it(W, i); it; ++it) {
        const int j = static_cast<int>(it.row());
        if (j == i) continue;
        double w = it.value();
        if (w < floor) {
          w = floor;
          if (j > i) ++clamped_weights_;
        }
        const Vec3 e = P.row(i) - P.row(j);
        ring_.push_back(j);
        ring_weight_.push_back(w);
        for (int d = 0; d < 3; ++d) {
          ring_edge_.push_back(w * e[d]);
          cell_sum_[3 * i + d] += w * e[d];
        }
        cell_rest_[i] += w * e.squaredNorm();
        triplets.emplace_back(i, j, -w);
        diagonal += w;
      }
      triplets.emplace_back(i, i, diagonal);
      ring_offsets_[i + 1] = static_cast<int>(ring_.size());
    }
  } else {
    // Spokes and rims: one weight per face corner (its opposite edge in that face), clamped per corner.
    std::vector<double> magnitudes(half_cot.size());
    std::transform(half_cot.begin(), half_cot.end(), magnitudes.begin(),
                   [](double c) { return std::abs(c); });
    const double floor = weight_floor(magnitudes);
    face_vertex_.assign(F.data(), F.data() + 3 * nf);
    face_weight_.assign(3 * nf, 0.0);
    face_edge_.assign(9 * nf, 0.0);
    face_corner_.assign(9 * nf, 0.0);
    face_buffer_.assign(9 * nf, 0.0);
    face_dsq_.assign(nf, 0.0);
    cell_rest_.assign(nv_, 0.0);
    std::vector<double> face_rest(nf, 0.0);
    for (long f = 0; f < nf; ++f) {
      double c[3];
      for (int k = 0; k < 3; ++k) {
        c[k] = half_cot[3 * f + k];
        if (c[k] < floor) c[k] = floor, ++clamped_weights_;
        face_weight_[3 * f + k] = c[k];
      }
      for (int k = 0; k < 3; ++k) {
        const int v = F(f, k), a = F(f, (k + 1) % 3), b = F(f, (k + 2) % 3);
        const Vec3 e = P.row(a) - P.row(b);  // edge opposite corner k
        for (int d = 0; d < 3; ++d) face_edge_[9 * f + 3 * k + d] = c[k] * e[d];
        face_rest[f] += c[k] * e.squaredNorm();
        // s_k = c_(k+1) (p_k − p_(k+2)) + c_(k+2) (p_k − p_(k+1)): the corner's two edges.
        const Vec3 s = c[(k + 1) % 3] * (P.row(v) - P.row(b)) + c[(k + 2) % 3] * (P.row(v) - P.row(a));
        for (int d = 0; d < 3; ++d) face_corner_[9 * f + 3 * k + d] = s[d];
        triplets.emplace_back(a, b, -c[k]);
        triplets.emplace_back(b, a, -c[k]);
        triplets.emplace_back(a, a, c[k]);
        triplets.emplace_back(b, b, c[k]);
      }
    }
    // (face, corner) pairs around each vertex.
    corner_offsets_.assign(nv_ + 1, 0);
    for (long f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) ++corner_offsets_[F(f, k) + 1];
    for (int i = 0; i < nv_; ++i) corner_offsets_[i + 1] += corner_offsets_[i];
    corners_.assign(corner_offsets_[nv_], 0);
    std::vector<int> fill(corner_offsets_.begin(), corner_offsets_.end() - 1);
    for (long f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        corners_[fill[F(f, k)]++] = static_cast<int>(3 * f + k);
        cell_rest_[F(f, k)] += face_rest[f];
      }
  }

  SparseMatrix L(nv_, nv_);
  L.setFromTriplets(triplets.begin(), triplets.end());
  triplets = {};
  constrained_ = region.constrained_vertices();
  handle_of_constrained_.clear();
  for (int v : constrained_) handle_of_constrained_.push_back(region.handle_of(v));
  try {
    system_.prepare(L, constrained_);
  } catch (const SolverError& e) {
    if (e.index() < 0) throw SolverError(std::string("arap: ") + e.what());  // not singular: e.g. out of memory
    throw SolverError("arap: the global system is singular near vertex " + std::to_string(e.index()) +
                          " (a free part of the mesh without a fixed or handle vertex, or a vertex without faces)",
                      e.index());
  }
  unknown_ = system_.unknown();

  // Iteration state and buffers, sized once.
  x_ = P;
  rotation_.assign(nv_, Mat3::Identity());
  quaternion_.assign(nv_, Eigen::Vector4d(0, 0, 0, 1));
  vertex_energy_.assign(nv_, 0.0);
  rhs_known_.resize(unknown_.size(), 3);
  rhs_.resize(unknown_.size(), 3);
  x_unknown_.resize(unknown_.size(), 3);
  targets_.resize(constrained_.size(), 3);
  local_targets_.resize(constrained_.size(), 3);
  energies_.clear();
  energies_.reserve(std::min(options_.max_iterations, 100000) + 1);  // beyond that a frame may allocate
  const long n = 3 * static_cast<long>(unknown_.size());
  u_.resize(n), warm_.resize(n), f_.resize(n), f_previous_.resize(n), g_previous_.resize(n);
  const int m = std::max(options_.anderson, 1);
  delta_f_.resize(n, m), delta_g_.resize(n, m);
  normal_.resize(m, m);
  diagonal_ = bounding_box_diagonal(P);
  // Harmonic fields of the handles (1 on handle k, 0 on the other constrained vertices), for the
  // rotations of a cold start.
  const int nh = region.num_handles();
  Eigen::MatrixXd known = Eigen::MatrixXd::Zero(constrained_.size(), nh);
  for (size_t c = 0; c < constrained_.size(); ++c)
    if (handle_of_constrained_[c] >= 0) known(c, handle_of_constrained_[c]) = 1;
  system_.solve(known, handle_field_);
  handle_quaternion_.assign(nh, Eigen::Vector4d(0, 0, 0, 1));
  cold_ = true;
}

void ArapDeformer::fit_rotation(long i, const Mat3& A) {
  const double f0 = alignment(rotation_[i], A);
  const double scale = A.norm();
  if (!(scale > 0)) return;  // an empty cell: every rotation fits; keep the last one
  Eigen::Quaterniond q(quaternion_[i][3], quaternion_[i][0], quaternion_[i][1], quaternion_[i][2]);
  Mat3 R = rotation_[i];
  bool newton = true, at_optimum = false;
  for (int it = 0; it < kFitIterations && newton; ++it) {
    // Newton step on f(δ) = tr((R exp[δ]×)ᵀ A) in the body frame: with M = Rᵀ A, gradient 2m
    // (skew(M) = [m]×) and Hessian −(tr M · I − sym M) = −K. K is solved in closed form (adjugate)
    // when positive definite; otherwise the exact fit below.
    const Mat3 M = R.transpose() * A;
    const Vec3 g(M(2, 1) - M(1, 2), M(0, 2) - M(2, 0), M(1, 0) - M(0, 1));
    const double t = M.trace();
    const double k00 = t - M(0, 0), k11 = t - M(1, 1), k22 = t - M(2, 2);
    const double k01 = -0.5 * (M(0, 1) + M(1, 0)), k02 = -0.5 * (M(0, 2) + M(2, 0)), k12 = -0.5 * (M(1, 2) + M(2, 1));
    const double c00 = k11 * k22 - k12 * k12, c01 = k02 * k12 - k01 * k22, c02 = k01 * k12 - k02 * k11;
    const double det = k00 * c00 + k01 * c01 + k02 * c02;
    newton = k00 > 0 && k00 * k11 - k01 * k01 > 0 && det > 1e-12 * scale * scale * scale;
    if (!newton) break;
    const double c11 = k00 * k22 - k02 * k02, c12 = k01 * k02 - k00 * k12, c22 = k00 * k11 - k01 * k01;
    const Vec3 delta = Vec3(c00 * g[0] + c01 * g[1] + c02 * g[2], c01 * g[0] + c11 * g[1] + c12 * g[2],
                            c02 * g[0] + c12 * g[1] + c22 * g[2]) / det;
    // Right-multiply by the Cayley rotation (1, δ/2): by 2·atan(|δ|/2) about δ.
    q = q * Eigen::Quaterniond(1.0, 0.5 * delta.x(), 0.5 * delta.y(), 0.5 * delta.z());
    q.normalize();
    R = q.toRotationMatrix();
    // Newton converges quadratically: after a step of |δ|² < kFitAngle the error is below kFitAngle.
    if (delta.squaredNorm() < kFitAngle) {
      at_optimum = it == 0;  // the last rotation already fitted
      break;
    }
  }
  if (!(alignment(R, A) >= f0) && newton && at_optimum) return;  // round-off: keep the last rotation
  // A fit that did not raise tr(Rᵀ A) (Newton not applicable, far from the optimum, or not finite): the
  // exact fit. Either way the energy never increases.
  if (!newton || !(alignment(R, A) >= f0)) {
    R = best_rotation(A.transpose());
    q = Eigen::Quaterniond(R);
    if (!(alignment(R, A) >= f0)) return;
  }
  rotation_[i] = R;
  quaternion_[i] = q.coeffs();
}

double ArapDeformer::local_step() {
  const auto t0 = std::chrono::steady_clock::now();
  const double* x = x_.data();
  if (options_.energy == ArapEnergy::Spokes) {
    parallel_for_chunks(nv_, [&](long b, long e) {
      for (long i = b; i < e; ++i) {
        const double xi0 = x[3 * i], xi1 = x[3 * i + 1], xi2 = x[3 * i + 2];
        double a00 = 0, a01 = 0, a02 = 0, a10 = 0, a11 = 0, a12 = 0, a20 = 0, a21 = 0, a22 = 0, dsq = 0;
        for (int h = ring_offsets_[i]; h < ring_offsets_[i + 1]; ++h) {
          const double* xj = x + 3 * static_cast<long>(ring_[h]);
          const double* we = ring_edge_.data() + 3 * static_cast<long>(h);
          const double d0 = xi0 - xj[0], d1 = xi1 - xj[1], d2 = xi2 - xj[2];
          a00 += d0 * we[0], a01 += d0 * we[1], a02 += d0 * we[2];
          a10 += d1 * we[0], a11 += d1 * we[1], a12 += d1 * we[2];
          a20 += d2 * we[0], a21 += d2 * we[1], a22 += d2 * we[2];
          dsq += ring_weight_[h] * (d0 * d0 + d1 * d1 + d2 * d2);
        }
        Mat3 A;
        A << a00, a01, a02, a10, a11, a12, a20, a21, a22;  // Σ_j w_ij d_ij e_ijᵀ
        fit_rotation(i, A);
        vertex_energy_[i] = dsq + cell_rest_[i] - 2 * alignment(rotation_[i], A);
      }
    }, kGrain);
  } else {
    // Per face: C_t = Σ_k c_k d_k e_kᵀ and Σ_k c_k |d_k|² (d_k the deformed edge opposite corner k), then
    // per vertex the sums over its faces.
    const long nf = static_cast<long>(face_dsq_.size());
    parallel_for_chunks(nf, [&](long b, long e) {
      for (long f = b; f < e; ++f) {
        const int* v = face_vertex_.data() + 3 * f;
        Mat3 C = Mat3::Zero();
        double dsq = 0;
        for (int k = 0; k < 3; ++k) {
          const double* xa = x + 3 * static_cast<long>(v[(k + 1) % 3]);
          const double* xb = x + 3 * static_cast<long>(v[(k + 2) % 3]);
          const Vec3 d(xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]);
          const Eigen::Map<const Vec3> ce(face_edge_.data() + 9 * f + 3 * k);
          C.noalias() += d * ce.transpose();
          dsq += face_weight_[3 * f + k] * d.squaredNorm();
        }
        Eigen::Map<Mat3>(face_buffer_.data() + 9 * f) = C;
        face_dsq_[f] = dsq;
      }
    }, kGrain);
    parallel_for_chunks(nv_, [&](long b, long e) {
      for (long i = b; i < e; ++i) {
        Mat3 A = Mat3::Zero();
        double dsq = 0;
        for (int c = corner_offsets_[i]; c < corner_offsets_[i + 1]; ++c) {
          const long f = corners_[c] / 3;
          A += Eigen::Map<const Mat3>(face_buffer_.data() + 9 * f);
          dsq += face_dsq_[f];
        }
        fit_rotation(i, A);
        vertex_energy_[i] = dsq + cell_rest_[i] - 2 * alignment(rotation_[i], A);
      }
    }, kGrain);
  }
  double energy = 0;
  for (double e : vertex_energy_) energy += e;
  local_seconds_ += seconds_since(t0);
  return std::max(energy, 0.0);
}

void ArapDeformer::global_step() {
  const auto t0 = std::chrono::steady_clock::now();
  const long nu = static_cast<long>(unknown_.size());
  if (nu == 0) return;
  const double* known = rhs_known_.data();
  double* rhs = rhs_.data();
  if (options_.energy == ArapEnergy::Spokes) {
    // b_i = Σ_j w_ij/2 (R_i + R_j)(p_i − p_j) = ½ R_i Σ_j w_ij e_ij + ½ Σ_j R_j w_ij e_ij.
    parallel_for_chunks(nu, [&](long b, long e) {
      for (long u = b; u < e; ++u) {
        const int i = unknown_[u];
        Vec3 s = rotation_[i] * Eigen::Map<const Vec3>(cell_sum_.data() + 3 * static_cast<long>(i));
        for (int h = ring_offsets_[i]; h < ring_offsets_[i + 1]; ++h)
          s.noalias() += rotation_[ring_[h]] * Eigen::Map<const Vec3>(ring_edge_.data() + 3 * static_cast<long>(h));
        for (int d = 0; d < 3; ++d) rhs[d * nu + u] = known[d * nu + u] + 0.5 * s[d];
      }
    }, kGrain);
  } else {
    // Per face (R_a + R_b + R_c)/3, then b_i = Σ over i's corners of that times s_corner.
    const long nf = static_cast<long>(face_dsq_.size());
    parallel_for_chunks(nf, [&](long b, long e) {
      for (long f = b; f < e; ++f) {
        const int* v = face_vertex_.data() + 3 * f;
        Eigen::Map<Mat3>(face_buffer_.data() + 9 * f) = (rotation_[v[0]] + rotation_[v[1]] + rotation_[v[2]]) / 3.0;
      }
    }, kGrain);
    parallel_for_chunks(nu, [&](long b, long e) {
      for (long u = b; u < e; ++u) {
        const int i = unknown_[u];
        Vec3 s = Vec3::Zero();
        for (int c = corner_offsets_[i]; c < corner_offsets_[i + 1]; ++c) {
          const long fc = corners_[c];
          s.noalias() += Eigen::Map<const Mat3>(face_buffer_.data() + 9 * (fc / 3)) *
                         Eigen::Map<const Vec3>(face_corner_.data() + 3 * fc);
        }
        for (int d = 0; d < 3; ++d) rhs[d * nu + u] = known[d * nu + u] + s[d];
      }
    }, kGrain);
  }
  system_.solver().solve(rhs_, x_unknown_);  // one back-substitution, three columns
  global_seconds_ += seconds_since(t0);
}

void ArapDeformer::scatter(const Eigen::VectorXd& u) {
  const long nu = static_cast<long>(unknown_.size());
  const double* src = u.data();
  double* x = x_.data();
  parallel_for_chunks(nu, [&](long b, long e) {
    for (long k = b; k < e; ++k)
      for (int d = 0; d < 3; ++d) x[3 * static_cast<long>(unknown_[k]) + d] = src[d * nu + k];
  }, 1 << 14);
}

void ArapDeformer::cold_start(const Positions& targets) {
  // Each handle's best rotation from its vertices' rest and target offsets (Kabsch), then per vertex
  // the normalised blend of the handles' quaternions and the identity with the harmonic weights, and one
  // global step with those rotations.
  const int nh = static_cast<int>(handle_quaternion_.size());
  for (int k = 0; k < nh; ++k) {
    Vec3 rest_mean = Vec3::Zero(), target_mean = Vec3::Zero();
    int count = 0;
    for (size_t c = 0; c < constrained_.size(); ++c)
      if (handle_of_constrained_[c] == k)
        rest_mean += local_.to_local(Vec3(rest_.row(constrained_[c]))),
            target_mean += targets.row(c).transpose(), ++count;
    if (count < 2) continue;
    rest_mean /= count, target_mean /= count;
    Mat3 C = Mat3::Zero();
    for (size_t c = 0; c < constrained_.size(); ++c)
      if (handle_of_constrained_[c] == k)
        C.noalias() += (local_.to_local(Vec3(rest_.row(constrained_[c]))) - rest_mean) *
                       (targets.row(c).transpose() - target_mean).transpose();
    Eigen::Quaterniond q(best_rotation(C));
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    handle_quaternion_[k] = q.coeffs();
  }
  parallel_for_chunks(nv_, [&](long b, long e) {
    for (long i = b; i < e; ++i) {
      Eigen::Vector4d q(0, 0, 0, 1);
      for (int k = 0; k < nh; ++k) {
        const double s = std::clamp(handle_field_(i, k), 0.0, 1.0);
        q += s * (handle_quaternion_[k] - Eigen::Vector4d(0, 0, 0, 1));
      }
      q.normalize();
      quaternion_[i] = q;
      rotation_[i] = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).toRotationMatrix();
    }
  }, kGrain);
  global_step();
  u_ = Eigen::Map<const Eigen::VectorXd>(x_unknown_.data(), x_unknown_.size());
  scatter(u_);
}

double ArapDeformer::anderson_step(double energy) {
  // Peng et al. 2018, Algorithm 1 on the fixed point u = G(u) of one local/global iteration: with the
  // residual f = G(u) − u and the differences ΔF, ΔG of the last m residuals and images, the next
  // iterate is G(u) − ΔG θ with θ = argmin |f − ΔF θ|.
  const long n = u_.size();
  const Eigen::Map<const Eigen::VectorXd> g(x_unknown_.data(), n);
  const int m = options_.anderson;
  f_ = g - u_;
  if (has_previous_) {
    const int c = next_column_;
    delta_f_.col(c) = f_ - f_previous_;
    delta_g_.col(c) = g - g_previous_;
    history_ = std::min(history_ + 1, m);
    next_column_ = (c + 1) % m;
    for (int j = 0; j < history_; ++j) normal_(c, j) = normal_(j, c) = delta_f_.col(c).dot(delta_f_.col(j));
  }
  f_previous_ = f_;
  g_previous_ = g;
  has_previous_ = true;
  u_ = g;
  if (history_ > 0) {
    Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 8, 1> rhs(history_);
    for (int j = 0; j < history_; ++j) rhs[j] = delta_f_.col(j).dot(f_);
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 8, 8> A = normal_.topLeftCorner(history_, history_);
    A.diagonal().array() += 1e-12 * A.diagonal().maxCoeff() + std::numeric_limits<double>::min();
    const Eigen::LDLT<decltype(A)> ldlt(A);
    const auto theta = ldlt.solve(rhs).eval();
    if (ldlt.info() == Eigen::Success && theta.allFinite())
      for (int j = 0; j < history_; ++j) u_.noalias() -= theta[j] * delta_g_.col(j);
  }
  scatter(u_);
  const double accelerated = local_step();
  if (accelerated <= energy || history_ == 0) return accelerated;
  // The extrapolation raised the energy: take the plain iterate and start the history afresh.
  u_ = g;
  scatter(u_);
  history_ = next_column_ = 0;
  return local_step();
}

void ArapDeformer::run(const Positions& world_targets, Positions& out) {
  local_seconds_ = global_seconds_ = 0;
  local_.to_local(world_targets, local_targets_);
  const Positions& targets = local_targets_;
  for (size_t c = 0; c < constrained_.size(); ++c) x_.row(constrained_[c]) = targets.row(c);
  // The constrained part of the global step's right-hand side, fixed for the frame: −Q_uk x_k.
  if (!unknown_.empty()) {
    rhs_known_.noalias() = system_.coupling() * targets;
    rhs_known_ *= -1.0;
  }
  const long nu = static_cast<long>(unknown_.size());
  for (long k = 0; k < nu; ++k)
    for (int d = 0; d < 3; ++d) u_[d * nu + k] = x_(unknown_[k], d);
  double energy;
  frame_report_.start = "cold start";
  if (cold_) {
    cold_start(targets);
    energy = local_step();
  } else {
    // The warm start against the cold one: keep the lower energy.
    const double warm = local_step();
    warm_ = u_;
    cold_start(targets);
    energy = local_step();
    if (warm < energy) {
      u_ = warm_;
      scatter(u_);
      energy = local_step();
      frame_report_.start = guess_ ? "initial guess" : "last result";
    }
  }
  cold_ = guess_ = false;
  energies_.clear();
  const double energy_unit = local_.scale * local_.scale;  // energy_history() is in the caller's units
  energies_.push_back(energy * energy_unit);
  history_ = next_column_ = 0;
  has_previous_ = false;
  const double tol = options_.tolerance * diagonal_;
  const Eigen::Map<const Eigen::VectorXd> g(x_unknown_.data(), x_unknown_.size());
  int iterations = 0;
  double step = 0;
  bool converged = nu == 0;
  while (!converged && iterations < options_.max_iterations) {
    global_step();
    ++iterations;
    // The largest vertex move of this iteration.
    step = 0;
    for (long k = 0; k < nu; ++k) {
      const double dx = g[k] - u_[k], dy = g[nu + k] - u_[nu + k], dz = g[2 * nu + k] - u_[2 * nu + k];
      step = std::max(step, dx * dx + dy * dy + dz * dz);
    }
    step = std::sqrt(step);
    converged = tol > 0 && step <= tol;
    if (converged || iterations == options_.max_iterations || options_.anderson == 0) {
      u_ = g;
      scatter(u_);
      energy = local_step();
    } else {
      energy = anderson_step(energy);
    }
    energies_.push_back(energy * energy_unit);
    if (progress_wanted()) {
      char line[128];
      std::snprintf(line, sizeof line, "arap: iteration %d, largest move %.3g of the diagonal", iterations,
                    step / diagonal_);
      progress(line);
    }
  }
  if (tol == 0) converged = true;  // exactly max_iterations were asked for
  frame_report_.iterations = iterations;
  frame_report_.residual = step / diagonal_;
  frame_report_.converged = converged;
  out = x_;
  local_.to_world(out);
  // The constrained vertices exactly where asked (the round trip through the local frame rounds).
  for (size_t c = 0; c < constrained_.size(); ++c) out.row(constrained_[c]) = world_targets.row(c);
}

void ArapDeformer::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  affine_targets(rest_, constrained_, handle_of_constrained_, transforms, targets_);
  run(targets_, out);
}

void ArapDeformer::do_deform_to(const Positions& targets, Positions& out) { run(targets, out); }

void ArapDeformer::do_set_initial_guess(const Positions& X) {
  x_ = local_.to_local(X);
  cold_ = false;
  guess_ = true;
}

void ArapDeformer::do_reset() {
  x_ = local_.to_local(rest_);
  std::fill(rotation_.begin(), rotation_.end(), Mat3::Identity());
  std::fill(quaternion_.begin(), quaternion_.end(), Eigen::Vector4d(0, 0, 0, 1));
  energies_.clear();
  cold_ = true;
  guess_ = false;
}

}  // namespace msd
