#include "msdeform/detail/normal_displacements.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/vector_kernels.h"
#include "msdeform/detail/closest_point.h"
#include "msdeform/detail/phong.h"

namespace msd {
namespace {

// Barycentric coordinates down to −kInsideSlack count as inside the triangle: a root on an edge may land a
// rounding error outside it, and walking back and forth over the edge would gain nothing.
constexpr double kInsideSlack = 1e-10;

// adjacency[3 f + k] = the face across the edge of face f opposite its corner k, or −1 on a boundary
// or non-manifold edge (where no single neighbour exists to walk to).
std::vector<int> face_adjacency(const Faces& F, const VertexFaces& star) {
  const std::vector<int>&offsets = star.offsets, &incident = star.faces;

  std::vector<int> adjacency(3 * F.rows(), -1);
  parallel_for_chunks(F.rows(), [&](long begin, long end) {
    for (long f = begin; f < end; ++f)
      for (int k = 0; k < 3; ++k) {
        const int u = F(f, (k + 1) % 3), w = F(f, (k + 2) % 3);
        int neighbour = -1, count = 0;
        for (int i = offsets[u]; i < offsets[u + 1]; ++i) {
          const int g = incident[i];
          if (g == f) continue;
          if (F(g, 0) == w || F(g, 1) == w || F(g, 2) == w) {
            neighbour = g;
            ++count;
          }
        }
        adjacency[3 * f + k] = count == 1 ? neighbour : -1;
      }
  });
  return adjacency;
}

// Newton search for one vertex (see the class comment).
struct BasePointSearch {
  const Positions& B;
  const Positions& N;
  const Faces& F;
  const std::vector<int>& adjacency;
  const NormalDisplacementOptions& options;
  double tolerance;  // absolute

  // From (face, w), finds a root of f = (p − x) × m. On success updates face and w and returns true.
  bool run(const Vec3& p, int& face, Vec3& w_io, int& iterations, int& walks) const {
    int f = face;
    Vec3 w = w_io;
    iterations = walks = 0;
    for (;;) {
      Vec3 step;
      const Newton n = newton_step(p, f, w, w.minCoeff() >= -kInsideSlack, step);
      if (n == Newton::Converged) {
        face = f;
        w_io = w;
        return true;
      }
      if (n == Newton::Failed) return false;
      if (iterations - walks >= options.max_iterations) return false;
      ++iterations;
      const Vec3 next = w + step;
      if (next.minCoeff() >= -kInsideSlack) {
        w = next;
        continue;
      }
      // The step leaves the triangle: stop where it crosses the first edge (seed: "proceed to the
      // respective neighbouring triangle").
      double t = 1;
      int k = 0;
      for (int j = 0; j < 3; ++j)
        if (next[j] < -kInsideSlack && step[j] < 0) {
          const double tj = std::max(w[j], 0.0) / -step[j];
          if (tj < t) t = tj, k = j;
        }
      w += t * step;
      w[k] = 0;
      const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
      w[k1] = std::max(w[k1], 0.0);
      w[k2] = std::max(w[k2], 0.0);
      const double sum = w[k1] + w[k2];
      if (!(sum > 0)) return false;
      w[k1] /= sum;
      w[k2] /= sum;
      const int g = adjacency[3 * f + k];
      if (g < 0) continue;  // boundary edge: stay on it; the iteration cap ends a search pushing outwards
      if (++walks > options.max_walks) return false;
      const int u = F(f, k1), v = F(f, k2);
      const double wu = w[k1], wv = w[k2];
      for (int j = 0; j < 3; ++j) w[j] = F(g, j) == u ? wu : F(g, j) == v ? wv : 0.0;
      f = g;
    }
  }

  // Second chance for a search that failed (e.g. a root exactly on a vertex or edge, where walking
  // ping-pongs between triangles): projected Gauss–Newton confined to face f, started at its centre.
  // On success sets w and returns true.
  bool run_in_triangle(const Vec3& p, int f, Vec3& w) const {
    w = Vec3::Constant(1.0 / 3.0);
    for (int it = 0; it <= options.max_iterations; ++it) {
      Vec3 step;
      const Newton n = newton_step(p, f, w, true, step);
      if (n != Newton::Step) return n == Newton::Converged;
      w += step;
      w = w.cwiseMax(0.0);  // project back onto the triangle
      const double sum = w.sum();
      if (!(sum > 0)) return false;
      w /= sum;
    }
    return false;
  }

  enum class Newton { Converged, Step, Failed };
  // At barycentrics w of face f: Converged if may_stop and the residual of f = (p − x) × m meets the
  // tolerance; Failed where the normal vanishes or the Jacobian is rank-deficient (p near a focal point
  // of B); else Step, with the Gauss–Newton step on the 3×2 Jacobian of r(α, β), γ = 1 − α − β
  // (x_α = a − c, m_α = n_a − n_c), written to step.
  Newton newton_step(const Vec3& p, int f, const Vec3& w, bool may_stop, Vec3& step) const {
    const int ia = F(f, 0), ib = F(f, 1), ic = F(f, 2);
    const Vec3 a = B.row(ia), b = B.row(ib), c = B.row(ic);
    const Vec3 na = N.row(ia), nb = N.row(ib), nc = N.row(ic);
    const Vec3 m = w[0] * na + w[1] * nb + w[2] * nc;
    // p − x from differences to corner a (w sums to 1): far from the origin, p − (w·(a, b, c)) would cancel
    // the coordinates' leading digits and leave rounding above the tolerance (no convergence at 1e6).
    const Vec3 ba = b - a, ca = c - a;
    const Vec3 d = (p - a) - w[1] * ba - w[2] * ca;
    const double m_len = m.norm();
    if (!(m_len > phong::kMinNormalLength)) return Newton::Failed;
    const Vec3 r = d.cross(m);
    if (may_stop && r.norm() <= tolerance * m_len) return Newton::Converged;
    const Vec3 ja = d.cross(na - nc) + ca.cross(m);         // (a − c) = −ca
    const Vec3 jb = d.cross(nb - nc) - (ba - ca).cross(m);  // (b − c) = ba − ca
    const double A = ja.squaredNorm(), Bc = ja.dot(jb), C = jb.squaredNorm();
    const double det = A * C - Bc * Bc;
    if (!(det > 1e-24 * A * C)) return Newton::Failed;
    const double ga = ja.dot(r), gb = jb.dot(r);
    const double da = -(C * ga - Bc * gb) / det, db = -(A * gb - Bc * ga) / det;
    step = Vec3(da, db, -da - db);
    return Newton::Step;
  }
};

// S'(v) = B'(w) + h n(w) for one sample (seed 9.3.2): the frame loop of reconstruct(). check gains
// x − x for each coordinate x written: 0 while they are finite, NaN from the first that is not.
template <class Sample>
inline void reconstruct_sample(const Sample& s, const phong::Columns& B, const phong::Rows& N, double* ox,
                               double* oy, double* oz, double& check) {
  const Vec3 w(s.w[0], s.w[1], s.w[2]);
  const Vec3 p = phong::interpolate(B, s.corner, w) + s.h * phong::direction(B, N, s.corner, w);
  ox[s.vertex] = p.x();
  oy[s.vertex] = p.y();
  oz[s.vertex] = p.z();
  check += (p.x() - p.x()) + (p.y() - p.y()) + (p.z() - p.z());
}

#if MSD_HAVE_AVX2_KERNELS
// Σ_k w_k X(corner_k) of four samples, one coordinate: the scalar interpolation's operations per lane.
// (Lambdas would not inherit the target attribute: helpers are functions.)
template <class Sample>
MSD_AVX2 inline __m256d corner_x4(const Sample* s, const double* x, long stride, int k) {
  return _mm256_set_pd(x[stride * s[3].corner[k]], x[stride * s[2].corner[k]], x[stride * s[1].corner[k]],
                       x[stride * s[0].corner[k]]);
}
template <class Sample>
MSD_AVX2 inline __m256d interpolate_x4(const Sample* s, const double* x, long stride, __m256d w0, __m256d w1,
                                       __m256d w2) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(w0, corner_x4(s, x, stride, 0)),
                                     _mm256_mul_pd(w1, corner_x4(s, x, stride, 1))),
                       _mm256_mul_pd(w2, corner_x4(s, x, stride, 2)));
}

// reconstruct_sample() for samples [begin, end), four at a time with the same operations in each lane, so
// the bits are the same. A group whose interpolated normal is too short in some lane (the face-normal
// fallback of phong::direction) runs through reconstruct_sample().
template <class Sample>
MSD_AVX2 void reconstruct_samples_x4(const Sample* samples, long begin, long end, const phong::Columns& B,
                                     const phong::Rows& N, double* ox, double* oy, double* oz, double& check) {
  static_assert(offsetof(Sample, h) == offsetof(Sample, w) + 3 * sizeof(double), "w and h are read as one row");
  __m256d checks = _mm256_setzero_pd();
  const __m256d min_length = _mm256_set1_pd(phong::kMinNormalLength);
  long k = begin;
  for (; k + 4 <= end; k += 4) {
    const Sample* s = samples + k;
    // (w0, w1, w2, h) of the four samples, transposed.
    __m256d w0 = _mm256_loadu_pd(s[0].w), w1 = _mm256_loadu_pd(s[1].w);
    __m256d w2 = _mm256_loadu_pd(s[2].w), h = _mm256_loadu_pd(s[3].w);
    transpose_x4(w0, w1, w2, h);
    const __m256d mx = interpolate_x4(s, N.p, 3, w0, w1, w2), my = interpolate_x4(s, N.p + 1, 3, w0, w1, w2),
                  mz = interpolate_x4(s, N.p + 2, 3, w0, w1, w2);
    const __m256d length = _mm256_sqrt_pd(square_sum_x4(mx, my, mz));
    if (_mm256_movemask_pd(_mm256_cmp_pd(length, min_length, _CMP_GT_OQ)) != 0xF) {
      for (int i = 0; i < 4; ++i) reconstruct_sample(s[i], B, N, ox, oy, oz, check);
      continue;
    }
    // b' + h (m / |m|), coordinate by coordinate.
    const __m256d px = _mm256_add_pd(interpolate_x4(s, B.x, 1, w0, w1, w2),
                                     _mm256_mul_pd(h, _mm256_div_pd(mx, length)));
    const __m256d py = _mm256_add_pd(interpolate_x4(s, B.y, 1, w0, w1, w2),
                                     _mm256_mul_pd(h, _mm256_div_pd(my, length)));
    const __m256d pz = _mm256_add_pd(interpolate_x4(s, B.z, 1, w0, w1, w2),
                                     _mm256_mul_pd(h, _mm256_div_pd(mz, length)));
    checks = _mm256_add_pd(checks, _mm256_add_pd(_mm256_add_pd(_mm256_sub_pd(px, px), _mm256_sub_pd(py, py)),
                                                 _mm256_sub_pd(pz, pz)));
    alignas(32) double x[4], y[4], z[4];
    _mm256_store_pd(x, px), _mm256_store_pd(y, py), _mm256_store_pd(z, pz);
    for (int i = 0; i < 4; ++i) {
      const int v = s[i].vertex;
      ox[v] = x[i], oy[v] = y[i], oz[v] = z[i];
    }
  }
  alignas(32) double lanes[4];
  _mm256_store_pd(lanes, checks);
  check += (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
  for (; k < end; ++k) reconstruct_sample(samples[k], B, N, ox, oy, oz, check);
}
#endif

}  // namespace

void NormalDisplacementOptions::validate() const {
  const std::string who = "NormalDisplacementOptions::";
  if (max_iterations < 0)
    throw InvalidInput(who + "max_iterations must be >= 0, got " + std::to_string(max_iterations));
  if (max_walks < 0) throw InvalidInput(who + "max_walks must be >= 0, got " + std::to_string(max_walks));
  if (!(tolerance > 0) || !std::isfinite(tolerance))
    throw InvalidInput(who + "tolerance must be finite and > 0, got " + format_number(tolerance));
}

NormalDisplacements::NormalDisplacements(const NormalDisplacementOptions& options) : options_(options) {
  options_.validate();  // here, not in encode(): a bad value fails before the caller loaded a mesh
}

void NormalDisplacements::encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) {
  const char* where = "NormalDisplacements::encode";
  if (Fb.rows() == 0) throw InvalidInput(std::string(where) + ": the base mesh B has no face");
  check_faces(Fb, B.rows(), where, "B");
  check_finite(S, where, "S");
  check_finite(B, where, "B");

  const int nb = static_cast<int>(B.rows());
  const long ns = static_cast<long>(S.rows());
  num_base_vertices_ = -1;  // stays "not encoded" if anything below throws
  const std::vector<char> placed = placed_mask(ns, where);  // a frame reconstructs the other vertices
  VertexNormals normals(Fb, nb);
  Positions N;
  normals.compute(B, N);
  const VertexFaces star = vertex_faces(Fb, nb);  // for walking, and for the second-chance search
  const std::vector<int> adjacency = face_adjacency(Fb, star);
  const ClosestPointQuery closest(B, Fb);
  const BasePointSearch search{B, N, Fb, adjacency, options_, options_.tolerance * bounding_box_diagonal(B)};

  const phong::Columns Bc(B), Nc(N);
  // Vertex i of S is usually close to vertex i of B (a base with S's connectivity): where B has that vertex
  // on a face, its distance bounds the closest point's and prunes the search (3x faster at 1M vertices).
  std::vector<char> on_base(nb, 0);
  for (Eigen::Index f = 0; f < Fb.rows(); ++f)
    for (int k = 0; k < 3; ++k) on_base[Fb(f, k)] = 1;
  // Each vertex of S lies over one connected piece of B and is searched for there only: a nearer part of
  // another piece (a second sheet, the far side of a UV seam) would bind it to a surface that moves
  // otherwise, and tear the result. With S's connectivity vertex i's piece is its own; on a base with other
  // connectivity (remeshed) each piece of S goes to the piece of B nearest to most of its vertices.
  // face_component stays empty where B is one piece; piece[i] = -1: anywhere (a vertex no face uses).
  std::vector<int> face_component, piece;
  std::vector<ClosestPoint> nearest;  // other connectivity: each vertex's closest point on all of B
  const std::vector<int> base_piece = vertex_components(Fb, nb);
  if (*std::max_element(base_piece.begin(), base_piece.end()) > 0) {
    face_component.resize(Fb.rows());
    for (Eigen::Index f = 0; f < Fb.rows(); ++f) face_component[f] = base_piece[Fb(f, 0)];
    if (Fs.rows() == Fb.rows() && ns == nb && Fs == Fb) {
      piece = base_piece;
    } else {
      piece = vertex_components(Fs, static_cast<int>(ns));
      nearest = closest.query_all(S);
      std::vector<std::pair<int, int>> votes;  // (piece of S, piece of B nearest to one of its vertices)
      for (long i = 0; i < ns; ++i)
        if (piece[i] >= 0) votes.emplace_back(piece[i], face_component[nearest[i].face]);
      std::sort(votes.begin(), votes.end());
      std::vector<int> chosen(*std::max_element(piece.begin(), piece.end()) + 1, -1);
      for (size_t a = 0, b = 0, most = 0; a < votes.size(); a = b) {
        while (b < votes.size() && votes[b] == votes[a]) ++b;          // one run of equal votes
        if (a == 0 || votes[a].first != votes[a - 1].first) most = 0;  // the first of a piece of S
        if (b - a > most) most = b - a, chosen[votes[a].first] = votes[a].second;
      }
      for (long i = 0; i < ns; ++i)
        if (piece[i] >= 0) piece[i] = chosen[piece[i]];
    }
  }
  Eigen::VectorXi face(ns);
  Eigen::MatrixX3d barycentric(ns, 3);
  Eigen::VectorXd height(ns);
  std::vector<char> ok(ns, 0);
  std::vector<int> iterations(ns, 0), walks(ns, 0);
  parallel_for_chunks(
      ns,
      [&](long begin, long end) {
        for (long i = begin; i < end; ++i) {
          const Vec3 p = S.row(i);
          const bool restricted = !face_component.empty() && piece[i] >= 0;
          // B's vertex i bounds the distance where it lies on the piece searched.
          const bool bounds = i < nb && on_base[i] && (!restricted || base_piece[i] == piece[i]);
          // The vote's closest point where it lies on the piece searched: a search there finds it again.
          const bool found = !nearest.empty() && (!restricted || face_component[nearest[i].face] == piece[i]);
          const ClosestPoint start =
              found ? nearest[i]
                    : closest.query(p,
                                    bounds ? (p - Bc.row(i)).norm() : std::numeric_limits<double>::infinity(),
                                    restricted ? face_component.data() : nullptr, restricted ? piece[i] : -1);
          int f = start.face;
          Vec3 w = start.barycentric;
          ok[i] = search.run(p, f, w, iterations[i], walks[i]);
          if (!ok[i]) {
            // Second chance: each face around the closest triangle's corners on its own; keep the root
            // nearest to p.
            double best = std::numeric_limits<double>::infinity();
            for (int k = 0; k < 3; ++k) {
              const int v = Fb(start.face, k);
              for (int j = star.offsets[v]; j < star.offsets[v + 1]; ++j) {
                Vec3 wt;
                if (!search.run_in_triangle(p, star.faces[j], wt)) continue;
                const double dist = (p - phong::interpolate(Bc, &Fb(star.faces[j], 0), wt)).squaredNorm();
                if (dist < best) best = dist, f = star.faces[j], w = wt, ok[i] = 1;
              }
            }
          }
          if (!ok[i]) {  // fall back to the closest point
            f = start.face;
            w = start.barycentric;
          }
          face[i] = f;
          barycentric.row(i) = w;
          const int* corners = &Fb(f, 0);
          height[i] = (p - phong::interpolate(Bc, corners, w)).dot(phong::direction(Bc, Nc, corners, w));
        }
      },
      512);

  EncodeReport report;
  for (long i = 0; i < ns; ++i) {
    report.walks += walks[i];
    if (ok[i]) {
      ++report.converged;
      report.max_iterations_used = std::max(report.max_iterations_used, iterations[i] - walks[i]);
    } else {
      ++report.fallback;
      report.fallback_vertices.push_back(static_cast<int>(i));
    }
  }

  // Counting sort of the samples by base face (stable: vertex order within a face).
  std::vector<int> first(Fb.rows() + 1, 0);
  for (long i = 0; i < ns; ++i) first[face[i] + 1] += !placed[i];
  for (Eigen::Index f = 0; f < Fb.rows(); ++f) first[f + 1] += first[f];
  std::vector<Sample> samples(first.back());
  for (long i = 0; i < ns; ++i)
    if (!placed[i])
      samples[first[face[i]]++] = Sample{{Fb(face[i], 0), Fb(face[i], 1), Fb(face[i], 2)},
                                         static_cast<int>(i),
                                         {barycentric(i, 0), barycentric(i, 1), barycentric(i, 2)},
                                         height[i]};
  if (!placed_.empty()) {  // B' normals at the corners of the samples' triangles only
    std::vector<char> read(nb, 0);
    for (const Sample& sample : samples)
      for (int corner : sample.corner) read[corner] = 1;
    std::vector<int> needed;
    for (int v = 0; v < nb; ++v)
      if (read[v]) needed.push_back(v);
    normals.restrict_to(std::move(needed));
  }

  // The warning leaves out placed vertices: they are where the caller puts them, whatever their encoding.
  reconstructed_fallbacks_.clear();
  for (int v : report.fallback_vertices)
    if (!placed[v]) reconstructed_fallbacks_.push_back(v);
  reconstructed_vertices_ = static_cast<int>(std::count(placed.begin(), placed.end(), 0));
  samples_ = std::move(samples);
  base_faces_ = Fb;
  normals_ = std::move(normals);
  normal_buffer_ = N;
  face_ = std::move(face);
  barycentric_ = std::move(barycentric);
  height_ = std::move(height);
  report_ = std::move(report);
  num_base_vertices_ = nb;
}

void NormalDisplacements::base_points(const Positions& B, Positions& out) const {
  if (!encoded()) throw UsageError("NormalDisplacements::base_points: called before encode()");
  if (B.rows() != num_base_vertices_)
    throw UsageError("NormalDisplacements::base_points: base has " + std::to_string(B.rows()) +
                     " vertices, the encoded base had " + std::to_string(num_base_vertices_));
  const long ns = static_cast<long>(face_.size());
  if (out.rows() != ns) out.resize(ns, 3);
  const phong::Columns Bc(B), W(barycentric_);
  parallel_for_chunks(ns, [&](long begin, long end) {
    for (long i = begin; i < end; ++i) out.row(i) = phong::interpolate(Bc, &base_faces_(face_[i], 0), W.row(i));
  });
}

void NormalDisplacements::reconstruct(const Positions& B_deformed, Positions& out) {
  if (!encoded()) throw UsageError("NormalDisplacements::reconstruct: called before encode()");
  check_not_aliased(B_deformed, out, "NormalDisplacements::reconstruct");
  if (B_deformed.rows() != num_base_vertices_)
    throw UsageError("NormalDisplacements::reconstruct: deformed base has " +
                     std::to_string(B_deformed.rows()) + " vertices, the encoded base had " +
                     std::to_string(num_base_vertices_));
  const long ns = static_cast<long>(face_.size());
  size_output(out, ns, "NormalDisplacements::reconstruct");
  normals_.compute(B_deformed, normal_buffer_);
  const phong::Columns Bc(B_deformed);
  const phong::Rows Nc(normal_buffer_);
  double* const ox = out.data();
  double* const oy = ox + ns;
  double* const oz = oy + ns;
  std::atomic<bool> finite{true};
  // Samples run in face order, so consecutive reads of B' stay close in memory.
  parallel_for_chunks(static_cast<long>(samples_.size()), [&](long begin, long end) {
    double check = 0;  // x − x is 0 for a finite x, NaN otherwise: one test per chunk
#if MSD_HAVE_AVX2_KERNELS
    if (cpu_has_avx2())
      reconstruct_samples_x4(samples_.data(), begin, end, Bc, Nc, ox, oy, oz, check);
    else
#endif
      for (long k = begin; k < end; ++k) reconstruct_sample(samples_[k], Bc, Nc, ox, oy, oz, check);
    if (!(check == 0)) finite = false;
  });
  if (!finite) {
    check_finite(B_deformed, "NormalDisplacements::reconstruct", "the deformed base");
    throw InvalidInput("NormalDisplacements::reconstruct: non-finite result from a finite base (overflow?)");
  }
}

Eigen::VectorXd normal_displacement_heights(const Positions& S, const Positions& B, const Faces& Fb,
                                            const NormalDisplacementOptions& options) {
  NormalDisplacements encoding(options);
  encoding.encode(S, Faces(), B, Fb);
  return encoding.heights();
}

std::vector<std::string> NormalDisplacements::encode_warnings() const {
  const std::vector<int>& fallback = reconstructed_fallbacks_;
  if (fallback.empty()) return {};
  std::string ids;
  for (size_t k = 0; k < fallback.size() && k < 5; ++k) ids += (k ? ", " : "") + std::to_string(fallback[k]);
  return {"normal displacements: " + std::to_string(fallback.size()) + " of the " +
          std::to_string(reconstructed_vertices_) +
          " vertices a frame reconstructs found no base point along the base's normals (Newton did not "
          "converge) and were encoded "
          "from their closest point on B, so the details there are not reproduced exactly (vertices " +
          ids + (fallback.size() > 5 ? ", ..." : "") + "); " + kNewtonFallbackRemedy};
}

}  // namespace msd
