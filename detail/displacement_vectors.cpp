#include "msdeform/detail/displacement_vectors.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
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
  face_normals_.resize(4 * F.rows());
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

VertexFrames::Lanes VertexFrames::lanes(const std::vector<int>* vertices) const {
  Lanes lanes;
  lanes.single = group_in_fours(
      vertices ? static_cast<int>(vertices->size()) : num_vertices(), vertices ? vertices->data() : nullptr,
      [&](int v) { return face_offsets_[v + 1] - face_offsets_[v]; },
      [&](const int* four, int m) {
        lanes.vertices.insert(lanes.vertices.end(), four, four + 4);
        for (int t = 0; t < m; ++t)
          for (int i = 0; i < 4; ++i) lanes.faces.push_back(incident_faces_[face_offsets_[four[i]] + t]);
        lanes.offsets.push_back(static_cast<int>(lanes.faces.size()));
      });
  return lanes;
}

void VertexFrames::frame_of(long v, const Positions& P, Vec3& n, Vec3& t, Vec3& t2) const {
  const phong::Columns X(P);
  Vec3 sum = Vec3::Zero();
  double weight = 0;
  for (int i = face_offsets_[v]; i < face_offsets_[v + 1]; ++i) {
    const double* fn = face_normals_.data() + 4 * incident_faces_[i];
    sum += Vec3(fn[0], fn[1], fn[2]);
    weight += fn[3];
  }
  const double len = sum.norm();
  if (!(len > kMinNormalFraction * weight) || !(len > 0)) {  // no normal: world frame
    n = Vec3::UnitZ(), t = Vec3::UnitX(), t2 = Vec3::UnitY();
    return;
  }
  n = sum / len;
  const Vec3 p = X.row(v);
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
  t2 = n.cross(t);
}

namespace {

#if MSD_HAVE_AVX2_KERNELS
// (a_x b_x + a_y b_y) + a_z b_z, lane by lane: Eigen's order for 3-vectors.
MSD_AVX2 inline __m256d dot(__m256d ax, __m256d ay, __m256d az, __m256d bx, __m256d by, __m256d bz) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(ax, bx), _mm256_mul_pd(ay, by)), _mm256_mul_pd(az, bz));
}

// frame_of for the four vertices of a lane group, operation for operation (Eigen's 3-vectors sum, dot and
// divide in this order; no fused multiply-add): writes frame[c][i] (c: n, t1, t2 by coordinate, 9 rows) and
// returns the mask of the lanes done; a lane without normal or whose first edge gives no tangent is left to
// frame_of. first[i]: the first neighbour of lane i.
MSD_AVX2 int frames_x4(const phong::Columns& X, const double* face_normals, const int* vertices,
                       const int* faces, int m, const int* first, double (*frame)[4]) {
  const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(vertices));
  __m256d sx = _mm256_setzero_pd(), sy = sx, sz = sx, weight = sx;
  for (int t = 0; t < m; ++t) {
    // The four face normals (x, y, z, length) as rows, transposed to one vector per component.
    const __m256d r0 = _mm256_loadu_pd(face_normals + 4 * faces[4 * t]);
    const __m256d r1 = _mm256_loadu_pd(face_normals + 4 * faces[4 * t + 1]);
    const __m256d r2 = _mm256_loadu_pd(face_normals + 4 * faces[4 * t + 2]);
    const __m256d r3 = _mm256_loadu_pd(face_normals + 4 * faces[4 * t + 3]);
    const __m256d lo01 = _mm256_unpacklo_pd(r0, r1), hi01 = _mm256_unpackhi_pd(r0, r1);
    const __m256d lo23 = _mm256_unpacklo_pd(r2, r3), hi23 = _mm256_unpackhi_pd(r2, r3);
    sx = _mm256_add_pd(sx, _mm256_permute2f128_pd(lo01, lo23, 0x20));
    sy = _mm256_add_pd(sy, _mm256_permute2f128_pd(hi01, hi23, 0x20));
    sz = _mm256_add_pd(sz, _mm256_permute2f128_pd(lo01, lo23, 0x31));
    weight = _mm256_add_pd(weight, _mm256_permute2f128_pd(hi01, hi23, 0x31));
  }
  const __m256d zero = _mm256_setzero_pd();
  const __m256d len = _mm256_sqrt_pd(dot(sx, sy, sz, sx, sy, sz));
  const __m256d has_normal =
      _mm256_and_pd(_mm256_cmp_pd(len, _mm256_mul_pd(_mm256_set1_pd(kMinNormalFraction), weight), _CMP_GT_OQ),
                    _mm256_cmp_pd(len, zero, _CMP_GT_OQ));
  const __m256d nx = _mm256_div_pd(sx, len), ny = _mm256_div_pd(sy, len), nz = _mm256_div_pd(sz, len);
  const __m128i j = _mm_loadu_si128(reinterpret_cast<const __m128i*>(first));
  const __m256d px = gather(X.x, v), py = gather(X.y, v), pz = gather(X.z, v);
  const __m256d ex = _mm256_sub_pd(gather(X.x, j), px), ey = _mm256_sub_pd(gather(X.y, j), py),
                ez = _mm256_sub_pd(gather(X.z, j), pz);
  const __m256d d = dot(ex, ey, ez, nx, ny, nz);
  const __m256d tx = _mm256_sub_pd(ex, _mm256_mul_pd(d, nx)), ty = _mm256_sub_pd(ey, _mm256_mul_pd(d, ny)),
                tz = _mm256_sub_pd(ez, _mm256_mul_pd(d, nz));
  const __m256d t_len2 = dot(tx, ty, tz, tx, ty, tz);
  const __m256d has_tangent =
      _mm256_and_pd(_mm256_cmp_pd(t_len2,
                                  _mm256_mul_pd(_mm256_set1_pd(kMinTangentFraction * kMinTangentFraction),
                                                dot(ex, ey, ez, ex, ey, ez)),
                                  _CMP_GT_OQ),
                    _mm256_cmp_pd(t_len2, zero, _CMP_GT_OQ));
  const __m256d t_len = _mm256_sqrt_pd(t_len2);
  const __m256d ux = _mm256_div_pd(tx, t_len), uy = _mm256_div_pd(ty, t_len), uz = _mm256_div_pd(tz, t_len);
  const __m256d rows[9] = {nx,
                           ny,
                           nz,
                           ux,
                           uy,
                           uz,
                           _mm256_sub_pd(_mm256_mul_pd(ny, uz), _mm256_mul_pd(nz, uy)),
                           _mm256_sub_pd(_mm256_mul_pd(nz, ux), _mm256_mul_pd(nx, uz)),
                           _mm256_sub_pd(_mm256_mul_pd(nx, uy), _mm256_mul_pd(ny, ux))};
  for (int r = 0; r < 9; ++r) _mm256_storeu_pd(frame[r], rows[r]);
  return _mm256_movemask_pd(_mm256_and_pd(has_normal, has_tangent));
}
#endif

}  // namespace

template <class Visit>
void VertexFrames::visit_frames(const Positions& P, Visit visit, const Lanes& lanes,
                                const std::vector<int>* faces) const {
  const long nf = faces ? static_cast<long>(faces->size()) : static_cast<long>(F_.rows());
  const int* const face_list = faces ? faces->data() : nullptr;
  const phong::Columns X(P);
  double* const face_normals = face_normals_.data();
  // Per face: the normal of length 2 · area (area weighting), or zero for a zero-area face, and its length.
  parallel_for_chunks(nf, [&](long begin, long end) {
    for (long k = begin; k < end; ++k) {
      const long f = face_list ? face_list[k] : k;
      const Vec3 p0 = X.row(F_(f, 0)), p1 = X.row(F_(f, 1)), p2 = X.row(F_(f, 2));
      const Vec3 n = (p1 - p0).cross(p2 - p0);
      const double longest2 =
          std::max({(p1 - p0).squaredNorm(), (p2 - p1).squaredNorm(), (p0 - p2).squaredNorm()});
      const double len = n.norm();
      const bool area = len > kMinAreaFraction * 2 * longest2;
      double* out = face_normals + 4 * f;
      out[0] = area ? n.x() : 0.0, out[1] = area ? n.y() : 0.0, out[2] = area ? n.z() : 0.0;
      out[3] = area ? len : 0.0;
    }
  });
  const long groups = static_cast<long>(lanes.offsets.size()) - 1;
  parallel_for_chunks(
      groups,
      [&](long begin, long end) {
#if MSD_HAVE_AVX2_KERNELS
        for (long g = begin; g < end; ++g) {
          const int* vertices = lanes.vertices.data() + 4 * g;
          const int* faces = lanes.faces.data() + lanes.offsets[g];
          const int m = (lanes.offsets[g + 1] - lanes.offsets[g]) / 4;
          int first[4];
          for (int i = 0; i < 4; ++i) first[i] = neighbours_[offsets_[vertices[i]]];
          double frame[9][4];
          const int done = frames_x4(X, face_normals, vertices, faces, m, first, frame);
          for (int i = 0; i < 4; ++i) {
            Vec3 n(frame[0][i], frame[1][i], frame[2][i]), t1(frame[3][i], frame[4][i], frame[5][i]),
                t2(frame[6][i], frame[7][i], frame[8][i]);
            if (!(done >> i & 1)) frame_of(vertices[i], P, n, t1, t2);
            visit(vertices[i], n, t1, t2);
          }
        }
#endif
      },
      1024);
  parallel_for_chunks(static_cast<long>(lanes.single.size()), [&](long begin, long end) {
    for (long k = begin; k < end; ++k) {
      Vec3 n, t1, t2;
      frame_of(lanes.single[k], P, n, t1, t2);
      visit(lanes.single[k], n, t1, t2);
    }
  });
}

void VertexFrames::compute(const Positions& P, Positions& N, Positions& T1, Positions& T2) const {
  const long nv = num_vertices();
  if (P.rows() != nv)
    throw UsageError("VertexFrames::compute: " + std::to_string(P.rows()) + " positions for " +
                     std::to_string(nv) + " vertices");
  if (N.rows() != nv) N.resize(nv, 3);
  if (T1.rows() != nv) T1.resize(nv, 3);
  if (T2.rows() != nv) T2.resize(nv, 3);
  // The reference: one vertex at a time (this runs once per encoding; the frames' loop uses lanes).
  Lanes one_by_one;
  one_by_one.single.resize(nv);
  std::iota(one_by_one.single.begin(), one_by_one.single.end(), 0);
  visit_frames(
      P,
      [&](long v, const Vec3& n, const Vec3& t1, const Vec3& t2) {
        N.row(v) = n;
        T1.row(v) = t1;
        T2.row(v) = t2;
      },
      one_by_one);
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
  // The vertices a frame reconstructs (all but the placed ones) and the faces whose normals they read.
  all_faces_ = placed_.empty();
  frame_faces_.clear();
  if (all_faces_) {
    frame_vertices_ = frames_.lanes(nullptr);
  } else {
    std::vector<char> read(Fb.rows(), 0);
    std::vector<int> vertices;
    for (int v = 0; v < nv; ++v) {
      if (placed[v]) continue;
      vertices.push_back(v);
      for (int i = frames_.face_offsets_[v]; i < frames_.face_offsets_[v + 1]; ++i) read[frames_.incident_faces_[i]] = 1;
    }
    for (Eigen::Index f = 0; f < Fb.rows(); ++f)
      if (read[f]) frame_faces_.push_back(static_cast<int>(f));
    frame_vertices_ = frames_.lanes(&vertices);
  }
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
  const long nv = static_cast<long>(coefficients_.rows());
  if (B_deformed.rows() != nv)
    throw UsageError("DisplacementVectors::reconstruct: deformed base has " +
                     std::to_string(B_deformed.rows()) + " vertices, the encoded base had " +
                     std::to_string(nv));
  if (out.rows() != nv) out.resize(nv, 3);
  const double* const c = coefficients_.data();  // column-major: α, β, γ (or the world vector)
  double* const o = out.data();
  std::atomic<bool> finite{true};  // x − x is 0 for a finite x, NaN otherwise
  if (options_.frame == DisplacementFrame::Local) {
    const phong::Columns b(B_deformed);
    // The frames of B' straight into (9.8): no per-frame #V by 3 frame arrays written and read back.
    // visit_frames runs its vertices in chunks on both cores; `finite` gathers their checks.
    frames_.visit_frames(
        B_deformed,
        [&](long v, const Vec3& n, const Vec3& t1, const Vec3& t2) {
          const Vec3 p = b.row(v) + (c[v] * n + c[nv + v] * t1 + c[2 * nv + v] * t2);
          o[v] = p.x(), o[nv + v] = p.y(), o[2 * nv + v] = p.z();
          if (!((p.x() - p.x()) + (p.y() - p.y()) + (p.z() - p.z()) == 0))
            finite.store(false, std::memory_order_relaxed);
        },
        frame_vertices_, all_faces_ ? nullptr : &frame_faces_);
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
