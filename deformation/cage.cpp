#include "msdeform/deformation/cage.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <utility>

#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/solver.h"
#include "msdeform/core/subdivision.h"

namespace msd {

namespace {

constexpr double kPi = 3.14159265358979323846;

inline double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// What is wrong with a cage's topology or geometry, or "" when it is a closed, edge-manifold, consistently
// oriented triangle mesh without zero-area faces or unreferenced vertices. *volume: its signed volume.
std::string cage_problem(const Positions& P, const Faces& F, double* volume) {
  const long nv = P.rows(), nf = F.rows();
  if (nv < 4 || nf < 4)
    return "a closed cage needs at least 4 vertices and 4 faces (got " + std::to_string(nv) + " and " +
           std::to_string(nf) + ")";
  const double diag = bounding_box_diagonal(P);
  std::vector<char> used(nv, 0);
  std::map<std::pair<int, int>, int> directed;  // (from, to) -> face
  double vol = 0;
  for (long f = 0; f < nf; ++f) {
    const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
    if (a == b || b == c || c == a) return "face " + std::to_string(f) + " repeats a vertex";
    const Vec3 pa = P.row(a), pb = P.row(b), pc = P.row(c);
    const Vec3 n = (pb - pa).cross(pc - pa);
    if (!(n.norm() > 1e-12 * diag * diag))
      return "face " + std::to_string(f) + " (vertices " + std::to_string(a) + ", " + std::to_string(b) +
             ", " + std::to_string(c) + ") has zero area";
    vol += pa.dot(pb.cross(pc)) / 6;
    used[a] = used[b] = used[c] = 1;
    for (int k = 0; k < 3; ++k) {
      const int from = F(f, k), to = F(f, (k + 1) % 3);
      auto [it, inserted] = directed.emplace(std::make_pair(from, to), static_cast<int>(f));
      if (!inserted)
        return "edge (" + std::to_string(from) + ", " + std::to_string(to) +
               ") is used in the same direction by faces " + std::to_string(it->second) + " and " +
               std::to_string(f) + ": the cage is non-manifold there or not consistently oriented";
    }
  }
  for (const auto& [e, f] : directed)
    if (!directed.count({e.second, e.first}))
      return "edge (" + std::to_string(e.first) + ", " + std::to_string(e.second) + ") of face " +
             std::to_string(f) + " has no opposite face: the cage is not closed there";
  for (long v = 0; v < nv; ++v)
    if (!used[v]) return "vertex " + std::to_string(v) + " is in no face";
  if (!(std::abs(vol) > 1e-12 * diag * diag * diag)) return "the cage encloses no volume";
  if (volume) *volume = vol;
  return "";
}

}  // namespace

// =====================================================================================================
// Mean value coordinates

MeanValueCage::MeanValueCage(const Positions& cage_P, const Faces& cage_F) : P_(cage_P) {
  check_mesh_arrays(cage_P, cage_F, "mean value coordinates");
  if (cage_P.rows() == 0 || cage_F.rows() == 0)
    throw InvalidInput("mean value coordinates: the cage is empty");
  const double diag = bounding_box_diagonal(cage_P);
  tol_ = 1e-13 * diag;
  centre_ = cage_P.colwise().mean().transpose();
  scale_ = diag > 0 ? diag : 1.0;
  unit_ = (cage_P.rowwise() - centre_.transpose()) / scale_;
  Eigen::Matrix4d gram = Eigen::Matrix4d::Zero();
  for (Eigen::Index l = 0; l < cage_P.rows(); ++l) {
    Eigen::Vector4d a(1, unit_(l, 0), unit_(l, 1), unit_(l, 2));
    gram += a * a.transpose();
  }
  gram_inv_ = gram.inverse();
  if (!gram_inv_.allFinite() ||
      !(std::abs(gram.determinant()) > 1e-14 * std::pow(static_cast<double>(cage_P.rows()), 4)))
    throw InvalidInput("mean value coordinates: the cage vertices are coplanar");
  std::map<std::pair<int, int>, int> edge_id;
  faces_.resize(cage_F.rows());
  for (Eigen::Index f = 0; f < cage_F.rows(); ++f) {
    Face& t = faces_[f];
    for (int k = 0; k < 3; ++k) t.v[k] = cage_F(f, k);
    for (int k = 0; k < 3; ++k) {
      const int a = std::min(t.v[(k + 1) % 3], t.v[(k + 2) % 3]),
                b = std::max(t.v[(k + 1) % 3], t.v[(k + 2) % 3]);
      auto [it, inserted] = edge_id.emplace(std::make_pair(a, b), static_cast<int>(edges_.size()));
      if (inserted) {
        edges_.push_back({a, b});
        edge_len_.push_back((P_.row(a) - P_.row(b)).norm());
      }
      t.e[k] = it->second;
    }
    const Vec3 p0 = P_.row(t.v[0]), p1 = P_.row(t.v[1]), p2 = P_.row(t.v[2]);
    const Vec3 N = (p1 - p0).cross(p2 - p0);
    t.area2 = N.norm();
    if (!(t.area2 > 1e-14 * diag * diag))
      throw InvalidInput("mean value coordinates: cage face " + std::to_string(f) + " has zero area");
    t.n = N / t.area2;
    Vec3 E[3];
    for (int k = 0; k < 3; ++k) {
      E[k] = Vec3(P_.row(t.v[(k + 2) % 3])) - Vec3(P_.row(t.v[(k + 1) % 3]));
      t.q[k] = E[k].cross(t.n);
      t.edge_len[k] = E[k].norm();
    }
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) t.gram[j][k] = E[j].dot(E[k]);
  }
}

void MeanValueCage::coordinates(const Vec3& x, MeanValueWorkspace& ws, double* w) const {
  const int m = num_vertices(), ne = num_edges();
  ws.r.resize(3 * m);
  ws.d.resize(m);
  ws.u.resize(3 * m);
  ws.g.resize(ne);
  ws.theta.resize(ne);
  std::fill(w, w + m, 0.0);
  double* r = ws.r.data();
  double* u = ws.u.data();
  double* d = ws.d.data();
  for (int l = 0; l < m; ++l) {
    for (int c = 0; c < 3; ++c) r[3 * l + c] = P_(l, c) - x[c];
    d[l] = std::sqrt(dot3(r + 3 * l, r + 3 * l));
    if (d[l] <= tol_) {  // on a vertex
      w[l] = 1;
      return;
    }
    for (int c = 0; c < 3; ++c) u[3 * l + c] = r[3 * l + c] / d[l];
  }
  // Per edge: the angle θ it subtends at x, from half-angle chords (accurate for every angle), and
  // g = θ / |r_a × r_b| = (θ / sin θ) / (d_a d_b).
  for (int e = 0; e < ne; ++e) {
    const int a = edges_[e].first, b = edges_[e].second;
    const double* ua = u + 3 * a;
    const double* ub = u + 3 * b;
    double s2 = 0, c2 = 0;
    for (int c = 0; c < 3; ++c) {
      s2 += (ua[c] - ub[c]) * (ua[c] - ub[c]);
      c2 += (ua[c] + ub[c]) * (ua[c] + ub[c]);
    }
    const double s = std::sqrt(s2), co = std::sqrt(c2);  // 2 sin(θ/2), 2 cos(θ/2)
    const double theta = 2 * std::atan2(s, co), sin_theta = 0.5 * s * co;
    if (co < s &&
        d[a] * d[b] * sin_theta <= tol_ * edge_len_[e]) {  // on the edge (obtuse angle: between a and b)
      w[a] = d[b] / (d[a] + d[b]);
      w[b] = d[a] / (d[a] + d[b]);
      return;
    }
    ws.theta[e] = theta;
    ws.g[e] = (s > 0 ? theta / sin_theta : 1.0) / (d[a] * d[b]);
  }
  const double face_tol = 0.25 * tol_;
  for (const Face& t : faces_) {
    const double* rv[3] = {r + 3 * t.v[0], r + 3 * t.v[1], r + 3 * t.v[2]};
    // Signed distance η of x from the face's plane, from the nearest corner.
    int nearest = 0;
    if (d[t.v[1]] < d[t.v[nearest]]) nearest = 1;
    if (d[t.v[2]] < d[t.v[nearest]]) nearest = 2;
    const double eta = -dot3(t.n.data(), rv[nearest]);
    double a[3];  // twice the signed areas (x's projection, edge k): λ_k = a_k / area2
    for (int k = 0; k < 3; ++k) a[k] = dot3(rv[(k + 1) % 3], t.q[k].data());
    if (std::abs(eta) <= face_tol) {
      if (a[0] >= 0 && a[1] >= 0 && a[2] >= 0) {  // on the face: its barycentric coordinates
        std::fill(w, w + m, 0.0);
        const double sum = a[0] + a[1] + a[2];
        for (int k = 0; k < 3; ++k) w[t.v[k]] = a[k] / sum;
        return;
      }
      continue;  // in the face's plane outside it: the face is seen edge-on and contributes nothing
    }
    const double g[3] = {ws.g[t.e[0]], ws.g[t.e[1]], ws.g[t.e[2]]};
    // 2 m⊥ = Σ θ_k a_k / L_k, L_k = |r_{k+1} × r_{k+2}| = sqrt(a_k² + η² |E_k|²).
    double mperp2 = g[0] * a[0] + g[1] * a[1] + g[2] * a[2];
    const bool outside = !(a[0] > 0 && a[1] > 0 && a[2] > 0);
    // Thin: x is close to the plane compared with its in-plane distance to every edge line (L_k ≈ |a_k|).
    const bool thin = std::abs(eta) * t.edge_len[0] < 0.25 * std::abs(a[0]) &&
                      std::abs(eta) * t.edge_len[1] < 0.25 * std::abs(a[1]) &&
                      std::abs(eta) * t.edge_len[2] < 0.25 * std::abs(a[2]);
    if (outside && thin &&
        std::abs(mperp2) < 0.125 * (std::abs(g[0] * a[0]) + std::abs(g[1] * a[1]) + std::abs(g[2] * a[2]))) {
      // A thin spherical triangle (x near the face's plane, outside the face): the sum cancels. With s_k the
      // sign of a_k, φ_k the angle edge k subtends at the projection (Σ s_k φ_k = 0 outside the face) and
      // κ_k = 1 − |a_k| / L_k, 2 m⊥ = Σ s_k (θ_k − φ_k) − Σ s_k θ_k κ_k, every term O(η²) and accurate.
      mperp2 = 0;
      const double eta2 = eta * eta;
      for (int k = 0; k < 3; ++k) {
        const double s = a[k] > 0 ? 1.0 : -1.0, abs_a = std::abs(a[k]), len2 = t.edge_len[k] * t.edge_len[k];
        const double L = std::sqrt(a[k] * a[k] + eta2 * len2);
        const double kappa = eta2 * len2 / (L * (L + abs_a));
        const double* r1 = rv[(k + 1) % 3];
        const double* r2 = rv[(k + 2) % 3];
        double C = 0;  // in-plane dot product of the two corners seen from the projection
        for (int c = 0; c < 3; ++c) C += (r1[c] + eta * t.n[c]) * (r2[c] + eta * t.n[c]);
        // θ − φ = atan2(L, C + η²) − atan2(|a|, C), by the difference formula without cancellation
        const double dtheta = std::atan2(eta2 * (C * len2 / (L + abs_a) - abs_a), (C + eta2) * C + L * abs_a);
        mperp2 += s * (dtheta - ws.theta[t.e[k]] * kappa);
      }
    }
    // w_j = −(m⊥/η) λ_j + ∇λ_j · m∥, with m∥ = −(η/2) n × Σ_k g_k E_k and ∇λ_j = (n × E_j) / area2.
    const double inv = 1.0 / (2 * t.area2);
    for (int j = 0; j < 3; ++j) {
      const double EjV = t.gram[j][0] * g[0] + t.gram[j][1] * g[1] + t.gram[j][2] * g[2];
      w[t.v[j]] -= (mperp2 * a[j] / eta + eta * EjV) * inv;
    }
  }
  double total = 0;
  for (int l = 0; l < m; ++l) total += w[l];
  // total > 0 inside the cage and < 0 outside (signed 1/distance along every ray); never 0 off the surface.
  if (!(std::abs(total) > 0) || !std::isfinite(total))
    throw SolverError("mean value coordinates: the weights at (" + format_number(x[0]) + ", " +
                      format_number(x[1]) + ", " + format_number(x[2]) +
                      ") do not normalise: they underflow or overflow there (a point "
                      "very far from the cage, or on it to rounding)");
  const double inv_total = 1.0 / total;
  for (int l = 0; l < m; ++l) w[l] *= inv_total;
  // Far from the cage the weights of front and back faces cancel in Σ w (it falls like 1/D⁴, each weight
  // like 1/D³), and the per-face round-off (relative ε·D/edge) is amplified by that. The least-norm
  // correction onto Σ w = 1, Σ w c = x removes what is left of it (O(|residual|), ≤ 1e-12 of the diagonal
  // within a diagonal of the cage) so partition of unity and linear precision hold to round-off everywhere.
  double rho[4] = {1, (x[0] - centre_[0]) / scale_, (x[1] - centre_[1]) / scale_,
                   (x[2] - centre_[2]) / scale_};
  for (int l = 0; l < m; ++l) {
    rho[0] -= w[l];
    for (int c = 0; c < 3; ++c) rho[c + 1] -= w[l] * unit_(l, c);
  }
  double delta[4];
  for (int i = 0; i < 4; ++i)
    delta[i] = gram_inv_(i, 0) * rho[0] + gram_inv_(i, 1) * rho[1] + gram_inv_(i, 2) * rho[2] +
               gram_inv_(i, 3) * rho[3];
  for (int l = 0; l < m; ++l)
    w[l] += delta[0] + delta[1] * unit_(l, 0) + delta[2] * unit_(l, 1) + delta[3] * unit_(l, 2);
}

double MeanValueCage::winding_number(const Vec3& x) const {
  double sum = 0;
  for (const Face& t : faces_) {
    const Vec3 r0 = Vec3(P_.row(t.v[0])) - x, r1 = Vec3(P_.row(t.v[1])) - x, r2 = Vec3(P_.row(t.v[2])) - x;
    const double d0 = r0.norm(), d1 = r1.norm(), d2 = r2.norm();
    // Van Oosterom & Strackee: tan(Ω/2) = det / (d0 d1 d2 + (r0·r1) d2 + (r1·r2) d0 + (r2·r0) d1); the
    // determinant from the face normal, which does not cancel near the face.
    const double det = r0.dot(t.n) * t.area2;
    const double den = d0 * d1 * d2 + r0.dot(r1) * d2 + r1.dot(r2) * d0 + r2.dot(r0) * d1;
    sum += 2 * std::atan2(det, den);
  }
  return sum / (4 * kPi);
}

void mean_value_coordinates(const Positions& cage_P, const Faces& cage_F, const Vec3& x, double* w) {
  const MeanValueCage cage(cage_P, cage_F);
  MeanValueWorkspace ws;
  cage.coordinates(x, ws, w);
}

// =====================================================================================================
// Harmonic coordinates

namespace {

// Squared distance from p to the triangle (a, b, c), by the Voronoi regions of its corners and edges.
double point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (ap - (d1 / (d1 - d3)) * ab).squaredNorm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (ap - (d2 / (d2 - d6)) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (bp - ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)).squaredNorm();
  const double denom = 1.0 / (va + vb + vc);
  return (ap - (vb * denom) * ab - (vc * denom) * ac).squaredNorm();
}

}  // namespace

struct HarmonicCoordinates::Impl {
  MeanValueCage mvc;
  Vec3 origin;
  double h = 0;
  Eigen::Vector3i n;        // nodes per axis
  std::vector<int> row_of;  // per node: its row in `values`, or -1 (far outside: MVC on demand)
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> values;  // stored nodes × #C
  int inside = 0, boundary = 0;
  double seconds = 0;

  long node(int i, int j, int k) const {
    return i + static_cast<long>(n[0]) * (j + static_cast<long>(n[1]) * k);
  }
  Vec3 position(long id) const {
    const long i = id % n[0], j = (id / n[0]) % n[1], k = id / (static_cast<long>(n[0]) * n[1]);
    return origin + h * Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
  }
};

HarmonicCoordinates::HarmonicCoordinates(const Positions& cage_P, const Faces& cage_F, int resolution)
    : impl_(std::make_unique<Impl>()) {
  const char* who = "harmonic coordinates";
  if (resolution < 4 || resolution > CageOptions::kMaxHarmonicResolution)
    throw InvalidInput(std::string(who) + ": the resolution must be in 4.." +
                       std::to_string(CageOptions::kMaxHarmonicResolution) + " cells (got " +
                       std::to_string(resolution) + ")");
  const auto t0 = std::chrono::steady_clock::now();
  Impl& g = *impl_;
  g.mvc = MeanValueCage(cage_P, cage_F);
  const int m = g.mvc.num_vertices();
  const Vec3 lo = cage_P.colwise().minCoeff(), hi = cage_P.colwise().maxCoeff();
  const Vec3 extent = hi - lo;
  g.h = extent.maxCoeff() / resolution;
  // The box plus a cell on every side, centred on the cage.
  for (int a = 0; a < 3; ++a) {
    const int cells = static_cast<int>(std::ceil(extent[a] / g.h - 1e-9)) + 2;
    g.n[a] = cells + 1;
    g.origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * cells * g.h;
  }
  const long num_nodes = static_cast<long>(g.n[0]) * g.n[1] * g.n[2];

  // Near-boundary nodes: within half a cell diagonal of a cage face.
  enum : char { kUnknown = 0, kNear = 1, kOutside = 2, kInside = 3 };
  std::vector<char> cls(num_nodes, kUnknown);
  const double radius = 0.5 * std::sqrt(3.0) * g.h, radius2 = radius * radius;
  for (Eigen::Index f = 0; f < cage_F.rows(); ++f) {
    const Vec3 a = cage_P.row(cage_F(f, 0)), b = cage_P.row(cage_F(f, 1)), c = cage_P.row(cage_F(f, 2));
    const Vec3 flo = a.cwiseMin(b).cwiseMin(c) - Vec3::Constant(radius);
    const Vec3 fhi = a.cwiseMax(b).cwiseMax(c) + Vec3::Constant(radius);
    int i0[3], i1[3];
    for (int ax = 0; ax < 3; ++ax) {
      i0[ax] = std::max(0, static_cast<int>(std::ceil((flo[ax] - g.origin[ax]) / g.h)));
      i1[ax] = std::min(g.n[ax] - 1, static_cast<int>(std::floor((fhi[ax] - g.origin[ax]) / g.h)));
    }
    for (int k = i0[2]; k <= i1[2]; ++k)
      for (int j = i0[1]; j <= i1[1]; ++j)
        for (int i = i0[0]; i <= i1[0]; ++i) {
          const long id = g.node(i, j, k);
          if (cls[id] != kNear && point_triangle_distance2(g.position(id), a, b, c) <= radius2)
            cls[id] = kNear;
        }
  }
  // Outside: a 6-connected flood fill from a corner (one cell beyond the cage's box, so never near) through
  // nodes that are not near-boundary. Two 6-neighbours that are both farther than half a cell from the
  // surface cannot have it between them, so the fill does not leak inside.
  const long strides[6] = {
      1, -1, g.n[0], -g.n[0], static_cast<long>(g.n[0]) * g.n[1], -static_cast<long>(g.n[0]) * g.n[1]};
  auto neighbour = [&](long id, int dir) -> long {
    const long i = id % g.n[0], j = (id / g.n[0]) % g.n[1], k = id / (static_cast<long>(g.n[0]) * g.n[1]);
    const long c[3] = {i, j, k};
    const long next = c[dir / 2] + (dir % 2 == 0 ? 1 : -1);
    if (next < 0 || next >= g.n[dir / 2]) return -1;
    return id + strides[dir];
  };
  std::vector<long> stack = {0};
  cls[0] = kOutside;
  while (!stack.empty()) {
    const long id = stack.back();
    stack.pop_back();
    for (int dir = 0; dir < 6; ++dir) {
      const long nb = neighbour(id, dir);
      if (nb >= 0 && cls[nb] == kUnknown) {
        cls[nb] = kOutside;
        stack.push_back(nb);
      }
    }
  }
  // Stored nodes: inside (solved), near-boundary and the outside nodes next to them (MVC), so that cells
  // around the cage interpolate from memory; other outside nodes are evaluated on demand.
  std::vector<long> inside_nodes, mvc_nodes;
  for (long id = 0; id < num_nodes; ++id)
    if (cls[id] == kUnknown) {
      cls[id] = kInside;
      inside_nodes.push_back(id);
    }
  std::vector<char> stored(num_nodes, 0);
  for (long id = 0; id < num_nodes; ++id) {
    if (cls[id] == kInside) {
      stored[id] = 1;
      continue;
    }
    bool keep = cls[id] == kNear;
    const long i = id % g.n[0], j = (id / g.n[0]) % g.n[1], k = id / (static_cast<long>(g.n[0]) * g.n[1]);
    for (int dk = -1; dk <= 1 && !keep; ++dk)
      for (int dj = -1; dj <= 1 && !keep; ++dj)
        for (int di = -1; di <= 1 && !keep; ++di) {
          const long a = i + di, b = j + dj, c = k + dk;
          if (a < 0 || b < 0 || c < 0 || a >= g.n[0] || b >= g.n[1] || c >= g.n[2]) continue;
          const char nc = cls[g.node(static_cast<int>(a), static_cast<int>(b), static_cast<int>(c))];
          keep = nc == kNear || nc == kInside;
        }
    if (keep) {
      stored[id] = 1;
      mvc_nodes.push_back(id);
    }
  }
  g.inside = static_cast<int>(inside_nodes.size());
  g.boundary = static_cast<int>(std::count(cls.begin(), cls.end(), kNear));
  const double bytes = 8.0 * static_cast<double>(inside_nodes.size() + mvc_nodes.size()) * m;
  if (bytes > 4e9)
    throw InvalidInput(std::string(who) + ": " + std::to_string(static_cast<long>(bytes / 1e6)) +
                       " MB of node values (" + std::to_string(inside_nodes.size() + mvc_nodes.size()) +
                       " nodes × " + std::to_string(m) +
                       " cage vertices); lower the grid resolution (harmonic_resolution) or use fewer cage vertices");
  g.row_of.assign(num_nodes, -1);
  int rows = 0;
  for (long id = 0; id < num_nodes; ++id)
    if (stored[id]) g.row_of[id] = rows++;
  g.values.resize(rows, m);

  // Dirichlet data: MVC at the near-boundary and adjacent outside nodes.
  parallel_for_chunks(
      static_cast<long>(mvc_nodes.size()),
      [&](long begin, long end) {
        MeanValueWorkspace ws;
        for (long i = begin; i < end; ++i) {
          const long id = mvc_nodes[i];
          g.mvc.coordinates(g.position(id), ws, g.values.row(g.row_of[id]).data());
        }
      },
      64);

  // Inside nodes: the 7-point Laplace equation, Σ_nb (u_nb − u_i) = 0, with the near-boundary neighbours
  // known.
  if (!inside_nodes.empty()) {
    std::vector<int> var_of(num_nodes, -1);
    std::vector<long> var_node;
    for (long id : inside_nodes) {
      var_of[id] = static_cast<int>(var_node.size());
      var_node.push_back(id);
    }
    std::vector<int> known;
    std::vector<Triplet> triplets;
    for (long id : inside_nodes) {
      for (int dir = 0; dir < 6; ++dir) {
        const long nb = neighbour(id, dir);
        if (nb < 0 || cls[nb] == kOutside)
          throw SolverError(std::string(who) + ": inside node " + std::to_string(id) +
                            " touches the outside (a bug)");
        if (cls[nb] == kInside && nb < id) continue;  // each inside pair once
        if (var_of[nb] < 0) {
          var_of[nb] = static_cast<int>(var_node.size());
          var_node.push_back(nb);
          known.push_back(var_of[nb]);
        }
        const int a = var_of[id], b = var_of[nb];
        triplets.push_back({a, a, 1.0});
        triplets.push_back({b, b, 1.0});
        triplets.push_back({a, b, -1.0});
        triplets.push_back({b, a, -1.0});
      }
    }
    const int nvar = static_cast<int>(var_node.size());
    SparseMatrix Q(nvar, nvar);
    Q.setFromTriplets(triplets.begin(), triplets.end());
    ConstrainedQuadratic system;
    system.prepare(Q, known);
    Eigen::MatrixXd known_values(known.size(), m), x;
    for (size_t c = 0; c < known.size(); ++c)
      known_values.row(c) = g.values.row(g.row_of[var_node[known[c]]]);
    system.solve(known_values, x);
    for (long id : inside_nodes) g.values.row(g.row_of[id]) = x.row(var_of[id]);
    if (!g.values.allFinite())
      throw SolverError(std::string(who) + ": the grid solve gave non-finite values");
  }
  g.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

HarmonicCoordinates::~HarmonicCoordinates() = default;

int HarmonicCoordinates::num_vertices() const { return impl_->mvc.num_vertices(); }
Eigen::Vector3i HarmonicCoordinates::grid_size() const { return impl_->n; }
double HarmonicCoordinates::cell_size() const { return impl_->h; }
int HarmonicCoordinates::num_inside_nodes() const { return impl_->inside; }
int HarmonicCoordinates::num_boundary_nodes() const { return impl_->boundary; }
double HarmonicCoordinates::solve_seconds() const { return impl_->seconds; }

void HarmonicCoordinates::coordinates(const Vec3& x, double* w) const {
  const Impl& g = *impl_;
  const int m = g.mvc.num_vertices();
  int cell[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double t = (x[a] - g.origin[a]) / g.h;
    const double c = std::clamp(std::floor(t), 0.0, static_cast<double>(g.n[a] - 2));
    cell[a] = static_cast<int>(c);
    f[a] = std::clamp(t - c, 0.0, 1.0);
  }
  std::fill(w, w + m, 0.0);
  thread_local MeanValueWorkspace ws;
  thread_local std::vector<double> on_demand;
  for (int corner = 0; corner < 8; ++corner) {
    const int di = corner & 1, dj = (corner >> 1) & 1, dk = (corner >> 2) & 1;
    const double wt = (di ? f[0] : 1 - f[0]) * (dj ? f[1] : 1 - f[1]) * (dk ? f[2] : 1 - f[2]);
    if (wt == 0) continue;
    const long id = g.node(cell[0] + di, cell[1] + dj, cell[2] + dk);
    const double* values;
    if (g.row_of[id] >= 0) {
      values = g.values.row(g.row_of[id]).data();
    } else {
      on_demand.resize(m);
      g.mvc.coordinates(g.position(id), ws, on_demand.data());
      values = on_demand.data();
    }
    for (int l = 0; l < m; ++l) w[l] += wt * values[l];
  }
}

// =====================================================================================================
// Cages

Faces check_cage(const Positions& cage_P, const Faces& cage_F, const char* who, bool* flipped) {
  check_mesh_arrays(cage_P, cage_F, who);
  double volume = 0;
  const std::string problem = cage_problem(cage_P, cage_F, &volume);
  if (!problem.empty())
    throw InvalidInput(std::string(who) + ": " + problem +
                       " (a cage must be a closed, manifold, consistently oriented triangle mesh)");
  Faces F = cage_F;
  if (volume < 0) F.col(1).swap(F.col(2));
  if (flipped) *flipped = volume < 0;
  return F;
}

namespace {

// A convex polytope as a list of outward (counter-clockwise seen from outside) polygons.
using Polygon = std::vector<Vec3>;

bool lex_less(const Vec3& a, const Vec3& b) {
  return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}

// Keeps the part of the polytope with d·y <= offset and closes it with the cap polygon on the plane.
// Points within tol of the plane count as on it. An edge crossing the plane is cut at a point computed
// from its lexicographically ordered endpoints, so the two polygons sharing the edge get the same point.
void clip_polytope(std::vector<Polygon>& polys, const Vec3& dir, double offset, double tol) {
  std::vector<Polygon> out;
  std::vector<Vec3> cap;
  auto side = [&](const Vec3& p) {
    const double s = dir.dot(p) - offset;
    return s > tol ? 1 : (s < -tol ? -1 : 0);
  };
  for (const Polygon& poly : polys) {
    Polygon kept;
    const size_t k = poly.size();
    for (size_t i = 0; i < k; ++i) {
      const Vec3& p = poly[i];
      const Vec3& q = poly[(i + 1) % k];
      const int sp = side(p), sq = side(q);
      if (sp <= 0) kept.push_back(p);
      if (sp == 0) cap.push_back(p);
      if (sp * sq < 0) {
        const bool swap = lex_less(q, p);
        const Vec3& a = swap ? q : p;
        const Vec3& b = swap ? p : q;
        const double sa = dir.dot(a) - offset, sb = dir.dot(b) - offset;
        const Vec3 x = a + (sa / (sa - sb)) * (b - a);
        kept.push_back(x);
        cap.push_back(x);
      }
    }
    if (kept.size() >= 3) out.push_back(std::move(kept));
  }
  std::sort(cap.begin(), cap.end(), lex_less);
  cap.erase(std::unique(cap.begin(), cap.end()), cap.end());
  if (cap.size() >= 3) {
    Vec3 centre = Vec3::Zero();
    for (const Vec3& p : cap) centre += p;
    centre /= static_cast<double>(cap.size());
    const Vec3 e1 = dir.unitOrthogonal(), e2 = dir.cross(e1);
    std::vector<std::pair<double, Vec3>> around;
    for (const Vec3& p : cap) around.push_back({std::atan2((p - centre).dot(e2), (p - centre).dot(e1)), p});
    std::sort(around.begin(), around.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    Polygon poly;
    for (const auto& [angle, p] : around) poly.push_back(p);
    out.push_back(std::move(poly));
  }
  polys.swap(out);
}

// offset_kdop_cage for points whose bounding box is centred at the origin.
void kdop_cage_near_origin(const Positions& P, double margin, int subdivisions, Positions& cage_P, Faces& cage_F) {
  const char* who = "offset_kdop_cage";
  if (P.rows() == 0) throw InvalidInput(std::string(who) + ": no points to enclose");
  check_finite(P, who, "the points");
  if (!(margin > 0 && margin <= 10))
    throw InvalidInput(std::string(who) + ": margin must be in (0, 10] (got " + format_number(margin) + ")");
  if (subdivisions < 0 || subdivisions > 4)
    throw InvalidInput(std::string(who) + ": subdivisions must be in 0..4 (got " +
                       std::to_string(subdivisions) + ")");
  const double diag = bounding_box_diagonal(P);
  if (!(diag > 0)) throw InvalidInput(std::string(who) + ": all points coincide; a cage needs an extent");
  const double offset = margin * diag, tol = 1e-9 * diag;
  const Vec3 lo = Vec3(P.colwise().minCoeff()) - Vec3::Constant(offset);
  const Vec3 hi = Vec3(P.colwise().maxCoeff()) + Vec3::Constant(offset);

  // The grown bounding box: its 6 faces are the axis planes of the 26-DOP.
  std::vector<Polygon> polys;
  auto corner = [&](int i, int j, int k) {
    return Vec3(i ? hi.x() : lo.x(), j ? hi.y() : lo.y(), k ? hi.z() : lo.z());
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int s = 0; s < 2; ++s) {
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      Polygon poly;
      const int square[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (const auto& sq : square) {
        int idx[3];
        idx[axis] = s;
        idx[a1] = sq[0];
        idx[a2] = sq[1];
        poly.push_back(corner(idx[0], idx[1], idx[2]));
      }
      // (a1, a2, axis) is right-handed: counter-clockwise about +axis; reverse on the low side.
      if (s == 0) std::reverse(poly.begin(), poly.end());
      polys.push_back(std::move(poly));
    }
  // The 20 other directions: edges (two non-zero components) and corners (three).
  std::vector<Vec3> dirs;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k)
        if (std::abs(i) + std::abs(j) + std::abs(k) >= 2) dirs.push_back(Vec3(i, j, k).normalized());
  for (const Vec3& dir : dirs) {
    const double support = (P * dir).maxCoeff();
    clip_polytope(polys, dir, support + offset, tol);
  }

  // Merge coincident vertices, drop repeated corners, fan-triangulate.
  std::vector<Vec3> verts;
  auto vertex_id = [&](const Vec3& p) {
    for (size_t i = 0; i < verts.size(); ++i)
      if ((verts[i] - p).norm() <= tol) return static_cast<int>(i);
    verts.push_back(p);
    return static_cast<int>(verts.size()) - 1;
  };
  std::vector<std::vector<int>> loops;
  for (const Polygon& poly : polys) {
    std::vector<int> loop;
    for (const Vec3& p : poly) {
      const int id = vertex_id(p);
      if (loop.empty() || loop.back() != id) loop.push_back(id);
    }
    while (loop.size() > 1 && loop.front() == loop.back()) loop.pop_back();
    if (loop.size() >= 3) loops.push_back(std::move(loop));
  }
  std::vector<Eigen::Vector3i> tris;
  const double area_tol = 1e-12 * diag * diag;
  for (const auto& loop : loops) {
    const int k = static_cast<int>(loop.size());
    auto corner_at = [&](int i) {
      const Vec3& p = verts[loop[(i + k - 1) % k]];
      const Vec3& c = verts[loop[i % k]];
      const Vec3& q = verts[loop[(i + 1) % k]];
      return (p - c).cross(q - c).norm() > area_tol;
    };
    // Fan from a corner whose neighbours are corners too: then no fan triangle has zero area (in a convex
    // polygon only vertices on the apex's own edges can be collinear with it). Else fan from the centroid.
    int apex = -1;
    for (int i = 0; i < k && apex < 0; ++i)
      if (corner_at(i) && corner_at(i + 1) && corner_at(i + k - 1)) apex = i;
    if (apex >= 0) {
      for (int i = 1; i + 1 < k; ++i) {
        const int a = loop[apex], b = loop[(apex + i) % k], c = loop[(apex + i + 1) % k];
        if ((verts[b] - verts[a]).cross(verts[c] - verts[a]).norm() > area_tol) tris.push_back({a, b, c});
      }
    } else {
      Vec3 centre = Vec3::Zero();
      for (int id : loop) centre += verts[id];
      verts.push_back(centre / k);
      const int c = static_cast<int>(verts.size()) - 1;
      for (int i = 0; i < k; ++i)
        if ((verts[loop[i]] - verts[c]).cross(verts[loop[(i + 1) % k]] - verts[c]).norm() > area_tol)
          tris.push_back({c, loop[i], loop[(i + 1) % k]});
    }
  }
  cage_P.resize(static_cast<Eigen::Index>(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) cage_P.row(i) = verts[i].transpose();
  cage_F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t i = 0; i < tris.size(); ++i) cage_F.row(i) = tris[i].transpose();
  // Midpoint subdivision (core/subdivision.h's linear refinement): every triangle into four, the cage
  // keeps its shape with more control vertices.
  if (subdivisions > 0) {
    const LoopRefinement refined = loop_refine(cage_F, static_cast<int>(cage_P.rows()), subdivisions);
    cage_P = refined.linear * cage_P;
    cage_F = refined.faces;
  }

  double volume = 0;
  const std::string problem = cage_problem(cage_P, cage_F, &volume);
  if (!problem.empty())
    throw SolverError(std::string(who) + ": the generated cage is broken (a bug): " + problem);
  if (!(volume > 0)) throw SolverError(std::string(who) + ": the generated cage is inward-oriented (a bug)");
  // Every point strictly inside: below every polygon's plane (they are the polytope's facets).
  for (const auto& loop : loops) {
    Vec3 n = Vec3::Zero(), centre = Vec3::Zero();
    for (size_t i = 0; i < loop.size(); ++i) {
      n += verts[loop[i]].cross(verts[loop[(i + 1) % loop.size()]]);
      centre += verts[loop[i]];
    }
    n.normalize();
    centre /= static_cast<double>(loop.size());
    const double limit = n.dot(centre) - 0.5 * offset;
    std::atomic<long> bad{-1};
    parallel_for_chunks(P.rows(), [&](long begin, long end) {
      for (long i = begin; i < end; ++i)
        if (!(P.row(i).dot(n) <= limit)) bad = i;
    });
    if (bad >= 0)
      throw SolverError(std::string(who) + ": point " + std::to_string(bad.load()) +
                        " is not inside the generated cage (a bug)");
  }
}

}  // namespace

void offset_kdop_cage(const Positions& P, double margin, int subdivisions, Positions& cage_P, Faces& cage_F) {
  // Built around the bounding box's centre: the support values d·x of a model far from the origin
  // (1e8 away) would lose the margin and the clipping tolerance to rounding.
  check_finite(P, "offset_kdop_cage", "the points");
  const Eigen::RowVector3d centre = bounding_box_centre(P).transpose();
  kdop_cage_near_origin(P.rowwise() - centre, margin, subdivisions, cage_P, cage_F);
  cage_P.rowwise() += centre;
}

// =====================================================================================================
// The deformer

CageDeformer::CageDeformer(CageOptions options) : options_(std::move(options)) {
  const char* who = "cage";
  name_ = options_.coordinates == CageCoordinates::MeanValue ? "cage-mvc" : "cage-harmonic";
  options_.least_norm.validate(name_);  // here, not in prepare() (fifth break test)
  if (!(options_.margin > 0 && options_.margin <= 10))
    throw InvalidInput(std::string(who) + ": margin must be in (0, 10] (got " +
                       format_number(options_.margin) + ")");
  if (options_.subdivisions < 0 || options_.subdivisions > 4)
    throw InvalidInput(std::string(who) + ": subdivisions must be in 0..4 (got " +
                       std::to_string(options_.subdivisions) + ")");
  if (options_.harmonic_resolution < 4 || options_.harmonic_resolution > CageOptions::kMaxHarmonicResolution)
    throw InvalidInput(std::string(who) + ": harmonic_resolution must be in 4.." +
                       std::to_string(CageOptions::kMaxHarmonicResolution) + " (got " +
                       std::to_string(options_.harmonic_resolution) + ")");
  if ((options_.cage_P.rows() == 0) != (options_.cage_F.rows() == 0))
    throw InvalidInput(std::string(who) + ": a user cage needs both cage_P and cage_F (got " +
                       std::to_string(options_.cage_P.rows()) + " vertices and " +
                       std::to_string(options_.cage_F.rows()) + " faces)");
}

CageDeformer::~CageDeformer() = default;

Positions CageDeformer::control_points() const {
  if (cage_P_.rows() == 0) throw UsageError(name_ + ": control_points() before prepare()");
  return cage_P_;
}

void CageDeformer::fit_basis(const Positions& P, const Region&) {
  const bool user_cage = options_.cage_P.rows() > 0;
  harmonic_.reset();
  // The cage and its coordinates are built relative to a centre (the coordinates are translation-invariant):
  // a shape far from the origin keeps its digits (at an offset of 1e8 sizes the automatic cage and the
  // harmonic coordinates lost 20 times the input's rounding).
  Positions centred_cage;
  if (user_cage) {
    const std::string who = name_ + ": the user cage";
    cage_F_ = check_cage(options_.cage_P, options_.cage_F, who.c_str());
    cage_P_ = options_.cage_P;
    cage_origin_ = bounding_box_centre(cage_P_);
    centred_cage = cage_P_.rowwise() - cage_origin_.transpose();
  } else {
    cage_origin_ = bounding_box_centre(P);
    offset_kdop_cage(P.rowwise() - cage_origin_.transpose(), options_.margin, options_.subdivisions,
                     centred_cage, cage_F_);
    cage_P_ = centred_cage.rowwise() + cage_origin_.transpose();
  }
  mvc_ = MeanValueCage(centred_cage, cage_F_);
  if (user_cage) {
    std::atomic<long> outside{0};
    parallel_for_chunks(
        P.rows(),
        [&](long begin, long end) {
          long count = 0;
          for (long i = begin; i < end; ++i)
            count += mvc_.winding_number(P.row(i).transpose() - cage_origin_) < 0.5;
          outside += count;
        },
        256);
    if (outside > 0)
      prepare_warnings_.push_back(
          name_ + ": " + std::to_string(outside.load()) + " of " + std::to_string(P.rows()) +
          " points lie outside the cage; the deformation extrapolates there (enlarge the "
          "cage to enclose them)");
  }
  if (options_.coordinates == CageCoordinates::Harmonic)
    harmonic_ = std::make_unique<HarmonicCoordinates>(centred_cage, cage_F_, options_.harmonic_resolution);
}

std::string CageDeformer::overshoot_advice() const {
  return "constraints with different motions pull on the same cage vertices, which the least-norm solve "
         "amplifies: give a cage drawn around the parts that move (--cage), or use rbf";
}

void CageDeformer::basis(const Vec3& x, BasisRow& row) const {
  const int m = basis_size();
  row.index.resize(m);
  row.value.resize(m);
  std::iota(row.index.begin(), row.index.end(), 0);
  const Vec3 centred = x - cage_origin_;
  if (harmonic_) {
    harmonic_->coordinates(centred, row.value.data());
  } else {
    thread_local MeanValueWorkspace ws;
    mvc_.coordinates(centred, ws, row.value.data());
  }
}

}  // namespace msd
