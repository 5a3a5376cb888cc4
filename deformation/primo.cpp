#include "msdeform/deformation/primo.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <utility>

#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/rotation.h"

namespace msd {

namespace {

// 2-point Gauss rule on [0, 1]: nodes ½ ± ½/√3, weights ½ each. On the side face (u along the edge, s
// across the thickness, s ∈ [−½, ½]) the four nodes are (u_k, s_l).
const double kGaussOffset = 0.5 / std::sqrt(3.0);

constexpr long kEnergyChunk = 8192;

// Stopping tolerance of the intermediate continuation stages, in bounding-box diagonals.
constexpr double kStageTolerance = 1e-4;

// Marquardt damping μ of (JᵀJ + μ·diag(JᵀJ)): small, because the normal matrix is Laplacian-like: its
// smooth modes (a translation carried along a bar) have eigenvalues ~1e-4–1e-6 of the diagonal, and
// μ = 1e-4 damped them so much that a pure translation took ~100 iterations and the prisms twisted on the
// way. μ grows ×10 per rejected step (up to kMaxAttempts) and shrinks ÷3 per accepted one.
constexpr double kInitialDamping = 1e-8, kMinDamping = 1e-12;
constexpr int kMaxAttempts = 14;
// The first shift of an indefinite exact Hessian, and the largest before Gauss-Newton takes over.
constexpr double kIndefiniteDamping = 1e-3, kMaxExactDamping = 1.0;
// Line search: halvings of the step per damping, and the largest prism turn of a first trial (radians).
constexpr int kLineSearchTrials = 6;
constexpr double kMaxTurn = 0.5;

}  // namespace

void PrimoDeformer::set_max_iterations(int max_iterations) {
  if (max_iterations < 1)
    throw InvalidInput("primo: max_iterations must be >= 1 (got " + std::to_string(max_iterations) + ")");
  options_.max_iterations = max_iterations;
}

PrimoDeformer::PrimoDeformer(PrimoOptions options) : options_(options) {
  if (!std::isfinite(options_.thickness) || !(options_.thickness > 0))
    throw InvalidInput("primo: the thickness must be finite and > 0 (got " +
                       format_number(options_.thickness) + ")");
  set_max_iterations(options_.max_iterations);
  if (!(options_.tolerance >= 0 && options_.tolerance <= 1))  // as --tolerance (above 1: one iteration)
    throw InvalidInput(
        "primo: the tolerance must lie in [0, 1], a fraction of the bounding-box diagonal (got " +
        format_number(options_.tolerance) + ")");
}

DeformerTraits PrimoDeformer::traits() const {
  DeformerTraits t;
  t.solve = DeformerSolve::Iterative;
  t.initial_guess = true;
  t.cotan_laplacian = false;  // prisms on the faces
  return t;
}

Vec3 PrimoDeformer::gauss_point(const Edge& e, int m) const {
  const double u = (m & 1) ? 0.5 + kGaussOffset : 0.5 - kGaussOffset;
  const double s = ((m & 2) ? kGaussOffset : -kGaussOffset) * height_;  // (s_l − ½)·h, s_l ∈ {½ ± ½/√3}
  return (1 - u) * (rest_.row(e.a).transpose() + s * normals_.row(e.a).transpose()) +
         u * (rest_.row(e.b).transpose() + s * normals_.row(e.b).transpose());
}

void PrimoDeformer::prepare_local(const Positions& P, const Faces& F, const Region& region) {
  rest_ = P;
  faces_ = F;
  const int nv = static_cast<int>(P.rows()), nf = static_cast<int>(F.rows());
  normals_ = vertex_normals(P, F);

  // Edges shared by two faces (a non-manifold edge couples every pair of its faces).
  std::vector<std::pair<long long, int>> halfedges;
  halfedges.reserve(3 * static_cast<size_t>(nf));
  double edge_sum = 0;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      edge_sum += (P.row(a) - P.row(b)).norm();
      halfedges.push_back({static_cast<long long>(std::min(a, b)) * nv + std::max(a, b), f});
    }
  height_ = options_.thickness * edge_sum / std::max(1, 3 * nf);
  std::sort(halfedges.begin(), halfedges.end());
  std::vector<double> area(nf);
  double area_sum = 0;
  for (int f = 0; f < nf; ++f) {
    area[f] = 0.5 * (P.row(F(f, 1)) - P.row(F(f, 0))).cross(P.row(F(f, 2)) - P.row(F(f, 0))).norm();
    area_sum += area[f];
  }
  const double min_area = 1e-12 * std::max(area_sum / std::max(nf, 1), 1e-300);  // guards zero-area pairs
  edges_.clear();
  for (size_t s = 0; s < halfedges.size();) {
    size_t e = s;
    while (e < halfedges.size() && halfedges[e].first == halfedges[s].first) ++e;
    const int a = static_cast<int>(halfedges[s].first / nv), b = static_cast<int>(halfedges[s].first % nv);
    const double len2 = (P.row(a) - P.row(b)).squaredNorm();
    for (size_t x = s; x < e; ++x)
      for (size_t y = x + 1; y < e; ++y) {
        const int f = halfedges[x].second, j = halfedges[y].second;
        if (f == j) continue;
        edges_.push_back({a, b, f, j, 0.25 * len2 / std::max(area[f] + area[j], min_area)});
      }
    s = e;
  }
  // Faces → edges, vertices → faces (compressed rows).
  face_edge_offsets_.assign(nf + 1, 0);
  for (const Edge& e : edges_) ++face_edge_offsets_[e.f + 1], ++face_edge_offsets_[e.j + 1];
  for (int f = 0; f < nf; ++f) face_edge_offsets_[f + 1] += face_edge_offsets_[f];
  face_edges_.resize(face_edge_offsets_[nf]);
  {
    std::vector<int> fill(face_edge_offsets_.begin(), face_edge_offsets_.end() - 1);
    for (int e = 0; e < static_cast<int>(edges_.size()); ++e) {
      face_edges_[fill[edges_[e].f]++] = e;
      face_edges_[fill[edges_[e].j]++] = e;
    }
  }
  vertex_face_offsets_.assign(nv + 1, 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++vertex_face_offsets_[F(f, k) + 1];
  for (int v = 0; v < nv; ++v) vertex_face_offsets_[v + 1] += vertex_face_offsets_[v];
  vertex_faces_.resize(vertex_face_offsets_[nv]);
  {
    std::vector<int> fill(vertex_face_offsets_.begin(), vertex_face_offsets_.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) vertex_faces_[fill[F(f, k)]++] = f;
  }

  // Constrained vertices and faces.
  constrained_ = region.constrained_vertices();
  constrained_index_.assign(nv, -1);
  handle_of_.clear();
  for (size_t c = 0; c < constrained_.size(); ++c) {
    constrained_index_[constrained_[c]] = static_cast<int>(c);
    handle_of_.push_back(region.handle_of(constrained_[c]));
  }
  face_is_constrained_.assign(nf, 0);
  constrained_faces_.clear();
  for (int f = 0; f < nf; ++f)
    if (constrained_index_[F(f, 0)] >= 0 && constrained_index_[F(f, 1)] >= 0 && constrained_index_[F(f, 2)] >= 0) {
      face_is_constrained_[f] = 1;
      constrained_faces_.push_back(f);
    }
  {
    std::vector<char> held(region.num_handles(), 0);
    for (int f : constrained_faces_)
      for (int k = 0; k < 3; ++k)
        if (const int h = region.handle_of(F(f, k)); h >= 0) held[h] = 1;
    for (int h = 0; h < region.num_handles(); ++h)
      if (!held[h])
        prepare_warnings_.push_back("primo: handle " + std::to_string(h) +
                                    " contains no face whose three vertices are all constrained, so no prism follows "
                                    "it and it moves only its own vertices; select a handle region of whole faces");
  }
  if (constrained_faces_.empty())
    throw TopologyError("primo: no face has all three vertices fixed or in a handle, so no prism is held; select "
                        "fixed and handle regions that contain whole faces");

  centroids_.resize(nf);
  for (int f = 0; f < nf; ++f) centroids_[f] = (P.row(F(f, 0)) + P.row(F(f, 1)) + P.row(F(f, 2))).transpose() / 3.0;

  // Every free face must reach a constrained face through shared edges, else its motion is undetermined.
  {
    std::vector<char> reached(face_is_constrained_.begin(), face_is_constrained_.end());
    std::vector<int> queue(constrained_faces_.begin(), constrained_faces_.end());
    for (size_t i = 0; i < queue.size(); ++i)
      for (int k = face_edge_offsets_[queue[i]]; k < face_edge_offsets_[queue[i] + 1]; ++k) {
        const Edge& e = edges_[face_edges_[k]];
        for (int g : {e.f, e.j})
          if (!reached[g]) reached[g] = 1, queue.push_back(g);
      }
    for (int f = 0; f < nf; ++f)
      if (!reached[f])
        throw TopologyError("primo: face " + std::to_string(f) +
                            " belongs to a group of free faces that shares no edge with a face whose three vertices "
                            "are all constrained; its prisms' motion is undetermined (extend the fixed or handle region)");
  }

  // A state whose energy is this small is a rigid motion to round-off (Gauss points off by ~1e-13 of the
  // shape's size): nothing is left to minimise, whatever the relative change says.
  double weight_sum = 0;
  for (const Edge& e : edges_) weight_sum += e.w;
  const double size = (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm() + height_;
  energy_floor_ = 1e-26 * weight_sum * size * size;
  diagonal_length_ = bounding_box_diagonal(P);
  if (!(diagonal_length_ > 0)) throw InvalidInput("primo: the mesh has a zero bounding-box diagonal (all vertices coincide)");

  rotation_.resize(nf);
  position_.resize(nf);
  rest_state();
  prepare_newton();
  targets_.resize(constrained_.size(), 3);
  target_rotation_.resize(constrained_faces_.size());
  target_position_.resize(constrained_faces_.size());
  start_rotation_.resize(constrained_faces_.size());
  start_position_.resize(constrained_faces_.size());
  chunk_energy_.assign((edges_.size() + kEnergyChunk - 1) / kEnergyChunk, 0.0);
  energies_.clear();
  energies_.reserve(std::min(options_.max_iterations, 100000) + 1);  // beyond that a frame may allocate
}

void PrimoDeformer::rest_state() {
  for (size_t f = 0; f < rotation_.size(); ++f) {
    rotation_[f].setIdentity();
    position_[f] = centroids_[f];
  }
}

void PrimoDeformer::do_reset() {
  rest_state();
  energies_.clear();
}

void PrimoDeformer::set_initial_guess_local(const Positions& X) {
  // Each free prism: the rigid fit of its six rest corners p ± (h/2)n to the guess's corners X ± (h/2)n'.
  const Positions guess_normals = vertex_normals(X, faces_);
  const long nf = faces_.rows();
  parallel_for_chunks(nf, [&](long b, long e) {
    for (long f = b; f < e; ++f) {
      Vec3 mean = Vec3::Zero();
      for (int k = 0; k < 3; ++k) mean += X.row(faces_(f, k)).transpose();
      mean /= 3.0;
      Mat3 C = Mat3::Zero();
      for (int k = 0; k < 3; ++k) {
        const int v = faces_(f, k);
        const Vec3 p = rest_.row(v).transpose() - centroids_[f], n = 0.5 * height_ * normals_.row(v).transpose();
        const Vec3 x = X.row(v).transpose() - mean, m = 0.5 * height_ * guess_normals.row(v).transpose();
        C += (p + n) * (x + m).transpose() + (p - n) * (x - m).transpose();
      }
      rotation_[f] = best_rotation(C);
      position_[f] = mean;
    }
  }, 2048);
}

void PrimoDeformer::fit_constrained(const Positions& targets) {
  for (size_t i = 0; i < constrained_faces_.size(); ++i) {
    const int f = constrained_faces_[i];
    Vec3 mean = Vec3::Zero();
    for (int k = 0; k < 3; ++k) mean += targets.row(constrained_index_[faces_(f, k)]).transpose();
    mean /= 3.0;
    Mat3 C = Mat3::Zero();
    for (int k = 0; k < 3; ++k) {
      const int v = faces_(f, k);
      C += (rest_.row(v).transpose() - centroids_[f]) * (targets.row(constrained_index_[v]).transpose() - mean).transpose();
    }
    target_rotation_[i] = best_rotation(C);
    target_position_[i] = mean;
  }
}

double PrimoDeformer::energy() {
  const long ne = static_cast<long>(edges_.size());
  double* chunks = chunk_energy_.data();  // one sum per fixed chunk, added in order: deterministic
  parallel_for_chunks(static_cast<long>(chunk_energy_.size()), [&](long cb, long ce) {
    for (long c = cb; c < ce; ++c) {
      double sum = 0;
      for (long i = c * kEnergyChunk; i < std::min(ne, (c + 1) * kEnergyChunk); ++i) {
        const Edge& e = edges_[i];
        double s = 0;
        for (int m = 0; m < 4; ++m) {
          const Vec3 q = gauss_point(e, m);
          s += (rotation_[e.f] * (q - centroids_[e.f]) + position_[e.f] - rotation_[e.j] * (q - centroids_[e.j]) -
                position_[e.j])
                   .squaredNorm();
        }
        sum += e.w * s;
      }
      chunks[c] = sum;
    }
  }, 1);
  double total = 0;
  for (double s : chunk_energy_) total += s;
  return total;
}

void PrimoDeformer::deform_local(const std::vector<Mat4>& transforms, Positions& out) {
  affine_targets(rest_, constrained_, handle_of_, transforms, targets_);
  fit_constrained(targets_);

  // Continuation: the constrained prisms move from their current motion to the target in stages of at
  // most 30° of rotation, each solved from the last; a large edit solved in one go from rest can end in a
  // folded local minimum (the 135° twist does).
  double angle = 0;
  for (size_t i = 0; i < constrained_faces_.size(); ++i) {
    const int f = constrained_faces_[i];
    start_rotation_[i] = rotation_[f];
    start_position_[i] = position_[f];
    angle = std::max(angle, Eigen::AngleAxisd(rotation_[f].transpose() * target_rotation_[i]).angle());
  }
  const int stages = std::max(1, static_cast<int>(std::ceil(angle / (M_PI / 6) - 1e-9)));
  int iterations = 0;
  double change = 0;
  bool converged = false;
  damping_ = kInitialDamping;
  for (int stage = 1; stage <= stages; ++stage) {
    const double t = static_cast<double>(stage) / stages;
    const bool last = stage == stages;
    converged = false;
    for (size_t i = 0; i < constrained_faces_.size(); ++i) {
      const int f = constrained_faces_[i];
      const Eigen::AngleAxisd turn(start_rotation_[i].transpose() * target_rotation_[i]);
      rotation_[f] = last ? target_rotation_[i]
                          : Mat3(start_rotation_[i] * Eigen::AngleAxisd(t * turn.angle(), turn.axis()).toRotationMatrix());
      position_[f] = last ? target_position_[i] : Vec3((1 - t) * start_position_[i] + t * target_position_[i]);
    }
    // Intermediate stages only need a nearby start for the next one. The test is on the step (the largest
    // move of a prism corner, in bounding-box diagonals), not on the relative energy change: near a rigid
    // motion E → 0 and its relative change is round-off, while the shape can still be far from converged.
    const double tolerance = (last ? options_.tolerance : std::max(options_.tolerance, kStageTolerance)) * diagonal_length_;
    double e_prev = energy();
    if (last) {
      energies_.clear();
      energies_.push_back(e_prev);
    }
    // An intermediate stage gets at most max_iterations / (2 · stages) iterations, so the last one (the
    // target constraints) always has at least half of them.
    const int stage_cap = last ? options_.max_iterations - iterations
                               : std::max(1, options_.max_iterations / (2 * stages));
    int stage_iterations = 0;
    while (iterations < options_.max_iterations && stage_iterations < stage_cap) {
      double e = e_prev, step = 0;
      const bool moved = newton_step(e_prev, e, step);  // E and the state are kept when no step lowers E
      ++iterations;
      ++stage_iterations;
      if (last) energies_.push_back(e);
      change = step / diagonal_length_;
      e_prev = e;
      if (progress_wanted()) {
        char line[128];
        std::snprintf(line, sizeof line, "primo: iteration %d, largest move %.3g of the diagonal", iterations, change);
        progress(line);
      }
      // A step no damping can make lower E, or E at the round-off floor of a rigid motion: a minimum.
      if (tolerance > 0 && (!moved || e <= energy_floor_ || step <= tolerance)) {
        converged = true;
        break;
      }
    }
    if (last) converged = converged || (options_.tolerance == 0 && stage_iterations > 0);
  }

  // Vertices: the mean of the incident prisms' copies; constrained vertices exactly at their targets.
  const long nv = rest_.rows();
  parallel_for_chunks(nv, [&](long b, long e) {
    for (long v = b; v < e; ++v) {
      const int c = constrained_index_[v];
      if (c >= 0) {
        out.row(v) = targets_.row(c);
        continue;
      }
      const int begin = vertex_face_offsets_[v], end = vertex_face_offsets_[v + 1];
      if (begin == end) {
        out.row(v) = rest_.row(v);
        continue;
      }
      Vec3 sum = Vec3::Zero();
      const Vec3 p = rest_.row(v).transpose();
      for (int i = begin; i < end; ++i) {
        const int f = vertex_faces_[i];
        sum += rotation_[f] * (p - centroids_[f]) + position_[f];
      }
      out.row(v) = (sum / (end - begin)).transpose();
    }
  }, 4096);

  frame_report_.iterations = iterations;
  frame_report_.residual = change;
  frame_report_.converged = converged;
}

}  // namespace msd

namespace msd {

namespace {

// [r]× such that [r]× v = r × v.
Mat3 cross_matrix(const Vec3& r) {
  Mat3 S;
  S << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  return S;
}

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

}  // namespace

void PrimoDeformer::prepare_newton() {
  const int nf = static_cast<int>(faces_.rows());
  free_faces_.clear();
  free_index_.assign(nf, -1);
  for (int f = 0; f < nf; ++f)
    if (!face_is_constrained_[f]) {
      free_index_[f] = static_cast<int>(free_faces_.size());
      free_faces_.push_back(f);
    }
  const int n = static_cast<int>(free_faces_.size());
  // Entry ids: 21 for the lower triangle of each diagonal block, then 36 per edge between free faces
  // (stored below the diagonal, in the block row of the face with the larger index).
  diag_entry_.resize(n);
  int id = 0;
  std::vector<Triplet> pattern;
  for (int I = 0; I < n; ++I) {
    diag_entry_[I] = id;
    for (int c = 0; c < 6; ++c)
      for (int r = c; r < 6; ++r) pattern.emplace_back(6 * I + r, 6 * I + c, ++id);
  }
  edge_entry_.assign(edges_.size(), -1);
  for (size_t e = 0; e < edges_.size(); ++e) {
    const int A = free_index_[edges_[e].f], B = free_index_[edges_[e].j];
    if (A < 0 || B < 0) continue;
    edge_entry_[e] = id;
    const int hi = std::max(A, B), lo = std::min(A, B);
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) pattern.emplace_back(6 * hi + r, 6 * lo + c, ++id);
  }
  hessian_.resize(6 * n, 6 * n);
  hessian_.setFromTriplets(pattern.begin(), pattern.end());  // values are entry ids + 1 (no duplicates)
  entry_position_.assign(id, -1);
  for (Eigen::Index k = 0; k < hessian_.nonZeros(); ++k)
    entry_position_[static_cast<int>(hessian_.valuePtr()[k]) - 1] = static_cast<int>(k);
  diagonal_.assign(6 * n, 0.0);
  gradient_.resize(6 * n, 1);
  step_.resize(6 * n, 1);
  move_.assign(n, 0.0);
  rotation_block_.resize(n);
  second_order_.resize(n);
  newton_solver_ = SparseSPDSolver();
  saved_rotation_.resize(nf);
  saved_position_.resize(nf);
}

void PrimoDeformer::apply_step(double alpha) {
  parallel_for_chunks(static_cast<long>(free_faces_.size()), [&](long b, long e) {
    for (long I = b; I < e; ++I) {
      const int f = free_faces_[I];
      const Vec3 w = alpha * step_.middleRows<3>(6 * I);
      const double angle = w.norm();
      rotation_[f] = angle > 0 ? Mat3(Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() * saved_rotation_[f])
                               : saved_rotation_[f];
      position_[f] = saved_position_[f] + alpha * step_.middleRows<3>(6 * I + 3);
      // The step's largest move of the prism's copies of its face's vertices (squared).
      double move = 0;
      for (int k = 0; k < 3; ++k) {
        const Vec3 r = rest_.row(faces_(f, k)).transpose() - centroids_[f];
        move = std::max(move, ((rotation_[f] - saved_rotation_[f]) * r + position_[f] - saved_position_[f]).squaredNorm());
      }
      move_[I] = move;
    }
  }, 4096);
}

// One Levenberg–Marquardt step on E over the free prisms' motions x = exp([ω]×) R (q − c) + g + δ:
// residuals d_m = x_f(q_m) − x_j(q_m), Jacobians J = [−[r]×, I] (r = R (q − c)), normal equations
// (JᵀWJ + μ·diag(JᵀWJ)) ξ = −JᵀWd. Accepted only if E decreases; otherwise μ grows and the state is kept.
bool PrimoDeformer::newton_step(double energy_now, double& energy_after, double& step_length) {
  const int n = static_cast<int>(free_faces_.size());
  double* values = hessian_.valuePtr();
  // Diagonal blocks and gradient, per free face.
  parallel_for_chunks(n, [&](long b, long e) {
    for (long I = b; I < e; ++I) {
      const int f = free_faces_[I];
      Mat6 H = Mat6::Zero();
      Vec6 g = Vec6::Zero();
      Mat3 second = Mat3::Zero();
      for (int k = face_edge_offsets_[f]; k < face_edge_offsets_[f + 1]; ++k) {
        const Edge& edge = edges_[face_edges_[k]];
        const int j = edge.f == f ? edge.j : edge.f;
        for (int m = 0; m < 4; ++m) {
          const Vec3 q = gauss_point(edge, m);
          const Vec3 r = rotation_[f] * (q - centroids_[f]);
          const Vec3 d = r + position_[f] - rotation_[j] * (q - centroids_[j]) - position_[j];
          const Mat3 S = cross_matrix(r);
          H.topLeftCorner<3, 3>() += edge.w * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
          H.topRightCorner<3, 3>() += edge.w * S;
          H.bottomRightCorner<3, 3>().diagonal().array() += edge.w;
          // The second-order term d·∇²d of the exact Hessian: exp([ω]×) r = r + ω×r + ½ ω×(ω×r) + …,
          // so ∂²(½|d|²)/∂ω² gains sym(r dᵀ) − (r·d) I (only the rotation block of the own prism).
          second += edge.w * (0.5 * (r * d.transpose() + d * r.transpose()) - r.dot(d) * Mat3::Identity());
          g.head<3>() += edge.w * r.cross(d);
          g.tail<3>() += edge.w * d;
        }
      }
      H.bottomLeftCorner<3, 3>() = H.topRightCorner<3, 3>().transpose();
      int id = diag_entry_[I];
      for (int c = 0; c < 6; ++c)
        for (int r = c; r < 6; ++r) values[entry_position_[id++]] = H(r, c);
      for (int r = 0; r < 6; ++r) diagonal_[6 * I + r] = H(r, r);
      gradient_.middleRows<6>(6 * I) = -g;
      rotation_block_[I] = H.topLeftCorner<3, 3>();
      second_order_[I] = second;
    }
  }, 1024);
  // Off-diagonal blocks, per edge between free faces: −w Σ_m J_fᵀ J_j.
  parallel_for_chunks(static_cast<long>(edges_.size()), [&](long b, long e) {
    for (long x = b; x < e; ++x) {
      if (edge_entry_[x] < 0) continue;
      const Edge& edge = edges_[x];
      int f = edge.f, j = edge.j;
      if (free_index_[f] < free_index_[j]) std::swap(f, j);  // block row of the larger index
      Mat6 H = Mat6::Zero();
      for (int m = 0; m < 4; ++m) {
        const Vec3 q = gauss_point(edge, m);
        const Mat3 Sf = cross_matrix(rotation_[f] * (q - centroids_[f]));
        const Mat3 Sj = cross_matrix(rotation_[j] * (q - centroids_[j]));
        H.topLeftCorner<3, 3>() -= Sf * Sj;
        H.topRightCorner<3, 3>() += Sf;
        H.bottomLeftCorner<3, 3>() -= Sj;
        H.bottomRightCorner<3, 3>().diagonal().array() += 1;
      }
      H *= -edge.w;
      int id = edge_entry_[x];
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) values[entry_position_[id++]] = H(r, c);
    }
  }, 4096);
  std::copy(rotation_.begin(), rotation_.end(), saved_rotation_.begin());
  std::copy(position_.begin(), position_.end(), saved_position_.begin());
  // Newton first (the exact Hessian converges where Gauss-Newton crawls: the residuals of a stretched
  // edit are not small); when that matrix is not positive definite, Gauss-Newton (JᵀJ is).
  bool exact = true;
  double mean_diagonal = 0;
  for (double v : diagonal_) mean_diagonal += v;
  mean_diagonal /= std::max<size_t>(diagonal_.size(), 1);
  for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
    // Rotation blocks (exact or Gauss-Newton) and Marquardt damping μ·diag(JᵀJ) of the diagonal (a small
    // floor keeps a zero-curvature direction solvable).
    parallel_for_chunks(n, [&](long b, long e) {
      for (long I = b; I < e; ++I) {
        int id = diag_entry_[I];
        for (int c = 0; c < 6; ++c)
          for (int r = c; r < 6; ++r, ++id) {
            if (r < 3) values[entry_position_[id]] = rotation_block_[I](r, c) + (exact ? second_order_[I](r, c) : 0.0);
            if (r == c)
              values[entry_position_[id]] = (r < 3 ? values[entry_position_[id]] : diagonal_[6 * I + r]) +
                                            damping_ * diagonal_[6 * I + r] + 1e-12 * mean_diagonal;
          }
      }
    }, 4096);
    try {
      if (newton_solver_.factored())
        newton_solver_.refactor(hessian_);
      else
        newton_solver_.factor(hessian_);
    } catch (const SolverError&) {
      // Not positive definite: shift the exact Hessian by μ·diag(JᵀJ) until it is (a buckling edit crosses
      // regions of negative curvature, where Gauss-Newton crawls), and fall back to Gauss-Newton once the
      // shift dominates.
      damping_ = std::max(10 * damping_, kIndefiniteDamping);
      if (exact && damping_ > kMaxExactDamping) exact = false, damping_ = kInitialDamping;
      continue;
    }
    newton_solver_.solve(gradient_, step_);
    // Backtracking along the Gauss-Newton direction: a line search costs energy evaluations only, a
    // larger damping a refactorisation. The first trial turns no prism by more than kMaxTurn.
    double largest_turn = 0;
    for (int I = 0; I < n; ++I) largest_turn = std::max(largest_turn, step_.middleRows<3>(6 * I).norm());
    double alpha = largest_turn > kMaxTurn ? kMaxTurn / largest_turn : 1.0;
    for (int trial = 0; trial < kLineSearchTrials; ++trial, alpha *= 0.5) {
      apply_step(alpha);
      energy_after = energy();
      if (energy_after <= energy_now) {
        if (trial == 0) damping_ = std::max(damping_ / 3, kMinDamping);
        double move = 0;
        for (double m : move_) move = std::max(move, m);
        step_length = std::sqrt(move);
        return true;
      }
    }
    damping_ *= 10;
    std::copy(saved_rotation_.begin(), saved_rotation_.end(), rotation_.begin());
    std::copy(saved_position_.begin(), saved_position_.end(), position_.begin());
  }
  energy_after = energy_now;
  step_length = 0;
  return false;
}

}  // namespace msd
