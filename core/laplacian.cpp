#include "msdeform/core/laplacian.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "msdeform/core/errors.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/region.h"

namespace msd {
namespace {

struct Corner {
  Vec3 p[3];
  double area2;  // twice the area
  bool degenerate;
};

bool degenerate_triangle(const Vec3 (&p)[3], double area2) {
  const double longest2 =
      std::max({(p[1] - p[0]).squaredNorm(), (p[2] - p[1]).squaredNorm(), (p[0] - p[2]).squaredNorm()});
  return degenerate_area(
      area2, longest2,
      std::max({p[0].cwiseAbs().maxCoeff(), p[1].cwiseAbs().maxCoeff(), p[2].cwiseAbs().maxCoeff()}));
}

}  // namespace

bool degenerate_area(double area2, double longest2, double largest_coordinate) {
  // Below the rounding of the corners' coordinates too (each within eps·m of the point meant, m their largest
  // magnitude: twice the area within about 4·eps·m·longest of its value): a zero-area triangle moved 1e6
  // from the origin came back as a needle of area 1e-9 of its edges', and changed the results.
  const double noise = 4 * std::numeric_limits<double>::epsilon() * largest_coordinate * std::sqrt(longest2);
  return !(area2 > std::max(2 * TriangleCotangents::kDegenerateAreaRatio * longest2, noise));  // also NaN
}

namespace {

Corner corner(const Positions& P, const Faces& F, Eigen::Index f) {
  Corner c;
  for (int k = 0; k < 3; ++k) c.p[k] = P.row(F(f, k));
  c.area2 = (c.p[1] - c.p[0]).cross(c.p[2] - c.p[0]).norm();
  c.degenerate = degenerate_triangle(c.p, c.area2);
  return c;
}

// A rows by (start.size() − 1) matrix in compressed storage, sized for the entries its columns will hold:
// start[c + 1] holds the count of column c on entry (start[0] = 0) and that column's first entry on return.
// The caller writes each column's row indices (ascending) and values from start[c] on.
SparseMatrix compressed_columns(Eigen::Index rows, std::vector<int>& start) {
  const long nc = static_cast<long>(start.size()) - 1;
  for (long c = 0; c < nc; ++c) start[c + 1] += start[c];
  SparseMatrix S(rows, nc);
  S.resizeNonZeros(start[nc]);
  std::copy(start.begin(), start.end(), S.outerIndexPtr());
  return S;
}

// The vertex (column of W) with the most neighbours.
Eigen::Index most_neighbours(const SparseMatrix& W) {
  Eigen::Index widest = 0;
  for (Eigen::Index j = 1; j < W.outerSize(); ++j)
    if (W.col(j).nonZeros() > W.col(widest).nonZeros()) widest = j;
  return widest;
}

// Peak memory per nonzero of such a product together with its factorisation, measured on fan disks of
// 3000 to 12000 neighbours: 34-36 bytes for the bi-Laplacian with its supernodal Cholesky factor, 47 for
// Laplacian editing's R^T R (Eigen's product) with its factor.
constexpr double kBytesPerCoupledNonzero = 48;

// Refuses `product` (which couples every two neighbours of a vertex) with `entries` nonzeros when a sparse
// matrix cannot hold them or they and the factorisation would not fit in the machine's memory (where
// the bare "out of memory" came after minutes of work), naming the vertex of most neighbours when its
// block makes up much of them, and the mesh's size otherwise.
void check_entries(const SparseMatrix& W, long long entries, int unknowns_per_vertex, const std::string& product) {
  const std::uint64_t memory = physical_memory();
  const double needed = entries * kBytesPerCoupledNonzero;
  const bool too_many = entries > std::numeric_limits<int>::max();
  if (!too_many && (memory == 0 || needed <= static_cast<double>(memory))) return;
  const Eigen::Index widest = most_neighbours(W);
  const auto gb = [](double bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f GB", bytes / 1e9);
    return std::string(text);
  };
  const std::string why =
      too_many ? " would have more than 2^31 - 1 nonzeros (the most a sparse matrix holds)"
               : " and its factorisation would need about " + gb(needed) + ", more than this machine's " +
                     gb(static_cast<double>(memory));
  const double block = static_cast<double>(unknowns_per_vertex) * static_cast<double>(W.col(widest).nonZeros());
  if (block * block < 0.25 * static_cast<double>(entries))  // many vertices, none of them a large fan
    throw InvalidInput(product + why + " for the mesh's " + std::to_string(W.cols()) +
                       " vertices; decimate the mesh or deform a coarser base");
  throw InvalidInput(product + why + ": it couples every two neighbours of a vertex, and vertex " +
                     std::to_string(widest) + " has " + std::to_string(W.col(widest).nonZeros() - 1) +
                     "; remesh so that no vertex has thousands of neighbours");
}

}  // namespace

TriangleCotangents triangle_cotangents(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Vec3 p[3] = {p0, p1, p2};
  TriangleCotangents t;
  t.area2 = (p[1] - p[0]).cross(p[2] - p[0]).norm();
  t.degenerate = degenerate_triangle(p, t.area2);
  if (t.degenerate) return t;
  for (int k = 0; k < 3; ++k) {
    t.cot[k] = (p[(k + 1) % 3] - p[k]).dot(p[(k + 2) % 3] - p[k]) / t.area2;
    if (std::abs(t.cot[k]) > LaplaceOperator::kMaxCotangent) ++t.needle_corners;
  }
  // A needle's three cotangents are scaled together, so that the largest is ±kMaxCotangent: a triangle's
  // weights stay positive semi-definite only as a whole (clamping (K', K', −K') one by one gives (K, K, −K)).
  const double largest = std::max({std::abs(t.cot[0]), std::abs(t.cot[1]), std::abs(t.cot[2])});
  const double scale = largest > LaplaceOperator::kMaxCotangent ? LaplaceOperator::kMaxCotangent / largest : 1.0;
  for (int k = 0; k < 3; ++k) t.weight[k] = scale * t.cot[k];
  return t;
}

LaplaceOperator cotan_laplacian(const Positions& P, const Faces& F) {
  const int nv = static_cast<int>(P.rows());
  LaplaceOperator out;
  out.mass = Eigen::VectorXd::Zero(nv);
  std::vector<Triplet> triplets;
  triplets.reserve(F.rows() * 12);  // four entries per corner
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3 p[3] = {P.row(F(f, 0)), P.row(F(f, 1)), P.row(F(f, 2))};
    const TriangleCotangents t = triangle_cotangents(p[0], p[1], p[2]);
    if (t.degenerate) {
      ++out.degenerate_faces;
      continue;
    }
    out.clamped_cotangents += t.needle_corners;
    const double* cot = t.weight;
    for (int k = 0; k < 3; ++k) {
      // The angle at corner k is opposite the edge (k+1, k+2).
      const int i = F(f, (k + 1) % 3), j = F(f, (k + 2) % 3);
      const double w = 0.5 * cot[k];
      triplets.emplace_back(i, j, w);
      triplets.emplace_back(j, i, w);
      triplets.emplace_back(i, i, -w);
      triplets.emplace_back(j, j, -w);
    }
    // Mixed Voronoi areas.
    const double area = 0.5 * t.area2;
    const int obtuse = cot[0] < 0 ? 0 : cot[1] < 0 ? 1 : cot[2] < 0 ? 2 : -1;
    for (int k = 0; k < 3; ++k) {
      double a;
      if (obtuse < 0) {
        const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        a = ((p[k1] - p[k]).squaredNorm() * cot[k2] + (p[k2] - p[k]).squaredNorm() * cot[k1]) / 8.0;
      } else {
        a = k == obtuse ? area / 2 : area / 4;
      }
      out.mass[F(f, k)] += a;
    }
  }
  out.W.resize(nv, nv);
  out.W.setFromTriplets(triplets.begin(), triplets.end());
  return out;
}

SparseMatrix uniform_laplacian(const Faces& F, int num_vertices) {
  std::vector<Triplet> triplets;
  triplets.reserve(F.rows() * 6);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int i = F(f, k), j = F(f, (k + 1) % 3);
      triplets.emplace_back(i, j, 1.0);
      triplets.emplace_back(j, i, 1.0);
    }
  SparseMatrix adjacency(num_vertices, num_vertices);
  // Each interior edge is seen from two faces: count it once.
  adjacency.setFromTriplets(triplets.begin(), triplets.end(), [](double, double) { return 1.0; });
  const Eigen::VectorXd degree = adjacency * Eigen::VectorXd::Ones(num_vertices);
  SparseMatrix diagonal(num_vertices, num_vertices);
  diagonal.reserve(Eigen::VectorXi::Ones(num_vertices));
  for (int i = 0; i < num_vertices; ++i) diagonal.insert(i, i) = degree[i];
  return adjacency - diagonal;
}

Eigen::VectorXd face_areas(const Positions& P, const Faces& F) {
  Eigen::VectorXd A(F.rows());
  parallel_for_chunks(F.rows(), [&](long b, long e) {
    for (long f = b; f < e; ++f) {
      const Corner c = corner(P, F, f);
      A[f] = c.degenerate ? 0.0 : 0.5 * c.area2;
    }
  });
  return A;
}

namespace {
// The area of triangle f, a sliver's too (face_areas() counts one below 1e-14 of its squared longest edge
// as degenerate: a handle translated by 1e69 stretched every free triangle into one, and the area ratio
// read 0), from edges scaled to a largest component of 1 (no overflow of the squares at any finite size).
double exact_area(const Positions& P, const Faces& F, Eigen::Index f) {
  const Vec3 p0 = P.row(F(f, 0));
  const Vec3 e1 = P.row(F(f, 1)).transpose() - p0, e2 = P.row(F(f, 2)).transpose() - p0;
  const double scale = std::max(e1.cwiseAbs().maxCoeff(), e2.cwiseAbs().maxCoeff());
  if (!(scale > 0)) return 0;
  return 0.5 * (e1 / scale).cross(e2 / scale).norm() * scale * scale;
}
}  // namespace

double free_area_ratio(const Positions& rest, const Positions& deformed, const Faces& F, const Region& region) {
  double before = 0, after = 0, all_before = 0, all_after = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const double a = exact_area(rest, F, f), b = exact_area(deformed, F, f);
    all_before += a, all_after += b;
    if (region.is_free(F(f, 0)) || region.is_free(F(f, 1)) || region.is_free(F(f, 2)))
      before += a, after += b;
  }
  return before > 0 ? after / before : all_before > 0 ? all_after / all_before : 1.0;
}

SparseMatrix gradient_operator(const Positions& P, const Faces& F) {
  std::vector<Triplet> triplets;
  triplets.reserve(F.rows() * 9);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Corner c = corner(P, F, f);
    if (c.degenerate) continue;
    const Vec3 n = (c.p[1] - c.p[0]).cross(c.p[2] - c.p[0]) / c.area2;
    for (int k = 0; k < 3; ++k) {
      // grad φ_k = n × (p_{k+2} - p_{k+1}) / (2A): perpendicular to the opposite edge, pointing at corner k.
      const Vec3 g = n.cross(c.p[(k + 2) % 3] - c.p[(k + 1) % 3]) / c.area2;
      for (int d = 0; d < 3; ++d) triplets.emplace_back(3 * f + d, F(f, k), g[d]);
    }
  }
  SparseMatrix G(3 * F.rows(), P.rows());
  G.setFromTriplets(triplets.begin(), triplets.end());
  return G;
}

SparseMatrix divergence_operator(const Positions& P, const Faces& F) {
  const Eigen::VectorXd area = face_areas(P, F);
  Eigen::VectorXd area3(3 * F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f) area3.segment<3>(3 * f).setConstant(area[f]);
  SparseMatrix D = -(gradient_operator(P, F).transpose() * area3.asDiagonal());
  return D;
}

SparseMatrix submatrix(const SparseMatrix& A, const std::vector<int>& rows, const std::vector<int>& cols) {
  // Straight into compressed storage, column by column on both cores (setFromTriplets took 0.5 s per call
  // at 1M vertices); rows within a column ascend in the new numbering, as setFromTriplets leaves them.
  std::vector<int> row_map(A.rows(), -1);
  for (size_t r = 0; r < rows.size(); ++r) row_map[rows[r]] = static_cast<int>(r);
  const long nc = static_cast<long>(cols.size());
  std::vector<int> start(static_cast<size_t>(nc) + 1, 0);
  parallel_for_chunks(nc, [&](long begin, long end) {
    for (long c = begin; c < end; ++c)
      for (SparseMatrix::InnerIterator it(A, cols[c]); it; ++it) start[c + 1] += row_map[it.row()] >= 0;
  });
  SparseMatrix S = compressed_columns(static_cast<Eigen::Index>(rows.size()), start);
  int* index = S.innerIndexPtr();
  double* value = S.valuePtr();
  parallel_for_chunks(nc, [&](long begin, long end) {
    std::vector<std::pair<int, double>> column;
    for (long c = begin; c < end; ++c) {
      column.clear();
      for (SparseMatrix::InnerIterator it(A, cols[c]); it; ++it)
        if (row_map[it.row()] >= 0) column.emplace_back(row_map[it.row()], it.value());
      std::sort(column.begin(), column.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      for (size_t k = 0; k < column.size(); ++k) index[start[c] + k] = column[k].first, value[start[c] + k] = column[k].second;
    }
  });
  return S;
}

LaplaceOperator laplace_operator(const Positions& P, const Faces& F, LaplacianWeights weights) {
  LaplaceOperator op;
  const int nv = static_cast<int>(P.rows());
  if (weights == LaplacianWeights::Cotan) {
    LaplaceOperator lap = cotan_laplacian(P, F);
    op.W = std::move(lap.W);
    op.mass = std::move(lap.mass);
    return op;
  }
  op.W = uniform_laplacian(F, nv);
  const double h = mean_edge_length(P, F);
  // On a regular triangulation with edge h the umbrella D⁻¹W applied to x² + y² gives h², while Δ gives 4.
  op.mass = -op.W.diagonal() * (h * h / 4.0);
  return op;
}

double mean_edge_length(const Positions& P, const Faces& F) {
  if (F.rows() == 0) return 0;
  double sum = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) sum += (P.row(F(f, k)) - P.row(F(f, (k + 1) % 3))).norm();
  return sum / (3.0 * static_cast<double>(F.rows()));
}

double signed_volume(const Positions& P, const Faces& F) {
  // Tetrahedra from the bounding box's centre, not the origin: the same sum for a closed mesh, without
  // the cancellation of terms of size |p|³ (the knight at an offset of 1e6 read −199.8 for 0.0245).
  if (P.rows() == 0) return 0;
  const Vec3 o = bounding_box_centre(P);
  double six_volume = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = P.row(F(f, 0)).transpose() - o, b = P.row(F(f, 1)).transpose() - o,
               c = P.row(F(f, 2)).transpose() - o;
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6.0;
}

SparseMatrix weighted_square(const SparseMatrix& W, const Eigen::VectorXd& w) {
  // Gustavson's column-by-column product, as Eigen's W * (diag(w) W) and summing in the same order (so
  // bit for bit the same), on both cores: Eigen's runs on one (1.6 s at 1M vertices). W is symmetric, so
  // column k of W is also its row k. First the size of each column's pattern, then its values.
  const long n = W.cols();
  struct Workspace {
    std::vector<double> value;
    std::vector<long> seen;  // the last column (pass 1: j, pass 2: n + j) that reached each row
    std::vector<int> rows;
  };
  tbb::enumerable_thread_specific<Workspace> workspaces(
      [n] { return Workspace{std::vector<double>(n), std::vector<long>(n, -1), {}}; });
  check_neighbour_coupling(W, 1, "the bi-Laplacian W M^-1 W");  // a vertex alone too many: before the count
  std::vector<int> start(static_cast<size_t>(n) + 1, 0);
  parallel_for_chunks(n, [&](long begin, long end) {
    Workspace& ws = workspaces.local();
    for (long j = begin; j < end; ++j)
      for (SparseMatrix::InnerIterator kt(W, j); kt; ++kt)
        for (SparseMatrix::InnerIterator it(W, kt.row()); it; ++it)
          if (ws.seen[it.row()] != j) ws.seen[it.row()] = j, ++start[j + 1];
  }, 1024);
  long long entries = 0;
  for (long j = 0; j < n; ++j) entries += start[j + 1];
  check_entries(W, entries, 1, "the bi-Laplacian W M^-1 W");
  SparseMatrix Q = compressed_columns(n, start);
  int* index = Q.innerIndexPtr();
  double* value = Q.valuePtr();
  parallel_for_chunks(n, [&](long begin, long end) {
    Workspace& ws = workspaces.local();
    for (long j = begin; j < end; ++j) {
      ws.rows.clear();
      for (SparseMatrix::InnerIterator kt(W, j); kt; ++kt) {
        const double y = w[kt.row()] * kt.value();  // (diag(w) W)_kj
        for (SparseMatrix::InnerIterator it(W, kt.row()); it; ++it) {
          const int i = static_cast<int>(it.row());
          if (ws.seen[i] != n + j) {
            ws.seen[i] = n + j;
            ws.value[i] = it.value() * y;
            ws.rows.push_back(i);
          } else {
            ws.value[i] += it.value() * y;
          }
        }
      }
      std::sort(ws.rows.begin(), ws.rows.end());
      for (size_t k = 0; k < ws.rows.size(); ++k) index[start[j] + k] = ws.rows[k], value[start[j] + k] = ws.value[ws.rows[k]];
    }
  }, 1024);
  return Q;
}

void check_neighbour_coupling(const SparseMatrix& W, int unknowns_per_vertex, const std::string& product) {
  const Eigen::Index widest = most_neighbours(W);
  const long long block =
      W.outerSize() > 0 ? unknowns_per_vertex * static_cast<long long>(W.col(widest).nonZeros()) : 0;
  check_entries(W, block * block, unknowns_per_vertex, product);
}

SparseMatrix polyharmonic_matrix(const LaplaceOperator& op, int k) {
  if (k < 1 || k > 3)
    throw InvalidInput("polyharmonic_matrix: order " + std::to_string(k) + " (expected 1, 2 or 3)");
  if (k == 1) return -op.W;
  const Eigen::VectorXd inv_mass = op.mass.unaryExpr([](double m) { return m > 0 ? 1.0 / m : 0.0; });
  SparseMatrix Q = weighted_square(op.W, inv_mass);  // W M⁻¹ W = M Δ²
  if (k == 3) {                                      // −W M⁻¹ W M⁻¹ W = −M Δ³
    const SparseMatrix L = inv_mass.asDiagonal() * op.W;  // Δ = M⁻¹W
    Q = -SparseMatrix(Q * L);
  }
  return Q;
}

const char* to_string(LaplacianWeights weights) {
  return weights == LaplacianWeights::Cotan ? "cotan" : "uniform";
}

}  // namespace msd
