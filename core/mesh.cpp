#include "msdeform/core/mesh.h"

#include <cmath>
#include <string>

#include "msdeform/core/errors.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/vector_kernels.h"

namespace msd {

Positions positions(const Mesh& mesh) {
  Positions P(mesh.n_vertices(), 3);
  for (auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    P.row(v.idx()) << p[0], p[1], p[2];
  }
  return P;
}

void set_positions(Mesh& mesh, const Positions& P) {
  if (P.rows() != static_cast<Eigen::Index>(mesh.n_vertices()))
    throw InvalidInput("set_positions: " + std::to_string(P.rows()) + " rows for a mesh of " +
                       std::to_string(mesh.n_vertices()) + " vertices");
  for (auto v : mesh.vertices()) mesh.set_point(v, Mesh::Point(P(v.idx(), 0), P(v.idx(), 1), P(v.idx(), 2)));
}

Faces faces(const Mesh& mesh) {
  Faces F(mesh.n_faces(), 3);
  for (auto f : mesh.faces()) {
    int k = 0;
    for (auto v : mesh.fv_range(f)) F(f.idx(), k++) = v.idx();
  }
  return F;
}

Mesh make_mesh(const Positions& P, const Faces& F) {
  Mesh mesh;
  mesh.reserve(P.rows(), P.rows() + F.rows(), F.rows());
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    if (!P.row(i).allFinite())
      throw InvalidInput("make_mesh: vertex " + std::to_string(i) + " has a non-finite coordinate");
    mesh.add_vertex(Mesh::Point(P(i, 0), P(i, 1), P(i, 2)));
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
    for (int idx : {a, b, c})
      if (idx < 0 || idx >= P.rows())
        throw InvalidInput("make_mesh: face " + std::to_string(f) + " has vertex index " + std::to_string(idx) +
                           " out of range [0, " + std::to_string(P.rows()) + ")");
    if (a == b || b == c || a == c)
      throw InvalidInput("make_mesh: face " + std::to_string(f) + " repeats a vertex index");
    auto fh = mesh.add_face(mesh.vertex_handle(a), mesh.vertex_handle(b), mesh.vertex_handle(c));
    if (!fh.is_valid())
      throw InvalidInput("make_mesh: face " + std::to_string(f) + " (" + std::to_string(a) + ", " +
                         std::to_string(b) + ", " + std::to_string(c) +
                         ") makes an edge or vertex non-manifold or flips orientation");
  }
  return mesh;
}

VertexNormals::VertexNormals(const Faces& F, int num_vertices) {
  // The (j, k) corner pairs of every vertex, counter-clockwise as in its faces.
  std::vector<int> count(num_vertices + 1, 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) ++count[F(f, c) + 1];
  for (int v = 0; v < num_vertices; ++v) count[v + 1] += count[v];
  std::vector<int> pairs(2 * static_cast<size_t>(count.back())), fill(count.begin(), count.end() - 1);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int at = fill[F(f, c)]++;
      pairs[2 * at] = F(f, (c + 1) % 3);
      pairs[2 * at + 1] = F(f, (c + 2) % 3);
    }
  // Chain the pairs into one fan per vertex where the vertex is manifold; keep the pairs otherwise.
  offsets_.assign(1, 0);
  kind_.assign(num_vertices, kIsolated);
  ring_.reserve(pairs.size() / 2 + num_vertices);
  std::vector<int> chain;
  std::vector<char> used;
  for (int v = 0; v < num_vertices; ++v) {
    const int* p = pairs.data() + 2 * count[v];
    const int n = count[v + 1] - count[v];
    if (n > 0) {
      // Start where no pair ends (a boundary fan), else anywhere.
      int start = 0;
      for (int a = 0; a < n; ++a) {
        bool ends_here = false;
        for (int b = 0; b < n && !ends_here; ++b) ends_here = p[2 * b + 1] == p[2 * a];
        if (!ends_here) {
          start = a;
          break;
        }
      }
      chain.assign(1, p[2 * start]);
      used.assign(n, 0);
      for (int cur = start; cur >= 0;) {
        used[cur] = 1;
        chain.push_back(p[2 * cur + 1]);
        int next = -1;
        for (int b = 0; b < n && next < 0; ++b)
          if (!used[b] && p[2 * b] == p[2 * cur + 1]) next = b;
        cur = next;
      }
      const bool all_used = static_cast<int>(chain.size()) == n + 1;
      if (all_used) {  // a closed fan repeats its first neighbour at the end
        kind_[v] = kFan;
        ring_.insert(ring_.end(), chain.begin(), chain.end());
      } else {
        kind_[v] = kFacePairs;
        ring_.insert(ring_.end(), p, p + 2 * n);
      }
    }
    offsets_.push_back(static_cast<int>(ring_.size()));
  }
  plan(nullptr);
}

void VertexNormals::compute(const Positions& P, Positions& N) const {
  if (N.rows() != static_cast<Eigen::Index>(kind_.size())) N.resize(kind_.size(), 3);
  compute_into(P, N.data(), 1, N.rows());
}

void VertexNormals::compute(const Positions& P, RowPositions& N) const {
  if (N.rows() != static_cast<Eigen::Index>(kind_.size())) N.resize(kind_.size(), 3);
  compute_into(P, N.data(), 3, 1);
}

void VertexNormals::restrict_to(std::vector<int> vertices) {
  const int num_vertices = static_cast<int>(kind_.size());
  for (size_t k = 0; k < vertices.size(); ++k)
    if (vertices[k] < 0 || vertices[k] >= num_vertices || (k > 0 && vertices[k] <= vertices[k - 1]))
      throw InvalidInput("VertexNormals::restrict_to: vertex list entry " + std::to_string(k) + " (" +
                         std::to_string(vertices[k]) + ") is out of range [0, " + std::to_string(num_vertices) +
                         ") or not ascending");
  plan(&vertices);
}

namespace {

#if MSD_HAVE_AVX2_KERNELS
// Normals of the fan groups [g0, g1) of VertexNormals (lane_vertices_, lane_ring_, lane_offsets_), four
// vertices per vector: compute_into's single-vertex operations lane by lane (no fused multiply-add), so the
// same bits.
MSD_AVX2 void fan_normals_x4(const double* px, const double* py, const double* pz, const int* vertices,
                             const int* ring, const int* offsets, long g0, long g1, double* out, long vs, long cs) {
  for (long g = g0; g < g1; ++g) {
    const int* r = ring + offsets[g];
    const int len = (offsets[g + 1] - offsets[g]) / 4;
    const int* v = vertices + 4 * g;
    const __m256d x = gather(px, v), y = gather(py, v), z = gather(pz, v);
    const int* j = r;
    __m256d ax = _mm256_sub_pd(gather(px, j), x), ay = _mm256_sub_pd(gather(py, j), y),
            az = _mm256_sub_pd(gather(pz, j), z);
    __m256d sx = _mm256_setzero_pd(), sy = sx, sz = sx;
    for (int t = 1; t < len; ++t) {
      j = r + 4 * t;
      const __m256d bx = _mm256_sub_pd(gather(px, j), x), by = _mm256_sub_pd(gather(py, j), y),
                    bz = _mm256_sub_pd(gather(pz, j), z);
      __m256d cx, cy, cz;
      cross_x4(ax, ay, az, bx, by, bz, cx, cy, cz);
      sx = _mm256_add_pd(sx, cx), sy = _mm256_add_pd(sy, cy), sz = _mm256_add_pd(sz, cz);
      ax = bx, ay = by, az = bz;
    }
    const __m256d norm = _mm256_sqrt_pd(square_sum_x4(sx, sy, sz));
    // 1 / norm where norm > 0, else 0 (a NaN norm compares false, as in the single-vertex loop)
    const __m256d inv =
        _mm256_and_pd(_mm256_cmp_pd(norm, _mm256_setzero_pd(), _CMP_GT_OQ), _mm256_div_pd(_mm256_set1_pd(1.0), norm));
    alignas(32) double n[3][4];
    _mm256_store_pd(n[0], _mm256_mul_pd(sx, inv));
    _mm256_store_pd(n[1], _mm256_mul_pd(sy, inv));
    _mm256_store_pd(n[2], _mm256_mul_pd(sz, inv));
    for (int i = 0; i < 4; ++i)
      for (int c = 0; c < 3; ++c) out[vertices[4 * g + i] * vs + c * cs] = n[c][i];
  }
}
#endif

}  // namespace

void VertexNormals::plan(const std::vector<int>* subset) {
  lane_vertices_.clear();
  lane_ring_.clear();
  lane_offsets_.assign(1, 0);
  single_.clear();
  const int count = subset ? static_cast<int>(subset->size()) : static_cast<int>(kind_.size());
  // Fans wait by length until four have it, so a group's vertices stay close in the vertex order; face
  // pairs, fans of 32 or more, the last few of each length and, without AVX2, all go one at a time.
  constexpr int kMaxLaneFan = 32;
  std::vector<int> waiting[kMaxLaneFan];
  for (int k = 0; k < count; ++k) {
    const int v = subset ? (*subset)[k] : k;
    const int len = offsets_[v + 1] - offsets_[v];
    if (!cpu_has_avx2() || kind_[v] != kFan || len >= kMaxLaneFan) {
      single_.push_back(v);
      continue;
    }
    std::vector<int>& four = waiting[len];
    four.push_back(v);
    if (four.size() < 4) continue;
    lane_vertices_.insert(lane_vertices_.end(), four.begin(), four.end());
    for (int t = 0; t < len; ++t)
      for (int u : four) lane_ring_.push_back(ring_[offsets_[u] + t]);
    lane_offsets_.push_back(static_cast<int>(lane_ring_.size()));
    four.clear();
  }
  for (const std::vector<int>& rest : waiting) single_.insert(single_.end(), rest.begin(), rest.end());
}

void VertexNormals::compute_into(const Positions& P, double* out, long vs, long cs) const {
  const double *px = P.col(0).data(), *py = P.col(1).data(), *pz = P.col(2).data();
#if MSD_HAVE_AVX2_KERNELS  // plan() makes no groups elsewhere
  const long groups = static_cast<long>(lane_offsets_.size()) - 1;
  parallel_for_chunks(groups, [&](long b, long e) {
    fan_normals_x4(px, py, pz, lane_vertices_.data(), lane_ring_.data(), lane_offsets_.data(), b, e, out, vs, cs);
  }, 1024);
#endif
  parallel_for_chunks(static_cast<long>(single_.size()), [&](long b, long e) {
    for (long k = b; k < e; ++k) {
      const long v = single_[k];
      const int* r = ring_.data() + offsets_[v];
      const int len = offsets_[v + 1] - offsets_[v];
      const double x = px[v], y = py[v], z = pz[v];
      double sx = 0, sy = 0, sz = 0;
      if (kind_[v] == kFan) {
        // Σ_t a_t × a_{t+1} with a_t = p_{r[t]} − p: each neighbour's difference is formed once.
        double ax = px[r[0]] - x, ay = py[r[0]] - y, az = pz[r[0]] - z;
        for (int t = 1; t < len; ++t) {
          const int j = r[t];
          const double bx = px[j] - x, by = py[j] - y, bz = pz[j] - z;
          sx += ay * bz - az * by;
          sy += az * bx - ax * bz;
          sz += ax * by - ay * bx;
          ax = bx, ay = by, az = bz;
        }
      } else if (kind_[v] == kFacePairs) {
        for (int t = 0; t < len; t += 2) {  // (p_i − p) × (p_j − p) per face
          const int i = r[t], j = r[t + 1];
          const double ax = px[i] - x, ay = py[i] - y, az = pz[i] - z;
          const double bx = px[j] - x, by = py[j] - y, bz = pz[j] - z;
          sx += ay * bz - az * by;
          sy += az * bx - ax * bz;
          sz += ax * by - ay * bx;
        }
      }
      const double norm = std::sqrt(sx * sx + sy * sy + sz * sz);
      const double inv = norm > 0 ? 1.0 / norm : 0.0;
      out[v * vs] = sx * inv, out[v * vs + cs] = sy * inv, out[v * vs + 2 * cs] = sz * inv;
    }
  });
}

Positions vertex_normals(const Positions& P, const Faces& F) {
  Positions N;
  VertexNormals(F, static_cast<int>(P.rows())).compute(P, N);
  return N;
}

VertexFaces vertex_faces(const Faces& F, int num_vertices) {
  VertexFaces out;
  out.offsets.assign(num_vertices + 1, 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++out.offsets[F(f, k) + 1];
  for (int v = 0; v < num_vertices; ++v) out.offsets[v + 1] += out.offsets[v];
  out.faces.resize(out.offsets.back());
  std::vector<int> fill(out.offsets.begin(), out.offsets.end() - 1);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) out.faces[fill[F(f, k)]++] = static_cast<int>(f);
  return out;
}

Vec3 bounding_box_centre(const Positions& P) {
  if (P.rows() == 0) return Vec3::Zero();
  return (0.5 * (P.colwise().minCoeff() + P.colwise().maxCoeff())).transpose();
}

double bounding_box_diagonal(const Positions& P) {
  if (P.rows() < 2) return 0.0;
  const Vec3 span = P.colwise().maxCoeff() - P.colwise().minCoeff();
  const double diagonal = span.norm();
  // Beyond about 1e±154 the squared length overflows or underflows: Eigen's scaled norm then (the plain one
  // elsewhere, so every other result stays as it was).
  return std::isfinite(diagonal) && diagonal > 1e-150 ? diagonal : span.stableNorm();
}

}  // namespace msd
