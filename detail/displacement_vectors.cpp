#include "msdeform/detail/displacement_vectors.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/vector_kernels.h"
#include "msdeform/detail/phong.h"

namespace msd {
namespace {

// An edge whose tangential part is shorter than this fraction of its length is (nearly) parallel to the
// normal and gives no usable tangent direction.
constexpr double kMinTangentFraction = 1e-6;
// Faces with area below this fraction of their squared longest edge are zero-area (as in cotan_laplacian).
constexpr double kMinAreaFraction = TriangleCotangents::kDegenerateAreaRatio;
// A vertex normal sum shorter than this fraction of its terms' total length has cancelled: no direction.
constexpr double kMinNormalFraction = 1e-12;
// Vertices per block of DisplacementVectors::reconstruct's fused pass: on a mesh numbered row by row, a
// block's face normals (about 2 per vertex, 32 bytes each) take 0.5 MB and stay in L2; the faces on a
// block's edges are computed twice (about 1/16 more on the 1M bumpy plane).
constexpr long kFrameBlock = 8192;

// compute_face_normals' work for the face with corners t = (a, b, c): its normal (p_b − p_a) × (p_c − p_a),
// of length 2 · area, and that length into out[0..3], or zeros for a zero-area face. Written out term by term
// so that face_normals_x4 can do the same operations.
inline void face_normal(const phong::Columns& X, const int* t, double* out) {
  const int a = t[0], b = t[1], c = t[2];
  const double ux = X.x[b] - X.x[a], uy = X.y[b] - X.y[a], uz = X.z[b] - X.z[a];
  const double vx = X.x[c] - X.x[a], vy = X.y[c] - X.y[a], vz = X.z[c] - X.z[a];
  const double wx = X.x[c] - X.x[b], wy = X.y[c] - X.y[b], wz = X.z[c] - X.z[b];
  const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
  const double longest2 = std::max(std::max(ux * ux + uy * uy + uz * uz, wx * wx + wy * wy + wz * wz),
                                   vx * vx + vy * vy + vz * vz);
  const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
  const bool area = len > kMinAreaFraction * 2 * longest2;
  out[0] = area ? nx : 0.0, out[1] = area ? ny : 0.0, out[2] = area ? nz : 0.0, out[3] = area ? len : 0.0;
}

#if MSD_HAVE_AVX2_KERNELS
// Coordinate x at corner c of faces f[0..3] of F (#F by 3, row-major), from four scalar loads (see gather()).
MSD_AVX2 inline __m256d corner_x4(const double* x, const int* F, int c, const long* f) {
  return _mm256_set_pd(x[F[3 * f[3] + c]], x[F[3 * f[2] + c]], x[F[3 * f[1] + c]], x[F[3 * f[0] + c]]);
}
MSD_AVX2 inline __m256d max_x4(__m256d a, __m256d b) {  // std::max(a, b): a < b ? b : a
  return _mm256_blendv_pd(a, b, _mm256_cmp_pd(a, b, _CMP_LT_OQ));
}
// face_normal for entries [k0, k1) of `list` (face k when null) into out + 4k, four at a time, lane by lane
// with the same operations (no fused multiply-add), so the same bits; the rows stored by a 4×4 transpose.
MSD_AVX2 void face_normals_x4(const phong::Columns& X, const int* F, const int* list, long k0, long k1, double* out) {
  long k = k0;
  for (; k + 4 <= k1; k += 4) {
    long f[4];
    for (int i = 0; i < 4; ++i) f[i] = list ? list[k + i] : k + i;
    const __m256d ax = corner_x4(X.x, F, 0, f), ay = corner_x4(X.y, F, 0, f), az = corner_x4(X.z, F, 0, f);
    const __m256d bx = corner_x4(X.x, F, 1, f), by = corner_x4(X.y, F, 1, f), bz = corner_x4(X.z, F, 1, f);
    const __m256d cx = corner_x4(X.x, F, 2, f), cy = corner_x4(X.y, F, 2, f), cz = corner_x4(X.z, F, 2, f);
    const __m256d ux = _mm256_sub_pd(bx, ax), uy = _mm256_sub_pd(by, ay), uz = _mm256_sub_pd(bz, az);
    const __m256d vx = _mm256_sub_pd(cx, ax), vy = _mm256_sub_pd(cy, ay), vz = _mm256_sub_pd(cz, az);
    const __m256d wx = _mm256_sub_pd(cx, bx), wy = _mm256_sub_pd(cy, by), wz = _mm256_sub_pd(cz, bz);
    __m256d nx, ny, nz;
    cross_x4(ux, uy, uz, vx, vy, vz, nx, ny, nz);
    const __m256d longest2 = max_x4(max_x4(square_sum_x4(ux, uy, uz), square_sum_x4(wx, wy, wz)),
                                    square_sum_x4(vx, vy, vz));
    __m256d len = _mm256_sqrt_pd(square_sum_x4(nx, ny, nz));
    const __m256d area =
        _mm256_cmp_pd(len, _mm256_mul_pd(_mm256_set1_pd(kMinAreaFraction * 2), longest2), _CMP_GT_OQ);
    nx = _mm256_and_pd(nx, area), ny = _mm256_and_pd(ny, area), nz = _mm256_and_pd(nz, area);
    len = _mm256_and_pd(len, area);
    transpose_x4(nx, ny, nz, len);  // now face i's (n, |n|) in the i-th
    _mm256_storeu_pd(out + 4 * k, nx);
    _mm256_storeu_pd(out + 4 * k + 4, ny);
    _mm256_storeu_pd(out + 4 * k + 8, nz);
    _mm256_storeu_pd(out + 4 * k + 12, len);
  }
  for (; k < k1; ++k) face_normal(X, F + 3 * (list ? list[k] : k), out + 4 * k);
}

// VertexFrames' arrays, for the four-vertex loop below: vertex v's i-th face (face_offsets[v] + i) has its
// normal at face_normals + 4 · slots[face_offsets[v] + i].
struct FrameArrays {
  const int *face_offsets, *slots, *offsets, *neighbours;
  const double* face_normals;
};

MSD_AVX2 inline __m256d load_or_gather(const double* x, const int* v, bool consecutive) {
  return consecutive ? _mm256_loadu_pd(x + v[0]) : gather(x, v);
}
MSD_AVX2 inline void store_or_scatter(double* x, const int* v, bool consecutive, __m256d value) {
  if (consecutive) return _mm256_storeu_pd(x + v[0], value);
  alignas(32) double lanes[4];
  _mm256_store_pd(lanes, value);
  for (int i = 0; i < 4; ++i) x[v[i]] = lanes[i];
}

// One coordinate of b' + ((α n + β t1) + γ t2) (9.8), lane by lane.
MSD_AVX2 inline __m256d frame_point_x4(__m256d b, __m256d n, __m256d t1, __m256d t2, __m256d alpha,
                                       __m256d beta, __m256d gamma) {
  return _mm256_add_pd(b, _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(alpha, n), _mm256_mul_pd(beta, t1)),
                                        _mm256_mul_pd(gamma, t2)));
}

// DisplacementVectors::reconstruct's local-frame loop, p' = b' + α n' + β t1' + γ t2' (9.8), for entries
// [k0, k1) of `list` (vertex k when null), four vertices at a time with VertexFrames::frame's and the
// formula's operations lane by lane (no fused multiply-add), so the same bits. A group in which some vertex
// has no normal or its first edge gives no tangent, and the last entries, go through one_vertex(context, v)
// one at a time, as do the scalar kernels. Writes the rows of out (o, column-major, nv rows); returns whether
// every written coordinate is finite.
MSD_AVX2 bool reconstruct_local_x4(const FrameArrays& a, const phong::Columns& X, const double* c, long nv,
                                   double* o, const int* list, long k0, long k1,
                                   bool (*one_vertex)(const void*, long), const void* context) {
  const __m256d zero = _mm256_setzero_pd(), min_normal = _mm256_set1_pd(kMinNormalFraction);
  const __m256d min_tangent2 = _mm256_set1_pd(kMinTangentFraction * kMinTangentFraction);
  __m256d check = zero;
  bool ok = true;
  long k = k0;
  for (; k + 4 <= k1; k += 4) {
    int v[4], edge[4], first[4], count[4], most = 0;
    for (int i = 0; i < 4; ++i) {
      v[i] = list ? list[k + i] : static_cast<int>(k + i);
      first[i] = a.face_offsets[v[i]];
      count[i] = a.face_offsets[v[i] + 1] - first[i];
      most = std::max(most, count[i]);
    }
    // Σ n_f and Σ |n_f| around each vertex, its faces in its order; a vertex with fewer faces adds zeros,
    // which leave its sums as they are (a sum from +0 is never −0).
    __m256d sx = zero, sy = zero, sz = zero, weight = zero;
    for (int j = 0; j < most; ++j) {
      __m256d r[4];
      for (int i = 0; i < 4; ++i)
        r[i] = j < count[i] ? _mm256_loadu_pd(a.face_normals + 4 * a.slots[first[i] + j]) : zero;
      transpose_x4(r[0], r[1], r[2], r[3]);
      sx = _mm256_add_pd(sx, r[0]), sy = _mm256_add_pd(sy, r[1]), sz = _mm256_add_pd(sz, r[2]);
      weight = _mm256_add_pd(weight, r[3]);
    }
    const __m256d len = _mm256_sqrt_pd(square_sum_x4(sx, sy, sz));
    const __m256d has_normal =
        _mm256_and_pd(_mm256_cmp_pd(len, _mm256_mul_pd(min_normal, weight), _CMP_GT_OQ),
                      _mm256_cmp_pd(len, zero, _CMP_GT_OQ));
    bool edges = true;
    for (int i = 0; i < 4; ++i) {
      edges = edges && a.offsets[v[i]] < a.offsets[v[i] + 1];
      edge[i] = edges ? a.neighbours[a.offsets[v[i]]] : v[i];
    }
    const bool consecutive = v[3] - v[0] == 3;
    const __m256d nx = _mm256_div_pd(sx, len), ny = _mm256_div_pd(sy, len), nz = _mm256_div_pd(sz, len);
    const __m256d px = load_or_gather(X.x, v, consecutive), py = load_or_gather(X.y, v, consecutive),
                  pz = load_or_gather(X.z, v, consecutive);
    const __m256d ex = _mm256_sub_pd(gather(X.x, edge), px), ey = _mm256_sub_pd(gather(X.y, edge), py),
                  ez = _mm256_sub_pd(gather(X.z, edge), pz);
    const __m256d en = dot_x4(ex, ey, ez, nx, ny, nz);
    __m256d tx = _mm256_sub_pd(ex, _mm256_mul_pd(en, nx)), ty = _mm256_sub_pd(ey, _mm256_mul_pd(en, ny)),
            tz = _mm256_sub_pd(ez, _mm256_mul_pd(en, nz));
    const __m256d t_len2 = square_sum_x4(tx, ty, tz);
    const __m256d has_tangent = _mm256_and_pd(
        _mm256_cmp_pd(t_len2, _mm256_mul_pd(min_tangent2, square_sum_x4(ex, ey, ez)), _CMP_GT_OQ),
        _mm256_cmp_pd(t_len2, zero, _CMP_GT_OQ));
    if (!edges || _mm256_movemask_pd(_mm256_and_pd(has_normal, has_tangent)) != 0xF) {
      for (int i = 0; i < 4; ++i) ok &= one_vertex(context, v[i]);
      continue;
    }
    const __m256d t_len = _mm256_sqrt_pd(t_len2);
    tx = _mm256_div_pd(tx, t_len), ty = _mm256_div_pd(ty, t_len), tz = _mm256_div_pd(tz, t_len);
    __m256d bx, by, bz;  // t2 = n × t1
    cross_x4(nx, ny, nz, tx, ty, tz, bx, by, bz);
    const __m256d alpha = load_or_gather(c, v, consecutive), beta = load_or_gather(c + nv, v, consecutive),
                  gamma = load_or_gather(c + 2 * nv, v, consecutive);
    const __m256d qx = frame_point_x4(px, nx, tx, bx, alpha, beta, gamma);
    const __m256d qy = frame_point_x4(py, ny, ty, by, alpha, beta, gamma);
    const __m256d qz = frame_point_x4(pz, nz, tz, bz, alpha, beta, gamma);
    store_or_scatter(o, v, consecutive, qx);
    store_or_scatter(o + nv, v, consecutive, qy);
    store_or_scatter(o + 2 * nv, v, consecutive, qz);
    check = _mm256_add_pd(check, _mm256_add_pd(_mm256_add_pd(_mm256_sub_pd(qx, qx), _mm256_sub_pd(qy, qy)),
                                               _mm256_sub_pd(qz, qz)));
  }
  ok &= _mm256_movemask_pd(_mm256_cmp_pd(check, zero, _CMP_EQ_OQ)) == 0xF;
  for (; k < k1; ++k) ok &= one_vertex(context, list ? list[k] : k);
  return ok;
}
#endif

}  // namespace

VertexFrames::VertexFrames(const Faces& F, int num_vertices) {
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= num_vertices)
        throw InvalidInput("VertexFrames: face " + std::to_string(f) + " has vertex index " +
                           std::to_string(F(f, k)) + " out of range [0, " + std::to_string(num_vertices) +
                           ")");
  F_ = F;
  VertexFaces star = vertex_faces(F, num_vertices);
  face_offsets_ = std::move(star.offsets);
  incident_faces_ = std::move(star.faces);
  // Every corner lists its two neighbours in winding order; faces are visited in index order.
  std::vector<int> offsets(num_vertices + 1, 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) offsets[F(f, k) + 1] += 2;
  for (int v = 0; v < num_vertices; ++v) offsets[v + 1] += offsets[v];
  std::vector<int> raw(offsets.back());
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = F(f, k);
      raw[fill[v]++] = F(f, (k + 1) % 3);
      raw[fill[v]++] = F(f, (k + 2) % 3);
    }
  // Keep the first occurrence of each neighbour.
  offsets_.assign(num_vertices + 1, 0);
  neighbours_.clear();
  neighbours_.reserve(raw.size() / 2 + num_vertices);
  for (int v = 0; v < num_vertices; ++v) {
    const auto first = neighbours_.size();
    for (int i = offsets[v]; i < offsets[v + 1]; ++i)
      if (raw[i] != v &&
          std::find(neighbours_.begin() + first, neighbours_.end(), raw[i]) == neighbours_.end())
        neighbours_.push_back(raw[i]);
    offsets_[v + 1] = static_cast<int>(neighbours_.size());
  }
}

std::vector<int> VertexFrames::edge_order(int v) const {
  if (v < 0 || v >= num_vertices()) return {};
  return std::vector<int>(neighbours_.begin() + offsets_[v], neighbours_.begin() + offsets_[v + 1]);
}

void VertexFrames::face_normals(const phong::Columns& X, const int* list, long k0, long k1,
                                double* out) const {
  const int* const F = F_.data();  // row-major
#if MSD_HAVE_AVX2_KERNELS
  if (cpu_has_avx2()) return face_normals_x4(X, F, list, k0, k1, out);
#endif
  for (long k = k0; k < k1; ++k) face_normal(X, F + 3 * (list ? list[k] : k), out + 4 * k);
}

void VertexFrames::frame(const phong::Columns& X, long v, const int* slots, const double* normals, Vec3& n,
                         Vec3& t1, Vec3& t2) const {
  Vec3 sum = Vec3::Zero();
  double weight = 0;
  for (int i = face_offsets_[v]; i < face_offsets_[v + 1]; ++i) {
    const double* fn = normals + 4 * slots[i];
    sum += Vec3(fn[0], fn[1], fn[2]);
    weight += fn[3];
  }
  const double len = sum.norm();
  if (!(len > kMinNormalFraction * weight) || !(len > 0)) {  // no normal: world frame
    n = Vec3::UnitZ(), t1 = Vec3::UnitX(), t2 = Vec3::UnitY();
    return;
  }
  n = sum / len;
  const Vec3 p = X.row(v);
  Vec3 t = Vec3::Zero();
  bool found = false;
  for (int i = offsets_[v]; i < offsets_[v + 1] && !found; ++i) {
    const Vec3 e = X.row(neighbours_[i]) - p;
    t = e - e.dot(n) * n;
    const double t_len2 = t.squaredNorm();  // squared lengths compared: one square root less per vertex
    if (t_len2 > kMinTangentFraction * kMinTangentFraction * e.squaredNorm() && t_len2 > 0) {
      t /= std::sqrt(t_len2);
      found = true;
    }
  }
  if (!found) {  // every edge (nearly) parallel to n: the world axis least aligned with n
    int axis = 0;
    n.cwiseAbs().minCoeff(&axis);
    const Vec3 e = Vec3::Unit(axis);
    t = (e - e.dot(n) * n).normalized();
  }
  t1 = t;
  t2 = n.cross(t);
}

void VertexFrames::compute(const Positions& P, Positions& N, Positions& T1, Positions& T2) const {
  const long nv = num_vertices();
  if (P.rows() != nv)
    throw UsageError("VertexFrames::compute: " + std::to_string(P.rows()) + " positions for " +
                     std::to_string(nv) + " vertices");
  if (N.rows() != nv) N.resize(nv, 3);
  if (T1.rows() != nv) T1.resize(nv, 3);
  if (T2.rows() != nv) T2.resize(nv, 3);
  const phong::Columns X(P);
  std::vector<double> normals(4 * F_.rows());
  parallel_for_chunks(F_.rows(),
                      [&](long begin, long end) { face_normals(X, nullptr, begin, end, normals.data()); });
  parallel_for_chunks(nv, [&](long begin, long end) {
    Vec3 n, t1, t2;
    for (long v = begin; v < end; ++v) {
      frame(X, v, incident_faces_.data(), normals.data(), n, t1, t2);
      N.row(v) = n, T1.row(v) = t1, T2.row(v) = t2;
    }
  });
}

DisplacementVectors::DisplacementVectors(const DisplacementVectorOptions& options) : options_(options) {}

void DisplacementVectors::encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) {
  const char* where = "DisplacementVectors::encode";
  if (S.rows() != B.rows())
    throw InvalidInput(std::string(where) + ": S has " + std::to_string(S.rows()) + " vertices, B has " +
                       std::to_string(B.rows()) +
                       "; displacement vectors need S and B with the same connectivity");
  if (Fs.rows() != Fb.rows())
    throw InvalidInput(std::string(where) + ": S has " + std::to_string(Fs.rows()) + " faces, B has " +
                       std::to_string(Fb.rows()) +
                       "; displacement vectors need S and B with the same connectivity");
  for (Eigen::Index f = 0; f < Fs.rows(); ++f)
    if (Fs.row(f) != Fb.row(f))
      throw InvalidInput(std::string(where) + ": face " + std::to_string(f) + " differs between S and B; " +
                         "displacement vectors need S and B with the same connectivity");
  check_finite(S, where, "S");
  check_finite(B, where, "B");
  encoded_ = false;
  const int nv = static_cast<int>(B.rows());
  const std::vector<char> placed = placed_mask(nv, where);
  frames_ = VertexFrames(Fb, nv);
  // The vertices a frame reconstructs (all but the placed ones), in blocks of kFrameBlock consecutive
  // entries, each block with the list of the faces its frames read (a face on the edge of two blocks is in
  // both) and each of its vertices' faces as a slot in that list.
  all_vertices_ = placed_.empty();
  frame_vertices_.clear();
  if (!all_vertices_)
    for (int v = 0; v < nv; ++v)
      if (!placed[v]) frame_vertices_.push_back(v);
  const long count = all_vertices_ ? nv : static_cast<long>(frame_vertices_.size());
  block_face_offsets_.assign(1, 0);
  block_faces_.clear();
  face_slots_.assign(frames_.incident_faces_.size(), 0);
  std::vector<long> block_of(Fb.rows(), -1);
  std::vector<int> slot_of(Fb.rows());
  long largest = 0;
  for (long k0 = 0; k0 < count; k0 += kFrameBlock) {
    const long first = static_cast<long>(block_faces_.size());
    for (long k = k0; k < std::min(count, k0 + kFrameBlock); ++k) {
      const int v = all_vertices_ ? static_cast<int>(k) : frame_vertices_[k];
      for (int i = frames_.face_offsets_[v]; i < frames_.face_offsets_[v + 1]; ++i) {
        const int f = frames_.incident_faces_[i];
        if (block_of[f] != k0) {
          block_of[f] = k0;
          slot_of[f] = static_cast<int>(block_faces_.size() - first);
          block_faces_.push_back(f);
        }
        face_slots_[i] = slot_of[f];
      }
    }
    block_face_offsets_.push_back(static_cast<int>(block_faces_.size()));
    largest = std::max(largest, static_cast<long>(block_faces_.size()) - first);
  }
  block_normals_ = tbb::enumerable_thread_specific<std::vector<double>>(std::vector<double>(4 * largest));
  const Positions H = S - B;
  if (options_.frame == DisplacementFrame::Global) {
    coefficients_ = H;
  } else {
    Positions N, T1, T2;
    frames_.compute(B, N, T1, T2);
    coefficients_.resize(H.rows(), 3);
    coefficients_.col(0) = (H.array() * N.array()).rowwise().sum();  // (9.8): α = h · n
    coefficients_.col(1) = (H.array() * T1.array()).rowwise().sum();
    coefficients_.col(2) = (H.array() * T2.array()).rowwise().sum();
  }
  encoded_ = true;
}

void DisplacementVectors::reconstruct(const Positions& B_deformed, Positions& out) {
  if (!encoded_) throw UsageError("DisplacementVectors::reconstruct: called before encode()");
  check_not_aliased(B_deformed, out, "DisplacementVectors::reconstruct");
  const long nv = static_cast<long>(coefficients_.rows());
  if (B_deformed.rows() != nv)
    throw UsageError("DisplacementVectors::reconstruct: deformed base has " +
                     std::to_string(B_deformed.rows()) + " vertices, the encoded base had " +
                     std::to_string(nv));
  size_output(out, nv, "DisplacementVectors::reconstruct");
  const double* const c = coefficients_.data();  // column-major: α, β, γ (or the world vector)
  double* const o = out.data();
  std::atomic<bool> finite{true};  // x − x is 0 for a finite x, NaN otherwise
  if (options_.frame == DisplacementFrame::Local) {
    // The frames of B' straight into (9.8): no per-frame #V by 3 frame arrays written and read back. The
    // vertices run in chunks on both cores; `finite` gathers their checks.
    // One fused pass per block: its faces' normals into this thread's buffer, which stays in L2 while the
    // block's frames read them (no #F by 4 array written and read back).
    const phong::Columns b(B_deformed);
    const int* const list = all_vertices_ ? nullptr : frame_vertices_.data();
    const long count = all_vertices_ ? nv : static_cast<long>(frame_vertices_.size());
    const long blocks = static_cast<long>(block_face_offsets_.size()) - 1;
    parallel_for_chunks(
        blocks,
        [&](long first_block, long end_block) {
          double* const normals = block_normals_.local().data();
          const auto one = [&](long v) {  // p' of vertex v; false where it is not finite
            Vec3 n, t1, t2;
            frames_.frame(b, v, face_slots_.data(), normals, n, t1, t2);
            const Vec3 p = b.row(v) + (c[v] * n + c[nv + v] * t1 + c[2 * nv + v] * t2);
            o[v] = p.x(), o[nv + v] = p.y(), o[2 * nv + v] = p.z();
            return (p.x() - p.x()) + (p.y() - p.y()) + (p.z() - p.z()) == 0;
          };
          bool ok = true;
          for (long block = first_block; block < end_block; ++block) {
            const long begin = block * kFrameBlock, end = std::min(count, begin + kFrameBlock);
            const int f0 = block_face_offsets_[block];
            frames_.face_normals(b, block_faces_.data() + f0, 0, block_face_offsets_[block + 1] - f0,
                                 normals);
#if MSD_HAVE_AVX2_KERNELS
            if (cpu_has_avx2()) {
              const FrameArrays arrays{frames_.face_offsets_.data(), face_slots_.data(),
                                       frames_.offsets_.data(), frames_.neighbours_.data(), normals};
              const auto scalar = [](const void* one_vertex, long v) {
                return (*static_cast<const decltype(one)*>(one_vertex))(v);
              };
              ok &= reconstruct_local_x4(arrays, b, c, nv, o, list, begin, end, scalar, &one);
              continue;
            }
#endif
            for (long k = begin; k < end; ++k) ok &= one(list ? list[k] : k);
          }
          if (!ok) finite.store(false, std::memory_order_relaxed);
        },
        1);
  } else {
    parallel_for_chunks(nv, [&](long begin, long end) {
      double check = 0;
      for (int d = 0; d < 3; ++d)
        for (long v = begin; v < end; ++v) {
          const double x = B_deformed.data()[d * nv + v] + c[d * nv + v];
          o[d * nv + v] = x;
          check += x - x;
        }
      if (!(check == 0)) finite = false;
    });
  }
  if (!finite) {
    check_finite(B_deformed, "DisplacementVectors::reconstruct", "the deformed base");
    throw InvalidInput("DisplacementVectors::reconstruct: non-finite result from a finite base (overflow?)");
  }
}

}  // namespace msd
