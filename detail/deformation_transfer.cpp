#include "msdeform/detail/deformation_transfer.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <numeric>
#include <string>
#include <utility>

#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/vector_kernels.h"
#include "msdeform/detail/phong.h"

namespace msd {
namespace {

using RowMat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

// A vertex of S' farther than this many times (diagonal of the deformed base and anchors + diagonal of
// S ∪ B) outside the deformed base's bounding box is not a transferred detail but a blown-up solve.
// Legitimate results stay within about one detail size of B'; 2 leaves room for stretching edits.
constexpr double kResultBound = 2;

// The box of a point set, grown by other points.
struct Box {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  void add(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // Grown by the rows of P shifted by `shift`, in one pass on both cores. Returns whether every coordinate
  // of P is finite (checked in the same pass; the box is meaningless otherwise).
  bool add(const Positions& P, const Eigen::RowVector3d& shift = Eigen::RowVector3d::Zero()) {
    std::mutex mutex;
    std::atomic<bool> finite{true};
    const long n = static_cast<long>(P.rows());
    parallel_for_chunks(
        n,
        [&](long begin, long end) {
          // Column by column, each read from the cache after the first pass (a chunk's column fits it).
          Box chunk;
          for (int c = 0; c < 3; ++c) {
            const double* x = P.data() + c * n + begin;
            if (!all_finite(x, end - begin)) finite = false;
            const Eigen::Map<const Eigen::ArrayXd> column(x, end - begin);
            chunk.lo[c] = column.minCoeff() + shift[c];
            chunk.hi[c] = column.maxCoeff() + shift[c];
          }
          std::lock_guard<std::mutex> lock(mutex);
          add(chunk.lo);
          add(chunk.hi);
        },
        1 << 16);
    return finite;
  }
  // Whether p is within √limit2 of the box: a squared distance with no root (false for a non-finite p).
  bool near(const Vec3& p, double limit2) const {
    return (p - p.cwiseMax(lo).cwiseMin(hi)).squaredNorm() < limit2;
  }
  // check_result()'s bound on the distance of S' from the box of B' and the Dirichlet values.
  double result_limit(double rest_extent) const { return kResultBound * (diagonal() + rest_extent); }
  // Norms that do not overflow for coordinates near DBL_MAX (a finite B' can have them).
  double diagonal() const { return (hi - lo).stableNorm(); }
  double distance(const Vec3& p) const {
    const Vec3 outside = p - p.cwiseMax(lo).cwiseMin(hi);
    const double d = outside.norm();
    return std::isfinite(d) ? d : outside.stableNorm();
  }
};

std::string format_point(const Vec3& p) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.6g, %.6g, %.6g)", p.x(), p.y(), p.z());
  return text;
}

// The third column n / √‖n‖ of a triangle's frame (n = (b − a) × (c − a)); zero for a zero normal.
inline Vec3 scaled_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0 ? Vec3(n / std::sqrt(len)) : Vec3::Zero();
}

#if MSD_HAVE_AVX2_KERNELS
// scaled_normal() of the triangles corners[begin .. end) into rows of out (3 per row), four at a time with
// its operations in each lane: the same bits. The scalar loop waited on its two square roots and three
// divisions (1M lift: a 1.3M-triangle pass in 4.4 ms).
MSD_AVX2 void scaled_normals_x4(const phong::Columns& X, const std::array<int, 3>* corners, long begin,
                                long end, double* out) {
  const __m256d zero = _mm256_setzero_pd();
  long k = begin;
  for (; k + 4 <= end; k += 4) {
    int index[3][4];  // corner c of the four triangles
    for (int i = 0; i < 4; ++i)
      for (int c = 0; c < 3; ++c) index[c][i] = corners[k + i][c];
    const __m256d ax = gather(X.x, index[0]), ay = gather(X.y, index[0]), az = gather(X.z, index[0]);
    const __m256d ex = _mm256_sub_pd(gather(X.x, index[1]), ax),
                  ey = _mm256_sub_pd(gather(X.y, index[1]), ay),
                  ez = _mm256_sub_pd(gather(X.z, index[1]), az);
    const __m256d gx = _mm256_sub_pd(gather(X.x, index[2]), ax),
                  gy = _mm256_sub_pd(gather(X.y, index[2]), ay),
                  gz = _mm256_sub_pd(gather(X.z, index[2]), az);
    __m256d nx, ny, nz;
    cross_x4(ex, ey, ez, gx, gy, gz, nx, ny, nz);
    const __m256d length = _mm256_sqrt_pd(square_sum_x4(nx, ny, nz));
    const __m256d root = _mm256_sqrt_pd(length), positive = _mm256_cmp_pd(length, zero, _CMP_GT_OQ);
    alignas(32) double x[4], y[4], z[4];
    _mm256_store_pd(x, _mm256_and_pd(positive, _mm256_div_pd(nx, root)));
    _mm256_store_pd(y, _mm256_and_pd(positive, _mm256_div_pd(ny, root)));
    _mm256_store_pd(z, _mm256_and_pd(positive, _mm256_div_pd(nz, root)));
    for (int i = 0; i < 4; ++i) {
      double* row = out + 3 * (k + i);
      row[0] = x[i], row[1] = y[i], row[2] = z[i];
    }
  }
  for (; k < end; ++k)
    Eigen::Map<Eigen::RowVector3d>(out + 3 * k) =
        scaled_normal(X.row(corners[k][0]), X.row(corners[k][1]), X.row(corners[k][2])).transpose();
}
#endif

// Sumner & Popović's frame [e1, e2, n / √‖n‖] of a triangle (columns).
Mat3 triangle_frame(const Vec3& a, const Vec3& b, const Vec3& c) {
  Mat3 V;
  V.col(0) = b - a;
  V.col(1) = c - a;
  V.col(2) = scaled_normal(a, b, c);
  return V;
}

int find_root(std::vector<int>& parent, int v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

DeformationTransfer::DeformationTransfer(const NormalDisplacementOptions& normal_options)
    : normal_(normal_options) {}

void DeformationTransfer::encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) {
  const char* where = "DeformationTransfer::encode";
  const auto t0 = std::chrono::steady_clock::now();
  check_faces(Fs, S.rows(), where, "S");
  check_faces(Fb, B.rows(), where, "B");
  check_finite(S, where, "S");
  check_finite(B, where, "B");
  const long ns = static_cast<long>(S.rows()), nfs = static_cast<long>(Fs.rows());
  const long nb = static_cast<long>(B.rows()), nfb = static_cast<long>(Fb.rows());
  std::vector<int> anchors = anchors_;
  for (int a : anchors)
    if (a < 0 || a >= ns)
      throw InvalidInput(std::string(where) + ": anchor vertex " + std::to_string(a) + " out of range [0, " +
                         std::to_string(ns) + ")");
  const std::vector<char> placed = placed_mask(ns, where);  // held where the caller writes them: anchors too
  for (long v = 0; v < ns; ++v)
    if (placed[v]) anchors.push_back(static_cast<int>(v));
  std::sort(anchors.begin(), anchors.end());
  anchors.erase(std::unique(anchors.begin(), anchors.end()), anchors.end());

  encoded_ = false;  // stays so if anything below throws
  Report report;
  num_base_vertices_ = static_cast<int>(nb);

  // Frames of the base triangles. A triangle that cotan_laplacian() leaves out (degenerate) or clamps (a
  // needle: some |cot| > kMaxCotangent) has a frame whose inverse amplifies the rounding of B' by up to
  // its cotangent (and, for the normal column, by 1/√area): it gets no frame of its own and borrows the
  // gradient of the nearest usable face (multi-source breadth-first search over faces sharing a vertex).
  using FaceMatrices = Eigen::Matrix<double, Eigen::Dynamic, 9, Eigen::RowMajor>;
  FaceMatrices frame_inverse(nfb, 9);  // V⁻¹ row-major, for usable faces
  frame_face_.setConstant(nfb, -1);
  std::vector<char> usable(nfb, 0), base_degenerate(nfb, 0);
  parallel_for_chunks(nfb, [&](long begin, long end) {
    for (long f = begin; f < end; ++f) {
      const Vec3 a = B.row(Fb(f, 0)), b = B.row(Fb(f, 1)), c = B.row(Fb(f, 2));
      const TriangleCotangents shape = triangle_cotangents(a, b, c);
      base_degenerate[f] = shape.degenerate;
      if (shape.degenerate || shape.needle_corners > 0) continue;
      const RowMat3 inverse = triangle_frame(a, b, c).inverse();
      if (!inverse.allFinite()) continue;
      frame_inverse.row(f) = Eigen::Map<const Eigen::Matrix<double, 1, 9>>(inverse.data());
      usable[f] = 1;
    }
  });
  for (long f = 0; f < nfb; ++f) {
    report.degenerate_base_faces += base_degenerate[f];
    report.needle_base_faces += !usable[f] && !base_degenerate[f];
  }
  {
    const VertexFaces star = vertex_faces(Fb, static_cast<int>(nb));
    const std::vector<int>&offsets = star.offsets, &around = star.faces;
    std::vector<int> queue;
    queue.reserve(nfb);
    for (long f = 0; f < nfb; ++f)
      if (usable[f]) {
        frame_face_[f] = static_cast<int>(f);
        queue.push_back(static_cast<int>(f));
      }
    for (size_t q = 0; q < queue.size() && static_cast<long>(queue.size()) < nfb; ++q) {
      const int f = queue[q];
      for (int k = 0; k < 3; ++k) {
        const int v = Fb(f, k);
        for (int i = offsets[v]; i < offsets[v + 1]; ++i)
          if (frame_face_[around[i]] < 0) {
            frame_face_[around[i]] = frame_face_[f];
            queue.push_back(around[i]);
          }
      }
    }
  }

  // Triangle correspondence S → B.
  report.identical_connectivity = ns == nb && nfs == nfb && (Fs.array() == Fb.array()).all();
  source_face_.resize(nfs);
  if (report.identical_connectivity) {
    std::iota(source_face_.data(), source_face_.data() + nfs, 0);
  } else {
    Positions centroids(nfs, 3);
    for (long t = 0; t < nfs; ++t)
      centroids.row(t) = (S.row(Fs(t, 0)) + S.row(Fs(t, 1)) + S.row(Fs(t, 2))) / 3;
    NormalDisplacements centroid_feet(normal_.options());
    centroid_feet.encode(centroids, Faces(), B, Fb);
    source_face_ = centroid_feet.base_faces();
  }
  for (long t = 0; t < nfs; ++t) {
    source_face_[t] = frame_face_[source_face_[t]];
    if (source_face_[t] < 0) ++report.unreachable_faces;
  }

  // The Poisson matrix Q = Σ_t Q_t and the per-corner vectors (Q_t S)_k, with Q_t = A_t ∇φ_a·∇φ_b = −W_t the
  // cotan weights of S's triangle t under cotan_laplacian()'s rule: degenerate triangles are left out
  // (their energy is 0 whatever x does), and a needle's cotangents are bounded by kMaxCotangent, all three
  // scaled together (TriangleCotangents::weight: its weight in the energy, not its shape), so that Q_t
  // stays positive semi-definite and Q factors.
  // (Q_t S)_k = Σ_m w_km (s_k − s_m) uses edge vectors only, so it does not depend on where S sits.
  std::vector<Triplet> triplets;
  triplets.reserve(12 * nfs);
  FaceMatrices face_q = FaceMatrices::Zero(nfs, 9);
  std::vector<int> parent(ns);
  std::iota(parent.begin(), parent.end(), 0);
  for (long t = 0; t < nfs; ++t) {
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = S.row(Fs(t, k));
    const TriangleCotangents shape = triangle_cotangents(p[0], p[1], p[2]);
    if (shape.degenerate) {
      ++report.degenerate_faces;
      continue;
    }
    report.clamped_cotangents += shape.needle_corners;
    Vec3 q[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    for (int k = 0; k < 3; ++k) {
      // The angle at corner k weighs the opposite edge (i, j).
      const int a = (k + 1) % 3, b = (k + 2) % 3, i = Fs(t, a), j = Fs(t, b);
      const double w = 0.5 * shape.weight[k];
      triplets.emplace_back(i, j, -w);
      triplets.emplace_back(j, i, -w);
      triplets.emplace_back(i, i, w);
      triplets.emplace_back(j, j, w);
      const Vec3 edge = p[a] - p[b];
      q[a] += w * edge;
      q[b] -= w * edge;
    }
    for (int k = 0; k < 3; ++k) face_q.block<1, 3>(t, 3 * k) = q[k].transpose();
    for (int k = 1; k < 3; ++k) {
      const int a = find_root(parent, Fs(t, 0)), b = find_root(parent, Fs(t, k));
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  SparseMatrix Q(ns, ns);
  Q.setFromTriplets(triplets.begin(), triplets.end());
  triplets = std::vector<Triplet>();

  // Constraints: the anchors, plus the lowest vertex of every component (over non-degenerate faces)
  // without one. (A face with a repeated vertex is degenerate, q = 0, so the corner lookup below may
  // pick either of its corners for that vertex.)
  std::vector<char> component_anchored(ns, 0);
  for (int a : anchors) component_anchored[find_root(parent, a)] = 1;
  std::vector<int> known = anchors;
  for (long v = 0; v < ns; ++v) {
    const int root = find_root(parent, static_cast<int>(v));
    if (!component_anchored[root]) {
      component_anchored[root] = 1;
      known.push_back(static_cast<int>(v));
      report.pinned_vertices.push_back(static_cast<int>(v));
    }
  }
  std::vector<char> is_known(ns, 0);
  for (int v : known) is_known[v] = 1;

  // The right-hand side's weights, by row of the reduced system (ConstrainedQuadratic orders the unknowns
  // ascending), for a race-free right-hand side row by row. G_t q = V' (V⁻¹ q): each corner's u = V⁻¹ q of
  // the base face its triangle takes, spread over that face's corners and its slot (q itself where the
  // triangle has no base face: G = I). The base faces the rows read get frame slots in the order the rows
  // first read them, so the right-hand side reads the normals nearly in the order a frame writes them.
  {
    const VertexFaces corners = vertex_faces(Fs, static_cast<int>(ns));
    for (auto* v : {&base_offsets_, &normal_offsets_}) v->assign(1, 0);
    for (auto* v : {&base_vertex_, &normal_slot_}) v->clear();
    for (auto* v : {&base_weight_, &normal_weight_}) v->clear();
    identity_rows_.clear();
    slot_corners_.clear();
    std::vector<int> slot(nfb, -1);
    std::vector<std::pair<int, double>> base_terms, normal_terms;
    // Appends the terms of one row to a CSR, merged by index (sorted: the first is the row's reference).
    const auto append = [](std::vector<std::pair<int, double>>& terms, std::vector<int>& offsets,
                           std::vector<int>& index, std::vector<double>& weight) {
      std::sort(terms.begin(), terms.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      for (size_t i = 0; i < terms.size(); ++i) {
        if (i > 0 && terms[i].first == terms[i - 1].first) {
          weight.back() += terms[i].second;
          continue;
        }
        index.push_back(terms[i].first);
        weight.push_back(terms[i].second);
      }
      offsets.push_back(static_cast<int>(index.size()));
    };
    int r = 0;
    for (long v = 0; v < ns; ++v) {
      if (is_known[v]) continue;
      base_terms.clear();
      normal_terms.clear();
      Vec3 identity = Vec3::Zero();
      for (int j = corners.offsets[v]; j < corners.offsets[v + 1]; ++j) {
        const int t = corners.faces[j], s = source_face_[t];
        const int k = Fs(t, 0) == v ? 0 : Fs(t, 1) == v ? 1 : 2;
        const Vec3 q = face_q.block<1, 3>(t, 3 * k).transpose();
        if (s < 0) {
          identity += q;
          continue;
        }
        const Vec3 u = Eigen::Map<const RowMat3>(frame_inverse.row(s).data()) * q;
        if (slot[s] < 0) {
          slot[s] = static_cast<int>(slot_corners_.size());
          slot_corners_.push_back({Fb(s, 0), Fb(s, 1), Fb(s, 2)});
        }
        base_terms.emplace_back(Fb(s, 0), -(u[0] + u[1]));
        base_terms.emplace_back(Fb(s, 1), u[0]);
        base_terms.emplace_back(Fb(s, 2), u[1]);
        normal_terms.emplace_back(slot[s], u[2]);
      }
      append(base_terms, base_offsets_, base_vertex_, base_weight_);
      append(normal_terms, normal_offsets_, normal_slot_, normal_weight_);
      if (identity != Vec3::Zero()) identity_rows_.emplace_back(r, identity);
      ++r;
    }
  }
  frame_inverse = FaceMatrices();
  face_q = FaceMatrices();

  system_.prepare(std::move(Q), known);

  // Where each row of the reduced system sits in its solver's order (SparseSPDSolver::solve_ordered()): a
  // frame writes row r of the right-hand side straight there and reads S' from there, in the mesh's order
  // (no permutation passes). The coupling Q(unknown, known) by row, for the right-hand side's pass.
  {
    const std::vector<int>& order = system_.solver().ordering();
    solve_row_.resize(order.size());
    for (size_t i = 0; i < order.size(); ++i) solve_row_[order[i]] = static_cast<int>(i);
    using RowMajorSparse = Eigen::SparseMatrix<double, Eigen::RowMajor>;
    const RowMajorSparse coupling = system_.coupling();
    coupling_offsets_.assign(coupling.outerIndexPtr(), coupling.outerIndexPtr() + coupling.rows() + 1);
    coupling_known_.assign(coupling.innerIndexPtr(), coupling.innerIndexPtr() + coupling.nonZeros());
    coupling_weight_.assign(coupling.valuePtr(), coupling.valuePtr() + coupling.nonZeros());
  }

  // The Dirichlet values: the rows the caller places (placed_vertices()) as it wrote them, the other
  // constrained vertices' normal-displacement reconstruction. normal_ reconstructs only those (every other
  // vertex is placed by the solve or by the caller), with B' normals only where they read them.
  {
    std::vector<char> left = placed;  // by the caller, then by the solve
    for (int v : system_.unknown()) left[v] = 1;
    std::vector<int> left_vertices;
    for (long v = 0; v < ns; ++v)
      if (left[v]) left_vertices.push_back(static_cast<int>(v));
    normal_.set_placed_vertices(std::move(left_vertices));
  }
  normal_.encode(S, Fs, B, Fb);

  slot_normal_.setZero(static_cast<long>(slot_corners_.size()), 3);
  ordered_.setZero(static_cast<long>(solve_row_.size()), 4);
  known_values_.resize(known.size(), 3);
  Box rest;
  rest.add(S);
  rest.add(B);
  rest_extent_ = rest.diagonal();
  report.factor_seconds = seconds_since(t0);
  report_ = std::move(report);
  num_vertices_ = ns;
  encoded_ = true;
}

void DeformationTransfer::reconstruct(const Positions& B_deformed, Positions& out) {
  const auto t0 = std::chrono::steady_clock::now();
  const char* where = "DeformationTransfer::reconstruct";
  if (!encoded_) throw UsageError(std::string(where) + ": called before encode()");
  check_not_aliased(B_deformed, out, where);
  if (B_deformed.rows() != num_base_vertices_)
    throw UsageError(std::string(where) + ": deformed base has " + std::to_string(B_deformed.rows()) +
                     " vertices, the encoded base had " + std::to_string(num_base_vertices_));
  Box box;  // of B' (checked finite in the same pass), then grown by the Dirichlet values: the result bound
  if (!box.add(B_deformed))
    check_finite(B_deformed, where, "the deformed base");  // throws, naming the vertex

  // The scaled normals ñ' of the base faces the unknown vertices' triangles read: the part of their frames
  // V' that is not linear in B' (G = V' V⁻¹, with V⁻¹ already folded into the right-hand side's weights).
  const phong::Columns Bc(B_deformed);
  parallel_for_chunks(static_cast<long>(slot_corners_.size()), [&](long begin, long end) {
#if MSD_HAVE_AVX2_KERNELS
    if (cpu_has_avx2()) return scaled_normals_x4(Bc, slot_corners_.data(), begin, end, slot_normal_.data());
#endif
    for (long k = begin; k < end; ++k) {
      const std::array<int, 3>& f = slot_corners_[k];
      slot_normal_.row(k) = scaled_normal(Bc.row(f[0]), Bc.row(f[1]), Bc.row(f[2]));
    }
  });

  // Dirichlet values: the placed rows as the caller wrote them, the normal-displacement reconstruction
  // b' + h n' of the other constrained vertices written into their rows of out.
  size_output(out, num_vertices_, where);
  normal_.reconstruct(B_deformed, out);
  const std::vector<int>& known = system_.known();
  parallel_for_chunks(static_cast<long>(known.size()), [&](long begin, long end) {
    for (long k = begin; k < end; ++k) known_values_.row(k) = out.row(known[k]);
  });
  // Solve for x − c with c the first Dirichlet value: Q's rows sum to zero, so the shift changes only the
  // known values, and the solve's rounding is relative to the size of S' rather than to its distance from
  // the origin.
  const Eigen::RowVector3d centre =
      known_values_.rows() > 0 ? Eigen::RowVector3d(known_values_.row(0)) : Eigen::RowVector3d::Zero();
  known_values_.rowwise() -= centre;

  // Reduced right-hand side Q_uu x_u = f_u − Q_uk x_k, f_i = Σ G_t (Q_t S)_k = Σ V'_t u_k over the corners
  // at vertex i (expanded over B' and ñ': base_weight_), each row written where the solver takes it.
  const std::vector<int>& unknown = system_.unknown();
  const long nu = static_cast<long>(unknown.size());
  // Rows of ordered_ are read and written in the solver's order, scattered: fetched this many rows ahead.
  constexpr long kAhead = 16;
  const double *kx = known_values_.data(), *ky = kx + known_values_.rows(), *kz = ky + known_values_.rows();
  const double* normals = slot_normal_.data();
  parallel_for_chunks(nu, [&](long begin, long end) {
    for (long r = begin; r < end; ++r) {
      if (r + kAhead < end) __builtin_prefetch(ordered_.row(solve_row_[r + kAhead]).data(), 1);
      double x = 0, y = 0, z = 0;  // scalar sums in registers
      const int b0 = base_offsets_[r], b1 = base_offsets_[r + 1];
      if (b0 < b1) {
        const int ref = base_vertex_[b0];
        const double rx = Bc.x[ref], ry = Bc.y[ref], rz = Bc.z[ref];
        for (int c = b0 + 1; c < b1; ++c) {
          const int j = base_vertex_[c];
          const double w = base_weight_[c];
          x += w * (Bc.x[j] - rx), y += w * (Bc.y[j] - ry), z += w * (Bc.z[j] - rz);
        }
      }
      for (int c = normal_offsets_[r]; c < normal_offsets_[r + 1]; ++c) {
        const double* n = normals + 3 * normal_slot_[c];
        const double w = normal_weight_[c];
        x += w * n[0], y += w * n[1], z += w * n[2];
      }
      for (int c = coupling_offsets_[r]; c < coupling_offsets_[r + 1]; ++c) {
        const int k = coupling_known_[c];
        const double w = coupling_weight_[c];
        x -= w * kx[k], y -= w * ky[k], z -= w * kz[k];
      }
      double* row = ordered_.row(solve_row_[r]).data();
      row[0] = x, row[1] = y, row[2] = z;
    }
  });
  for (const auto& [r, q] : identity_rows_) ordered_.row(solve_row_[r]).head<3>() += q.transpose();
  if (nu > 0) system_.solver().solve_ordered(ordered_.data(), 3);
  // S' of the unknown vertices, each row tested against check_result()'s bound as it is written (the
  // Dirichlet rows are finite, and in the box by construction): only when one fails (beyond the bound or
  // not finite) does check_result() read all of S' to measure it and name the worst vertex.
  box.add(known_values_, centre);
  const double limit = box.result_limit(rest_extent_), limit2 = limit * limit;
  std::atomic<bool> near{true};
  parallel_for_chunks(nu, [&](long begin, long end) {
    bool chunk_near = true;
    for (long r = begin; r < end; ++r) {
      if (r + kAhead < end) __builtin_prefetch(ordered_.row(solve_row_[r + kAhead]).data());
      const double* row = ordered_.row(solve_row_[r]).data();
      const Vec3 p(row[0] + centre[0], row[1] + centre[1], row[2] + centre[2]);
      out.row(unknown[r]) = p;
      chunk_near &= box.near(p, limit2);
    }
    if (!chunk_near) near = false;
  });
  if (!near) check_result(B_deformed, centre, out);
  report_.seconds = seconds_since(t0);
}

void DeformationTransfer::check_result(const Positions& B_deformed, const Eigen::RowVector3d& centre,
                                       const Positions& out) const {
  Box box;
  box.add(B_deformed);
  box.add(known_values_, centre);  // the Dirichlet values (to rounding: out holds them unshifted)
  const double limit = box.result_limit(rest_extent_);
  // Within the bound when the squared distance is below the squared bound (no square root per vertex);
  // anything else (beyond it, not finite, or squares out of range) is measured exactly.
  const double limit2 = limit * limit;
  // The worst vertex: not finite, else the farthest outside the box (lowest index on ties).
  std::mutex mutex;
  long worst = -1;
  double worst_distance = 0;
  parallel_for_chunks(static_cast<long>(out.rows()), [&](long begin, long end) {
    long chunk_worst = -1;
    double chunk_distance = 0;
    for (long i = begin; i < end; ++i) {
      const Vec3 p = out.row(i);
      if (box.near(p, limit2)) continue;
      const bool finite = p.allFinite();
      const double d = finite ? box.distance(p) : std::numeric_limits<double>::infinity();
      if ((!finite || d > limit) && (chunk_worst < 0 || d > chunk_distance)) {
        chunk_worst = i;
        chunk_distance = d;
      }
    }
    if (chunk_worst < 0) return;
    std::lock_guard<std::mutex> lock(mutex);
    if (worst < 0 || chunk_distance > worst_distance ||
        (chunk_distance == worst_distance && chunk_worst < worst)) {
      worst = chunk_worst;
      worst_distance = chunk_distance;
    }
  });
  if (worst < 0) return;
  const Vec3 p = out.row(worst);
  std::string cause;
  if (!p.allFinite()) {
    cause = "is not finite (the Poisson solve overflowed)";
  } else {
    char text[256];
    std::snprintf(text, sizeof text,
                  " is %.3g outside the bounding box of the deformed base and anchors (bound %.3g = %g x "
                  "(their diagonal %.3g + the diagonal of S and B %.3g))",
                  worst_distance, limit, kResultBound, box.diagonal(), rest_extent_);
    cause = "at " + format_point(p) + text;
  }
  const Report& r = report_;
  throw SolverError(
      "DeformationTransfer::reconstruct: vertex " + std::to_string(worst) + " of S' " + cause +
          ": the transferred gradients are unbounded, e.g. a base triangle turned inside out or nearly "
          "flat in B' (B: " +
          std::to_string(r.needle_base_faces) + " needle and " + std::to_string(r.degenerate_base_faces) +
          " degenerate triangles without a frame; S: " + std::to_string(r.degenerate_faces) +
          " degenerate triangles, " + std::to_string(r.clamped_cotangents) +
          " clamped cotangents). No result returned",
      worst);
}

}  // namespace msd
