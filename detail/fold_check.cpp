#include "msdeform/detail/fold_check.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <utility>

#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/vector_kernels.h"
#include "msdeform/detail/closest_point.h"
#include "msdeform/detail/phong.h"

namespace msd {
namespace {

// n_a · n_b for triangle ta of A and tb of B, each n twice the area-weighted normal. Raw columns and
// indices in locals: this runs every frame over all triangles (Eigen's row views of the column-major
// arrays cost a third of it). Of order size⁴: it overflows beyond sizes of about 1e77 and underflows below
// 1e-77, where orientation() takes over.
inline double dot_of_normals(const phong::Columns& A, const int* ta, const phong::Columns& B, const int* tb) {
  const int a0 = ta[0], a1 = ta[1], a2 = ta[2], b0 = tb[0], b1 = tb[1], b2 = tb[2];
  const double ax = A.x[a1] - A.x[a0], ay = A.y[a1] - A.y[a0], az = A.z[a1] - A.z[a0];
  const double cx = A.x[a2] - A.x[a0], cy = A.y[a2] - A.y[a0], cz = A.z[a2] - A.z[a0];
  const double ex = B.x[b1] - B.x[b0], ey = B.y[b1] - B.y[b0], ez = B.z[b1] - B.z[b0];
  const double gx = B.x[b2] - B.x[b0], gy = B.y[b2] - B.y[b0], gz = B.z[b2] - B.z[b0];
  return (ay * cz - az * cy) * (ey * gz - ez * gy) + (az * cx - ax * cz) * (ez * gx - ex * gz) +
         (ax * cy - ay * cx) * (ex * gy - ey * gx);
}

// A product of normals whose sign can be trusted: neither zero, subnormal nor overflowed.
inline bool normal_range(double d) {
  const double m = std::abs(d);
  return m >= std::numeric_limits<double>::min() && m <= std::numeric_limits<double>::max();
}

// count()'s pass over stored triangles [begin, end): adds the folded ones to `folded` and those whose product
// of normals is not in normal_range() (and that have a rest sign) to `unsure`.
void count_folds(const phong::Columns& s, const int* fs, const phong::Columns& b, const int* fb,
                 const int* ref, const signed char* rest, long begin, long end, int& folded, int& unsure) {
  int n = 0, u = 0;
  for (long f = begin; f < end; ++f) {
    // Folded when the orientation changed sign: (n_S' · n_B') · rest < 0. Branch-free: a data-dependent
    // branch per triangle (skip the uncounted ones, compare signs) costs half of the pass. A product
    // that is zero, subnormal or not finite (a collapsed triangle, or sizes beyond 1e±77) is unsure.
    const double d = dot_of_normals(s, fs + 3 * f, b, fb + 3 * (ref ? ref[f] : f));
    n += d * rest[f] < 0;
    u += (rest[f] != 0) & !normal_range(d);
  }
  folded += n, unsure += u;
}

#if MSD_HAVE_AVX2_KERNELS
// count_folds four triangles at a time, each lane with dot_of_normals' operations in its order (no fused
// multiply-add): the same products, so the same counts. On the 1M lift (1.26M triangles counted) the pass
// took 2.7–2.8 ms, the scalar one 3.6–4.3 ms.
MSD_AVX2 void count_folds_x4(const phong::Columns& s, const int* fs, const phong::Columns& b, const int* fb,
                             const int* ref, const signed char* rest, long begin, long end, int& folded,
                             int& unsure) {
  const __m256d zero = _mm256_setzero_pd(), sign = _mm256_set1_pd(-0.0);
  const __m256d smallest = _mm256_set1_pd(std::numeric_limits<double>::min());
  const __m256d largest = _mm256_set1_pd(std::numeric_limits<double>::max());
  int n = 0, u = 0;
  long f = begin;
  for (; f + 4 <= end; f += 4) {
    int ia[3][4], ib[3][4];  // corner k of the four triangles of S' and of their base triangles
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k) ia[k][i] = fs[3 * (f + i) + k];
    if (ref) {
      for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 3; ++k) ib[k][i] = fb[3 * ref[f + i] + k];
    } else {  // shared connectivity (fb is fs)
      std::memcpy(ib, ia, sizeof ia);
    }
    const __m256d a0x = gather(s.x, ia[0]), a0y = gather(s.y, ia[0]), a0z = gather(s.z, ia[0]);
    const __m256d ax = _mm256_sub_pd(gather(s.x, ia[1]), a0x), ay = _mm256_sub_pd(gather(s.y, ia[1]), a0y),
                  az = _mm256_sub_pd(gather(s.z, ia[1]), a0z);
    const __m256d cx = _mm256_sub_pd(gather(s.x, ia[2]), a0x), cy = _mm256_sub_pd(gather(s.y, ia[2]), a0y),
                  cz = _mm256_sub_pd(gather(s.z, ia[2]), a0z);
    const __m256d b0x = gather(b.x, ib[0]), b0y = gather(b.y, ib[0]), b0z = gather(b.z, ib[0]);
    const __m256d ex = _mm256_sub_pd(gather(b.x, ib[1]), b0x), ey = _mm256_sub_pd(gather(b.y, ib[1]), b0y),
                  ez = _mm256_sub_pd(gather(b.z, ib[1]), b0z);
    const __m256d gx = _mm256_sub_pd(gather(b.x, ib[2]), b0x), gy = _mm256_sub_pd(gather(b.y, ib[2]), b0y),
                  gz = _mm256_sub_pd(gather(b.z, ib[2]), b0z);
    __m256d nax, nay, naz, nbx, nby, nbz;  // the two normals, a × c and e × g
    cross_x4(ax, ay, az, cx, cy, cz, nax, nay, naz);
    cross_x4(ex, ey, ez, gx, gy, gz, nbx, nby, nbz);
    const __m256d d = dot_x4(nax, nay, naz, nbx, nby, nbz);
    int packed;
    std::memcpy(&packed, rest + f, 4);
    const __m256d r = _mm256_cvtepi32_pd(_mm_cvtepi8_epi32(_mm_cvtsi32_si128(packed)));
    const __m256d m = _mm256_andnot_pd(sign, d);
    const __m256d in_range =
        _mm256_and_pd(_mm256_cmp_pd(m, smallest, _CMP_GE_OQ), _mm256_cmp_pd(m, largest, _CMP_LE_OQ));
    n += __builtin_popcount(_mm256_movemask_pd(_mm256_cmp_pd(_mm256_mul_pd(d, r), zero, _CMP_LT_OQ)));
    u += __builtin_popcount(
        _mm256_movemask_pd(_mm256_andnot_pd(in_range, _mm256_cmp_pd(r, zero, _CMP_NEQ_OQ))));
  }
  folded += n, unsure += u;
  count_folds(s, fs, b, fb, ref, rest, f, end, folded, unsure);
}
#endif

// The normal of triangle t of X scaled to a largest component of 1, from edges scaled the same way (no
// overflow or underflow at any finite size); zero for a triangle that cotan_laplacian calls degenerate
// (area below 1e-14 of its squared longest edge): its orientation is rounding noise.
Vec3 unit_scale_normal(const phong::Columns& X, const int* t) {
  const Vec3 p0 = X.row(t[0]);
  Vec3 e1 = X.row(t[1]) - p0, e2 = X.row(t[2]) - p0;
  const double scale = std::max(e1.cwiseAbs().maxCoeff(), e2.cwiseAbs().maxCoeff());
  if (!(scale > 0) || !std::isfinite(scale)) return Vec3::Zero();
  e1 /= scale, e2 /= scale;
  const Vec3 n = e1.cross(e2);
  const double longest2 = std::max({e1.squaredNorm(), e2.squaredNorm(), (e2 - e1).squaredNorm()});
  // Degenerate as triangle_cotangents() says, measured in units of `scale`.
  const double m = std::max({p0.cwiseAbs().maxCoeff(), X.row(t[1]).cwiseAbs().maxCoeff(),
                             X.row(t[2]).cwiseAbs().maxCoeff()}) /
                   scale;
  if (degenerate_area(n.norm(), longest2, m)) return Vec3::Zero();
  return n / n.cwiseAbs().maxCoeff();
}

// Sign of n_a · n_b (−1, 0 or 1), right at any finite size; 0 where either triangle is degenerate.
int orientation(const phong::Columns& A, const int* ta, const phong::Columns& B, const int* tb) {
  const double d = unit_scale_normal(A, ta).dot(unit_scale_normal(B, tb));
  return (d > 0) - (d < 0);
}

// Cosine of the angle between the normals of ta and tb (0 where either triangle is degenerate).
double normal_cosine(const phong::Columns& A, const int* ta, const phong::Columns& B, const int* tb) {
  const Vec3 a = unit_scale_normal(A, ta), b = unit_scale_normal(B, tb);
  const double lengths = a.norm() * b.norm();
  return lengths > 0 ? a.dot(b) / lengths : 0.0;
}

// A map x ↦ A x + t whose AᵀA = s²(I + E) with s > 0 and every |E_ij| ≤ kSimilarity (a similarity as
// written in a file with 6 or more digits). Normals move by cof(A), and cof(A)ᵀcof(A) = det(A)² (AᵀA)⁻¹ =
// s⁴ det(I + E) (I + E)⁻¹: a product of two normals it moves together becomes s⁴ det(I + E) (n_a · n_b −
// n_aᵀ E n_b + O(E²)), whose sign is n_a · n_b's wherever |cos(n_a, n_b)| > ‖E‖ (at most 3 kSimilarity).
constexpr double kSimilarity = 1e-6;
bool is_similarity(const Mat4& T) {
  const Mat3 A = T.topLeftCorner<3, 3>();
  const Mat3 M = A.transpose() * A;
  const double s2 = M.trace() / 3;
  if (!(s2 > 0) || !std::isfinite(s2)) return false;
  return (M - s2 * Mat3::Identity()).cwiseAbs().maxCoeff() <= kSimilarity * s2;
}

// Triangles whose rest normals are closer to perpendicular than this (cosine) are counted in every frame
// (300 times the most a similarity by the test above can move a cosine).
constexpr double kNearPerpendicular = 1e-3;

}  // namespace

void FoldCheck::prepare(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) {
  const char* who = "FoldCheck::prepare";
  check_faces(Fs, S.rows(), who, "S");
  check_faces(Fb, B.rows(), who, "B");
  const bool shared = Fs.rows() == Fb.rows() && S.rows() == B.rows() && Fs == Fb;
  faces_ = Fs;
  base_faces_ = shared ? Faces() : Fb;  // shared: triangle t of S is triangle t of B
  shared_ = shared;
  num_vertices_ = S.rows();
  num_base_vertices_ = B.rows();
  std::unique_ptr<ClosestPointQuery> query;
  if (!shared) query = std::make_unique<ClosestPointQuery>(B, Fb);
  reference_.resize(shared ? 0 : Fs.rows());
  rest_sign_.assign(Fs.rows(), 0);
  near_perpendicular_.assign(Fs.rows(), 0);
  const phong::Columns s(S), b(B);
  for (Eigen::Index f = 0; f < Fs.rows(); ++f) {
    int r = static_cast<int>(f);
    if (!shared) {
      const Vec3 centroid = (S.row(Fs(f, 0)) + S.row(Fs(f, 1)) + S.row(Fs(f, 2))) / 3;
      r = reference_[f] = query->query(centroid).face;
    }
    // A needle of S (a corner's |cot| beyond the cotan Laplacian's clamp, 1e5: a sliver some 1e-5 of its
    // length high or less) turns over at the slightest move of a corner; the input's own needles are not
    // folds of the detail layer (prepare warns about them), and a smaller detail scale cannot help there.
    const bool needle =
        triangle_cotangents(S.row(Fs(f, 0)), S.row(Fs(f, 1)), S.row(Fs(f, 2))).needle_corners > 0;
    rest_sign_[f] = needle ? 0 : static_cast<signed char>(orientation(s, &Fs(f, 0), b, &Fb(r, 0)));
    near_perpendicular_[f] = std::abs(normal_cosine(s, &Fs(f, 0), b, &Fb(r, 0))) < kNearPerpendicular;
  }
  order_.resize(Fs.rows());
  std::iota(order_.begin(), order_.end(), 0);
  groups_.assign(1, Group{Region::kFree, 0, static_cast<long>(Fs.rows())});
}

void FoldCheck::set_placements(const Region& s_region, const Region& b_region) {
  const char* who = "FoldCheck::set_placements";
  if (num_base_vertices_ < 0) throw UsageError(std::string(who) + " before prepare()");
  if (s_region.num_vertices() != num_vertices_ || b_region.num_vertices() != num_base_vertices_)
    throw UsageError(std::string(who) + ": the regions have " + std::to_string(s_region.num_vertices()) +
                     " and " + std::to_string(b_region.num_vertices()) + " vertices, S and B " +
                     std::to_string(num_vertices_) + " and " + std::to_string(num_base_vertices_));
  // Each stored triangle's group: the code all six corners share (kFree where they do not).
  const long n = static_cast<long>(order_.size());
  std::vector<int> code(n);
  for (long i = 0; i < n; ++i) {
    const int* corners = &faces_(i, 0);
    const int* base_corners = shared_ ? corners : &base_faces_(reference_[i], 0);
    int c = s_region.code(corners[0]);
    for (int k = 0; k < 3; ++k)
      if (s_region.code(corners[k]) != c || b_region.code(base_corners[k]) != c) c = Region::kFree;
    code[i] = near_perpendicular_[order_[i]] ? Region::kFree : c;
  }
  // Stored again by group (kFree first, then fixed, then the handles in order), each group in S's order.
  const auto group_key = [&](long i) {
    return std::make_pair(code[i] == Region::kFree ? -1 : code[i], order_[i]);
  };
  std::vector<long> slot(n);
  std::iota(slot.begin(), slot.end(), 0L);
  std::sort(slot.begin(), slot.end(), [&](long a, long b) { return group_key(a) < group_key(b); });
  const Faces faces = faces_;
  const Eigen::VectorXi reference = reference_;
  const std::vector<signed char> rest_sign = rest_sign_;
  const std::vector<int> order = order_;
  groups_.clear();
  for (long i = 0; i < n; ++i) {
    const long j = slot[i];
    faces_.row(i) = faces.row(j);
    if (!shared_) reference_[i] = reference[j];
    rest_sign_[i] = rest_sign[j];
    order_[i] = order[j];
    if (groups_.empty() || groups_.back().code != code[j]) groups_.push_back(Group{code[j], i, i});
    groups_.back().end = i + 1;
  }
}

bool FoldCheck::counted(const Group& g, const std::vector<Mat4>& transforms) const {
  if (g.code == Region::kFree || transforms.empty()) return true;
  if (g.code == Region::kFixed) return false;
  const size_t k = static_cast<size_t>(g.code - Region::kFirstHandle);
  return k >= transforms.size() || !is_similarity(transforms[k]);
}

long FoldCheck::skipped(const std::vector<Mat4>& transforms) const {
  long n = 0;
  for (const Group& g : groups_)
    if (!counted(g, transforms)) n += g.end - g.begin;
  return n;
}

int FoldCheck::count(const Positions& S_deformed, const Positions& B_deformed,
                     const std::vector<Mat4>& transforms) const {
  if (num_base_vertices_ < 0) throw UsageError("FoldCheck::count before prepare()");
  if (B_deformed.rows() != num_base_vertices_ || S_deformed.rows() != num_vertices_)
    throw UsageError("FoldCheck::count: S' or B' has the wrong number of rows");
  const phong::Columns s(S_deformed), b(B_deformed);
  const int* const fs = faces_.data();
  const int* const fb = shared_ ? fs : base_faces_.data();
  const int* const ref = shared_ ? nullptr : reference_.data();
  const signed char* const rest = rest_sign_.data();
  // Runs of consecutive counted groups, each triangle once.
  const auto for_each_run = [&](auto run) {
    for (size_t g = 0; g < groups_.size();) {
      if (!counted(groups_[g], transforms)) {
        ++g;
        continue;
      }
      const long begin = groups_[g].begin;
      while (g < groups_.size() && counted(groups_[g], transforms)) ++g;
      run(begin, groups_[g - 1].end);
    }
  };
  std::atomic<int> folded{0}, unsure{0};
  for_each_run([&](long first, long last) {
    parallel_for_chunks(last - first, [=, &folded, &unsure](long begin, long end) {
      int n = 0, u = 0;
#if MSD_HAVE_AVX2_KERNELS
      if (cpu_has_avx2())
        count_folds_x4(s, fs, b, fb, ref, rest, first + begin, first + end, n, u);
      else
#endif
        count_folds(s, fs, b, fb, ref, rest, first + begin, first + end, n, u);
      folded += n;
      unsure += u;
    });
  });
  if (unsure == 0) return folded;
  // Rare: the pass again, deciding the unsure triangles from normals scaled to unit size.
  int recount = 0;
  for_each_run([&](long first, long last) {
    for (long f = first; f < last; ++f) {
      if (rest[f] == 0) continue;
      const int* tb = fb + 3 * (ref ? ref[f] : f);
      const double d = dot_of_normals(s, fs + 3 * f, b, tb);
      recount += normal_range(d) ? d * rest[f] < 0 : orientation(s, fs + 3 * f, b, tb) == -rest[f];
    }
  });
  return recount;
}

}  // namespace msd
