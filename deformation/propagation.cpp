#include "deformation/propagation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <utility>

#include <Eigen/SVD>

#include "core/checks.h"
#include "core/errors.h"
#include "core/laplacian.h"
#include "core/parallel.h"
#include "core/solver.h"

namespace msd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------------
// Exact nearest-point distances: a balanced k-d tree (median split on the widest axis, small leaves).

class KdTree {
 public:
  KdTree(const Positions& P, const std::vector<int>& ids) {
    points_.reserve(ids.size());
    for (int v : ids) points_.emplace_back(P.row(v).transpose());
    nodes_.reserve(2 * ids.size() / kLeafSize + 2);
    if (!points_.empty()) build(0, static_cast<int>(points_.size()));
  }

  //! Distance from q to the nearest stored point (+∞ for an empty tree).
  double nearest_distance(const Vec3& q) const {
    if (nodes_.empty()) return kInf;
    double best2 = kInf;
    struct Entry {
      int node;
      double bound2;  // squared distance from q to the node's bounding box
    };
    std::array<Entry, 128> stack;  // one pending sibling per level: depth <= log2(2^31 / kLeafSize) + 1
    int top = 0;
    stack[top++] = {0, box_distance2(nodes_[0], q)};
    while (top > 0) {
      const Entry e = stack[--top];
      if (e.bound2 >= best2) continue;
      const Node& n = nodes_[e.node];
      if (n.left < 0) {
        for (int i = n.begin; i < n.end; ++i) best2 = std::min(best2, (points_[i] - q).squaredNorm());
        continue;
      }
      const double dl = box_distance2(nodes_[n.left], q), dr = box_distance2(nodes_[n.right], q);
      // Push the farther child first so the nearer one is searched first and tightens best2.
      if (dl < dr) {
        stack[top++] = {n.right, dr};
        stack[top++] = {n.left, dl};
      } else {
        stack[top++] = {n.left, dl};
        stack[top++] = {n.right, dr};
      }
    }
    return std::sqrt(best2);
  }

 private:
  static constexpr int kLeafSize = 8;
  struct Node {
    int begin, end;
    int left = -1, right = -1;  // children; left < 0 for a leaf
    Vec3 lo, hi;                // bounding box of the node's points
  };

  static double box_distance2(const Node& n, const Vec3& q) {
    return (n.lo - q).cwiseMax(q - n.hi).cwiseMax(0.0).squaredNorm();
  }

  int build(int begin, int end) {
    Vec3 lo = points_[begin], hi = lo;
    for (int i = begin + 1; i < end; ++i) {
      lo = lo.cwiseMin(points_[i]);
      hi = hi.cwiseMax(points_[i]);
    }
    const int id = static_cast<int>(nodes_.size());
    nodes_.push_back({begin, end, -1, -1, lo, hi});
    if (end - begin <= kLeafSize) return id;
    int axis;
    (hi - lo).maxCoeff(&axis);
    const int mid = begin + (end - begin) / 2;
    std::nth_element(points_.begin() + begin, points_.begin() + mid, points_.begin() + end,
                     [axis](const Vec3& a, const Vec3& b) { return a[axis] < b[axis]; });
    const int left = build(begin, mid);
    const int right = build(mid, end);
    nodes_[id].left = left;
    nodes_[id].right = right;
    return id;
  }

  std::vector<Vec3> points_;
  std::vector<Node> nodes_;
};

//! #V distances from every vertex of P to the nearest vertex of `set` (+∞ when set is empty).
Eigen::VectorXd euclidean_distance(const Positions& P, const std::vector<int>& set) {
  Eigen::VectorXd d(P.rows());
  const KdTree tree(P, set);
  parallel_for_chunks(P.rows(), [&](long b, long e) {
    for (long i = b; i < e; ++i) d[i] = tree.nearest_distance(P.row(i).transpose());
  });
  return d;
}

// ---------------------------------------------------------------------------------------------------

//! Vertex adjacency (CSR) of the edges that carry cotan weights, i.e. of the non-degenerate faces.
struct EdgeGraph {
  std::vector<int> offsets, neighbours;
  std::vector<double> lengths;
};

EdgeGraph edge_graph(const SparseMatrix& W, const Positions& P) {
  EdgeGraph g;
  g.offsets.assign(W.outerSize() + 1, 0);
  for (int j = 0; j < W.outerSize(); ++j) {
    for (SparseMatrix::InnerIterator it(W, j); it; ++it)
      if (it.row() != j) {
        g.neighbours.push_back(static_cast<int>(it.row()));
        g.lengths.push_back((P.row(it.row()) - P.row(j)).norm());
      }
    g.offsets[j + 1] = static_cast<int>(g.neighbours.size());
  }
  return g;
}

//! Shortest paths along edges from the nearest source (Dijkstra): an upper bound of the geodesic distance,
//! +∞ where no source is reachable.
Eigen::VectorXd graph_distance(const EdgeGraph& g, const std::vector<int>& sources) {
  const int n = static_cast<int>(g.offsets.size()) - 1;
  Eigen::VectorXd d = Eigen::VectorXd::Constant(n, kInf);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  for (int s : sources) {
    d[s] = 0;
    queue.push({0.0, s});
  }
  while (!queue.empty()) {
    const auto [dist, v] = queue.top();
    queue.pop();
    if (dist > d[v]) continue;
    for (int k = g.offsets[v]; k < g.offsets[v + 1]; ++k) {
      const int w = g.neighbours[k];
      const double candidate = dist + g.lengths[k];
      if (candidate < d[w]) {
        d[w] = candidate;
        queue.push({candidate, w});
      }
    }
  }
  return d;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Heat method

struct HeatGeodesics::Impl {
  HeatGeodesicsOptions options;
  int n = 0;
  SparseMatrix W, G, D;
  Eigen::VectorXd mass;
  EdgeGraph graph;
  double h = 0;  // mean edge length
  SparseSPDSolver heat;
  int heat_doublings = -1;  // how often t = m·h² was doubled for the factored heat operator (-1: none yet)
  double t_last = 0;

  // Largest graph distance, in units of √t, for which exp(−d/√t) stays far above double underflow.
  static constexpr double kMaxStepsOfSqrtT = 500;

  Impl(const Positions& P, const Faces& F, HeatGeodesicsOptions o) : options(o), n(static_cast<int>(P.rows())) {
    if (!(o.time_factor > 0) || !std::isfinite(o.time_factor))
      throw InvalidInput("HeatGeodesics: time_factor must be positive and finite (got " + std::to_string(o.time_factor) + ")");
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        if (F(f, k) < 0 || F(f, k) >= n)
          throw InvalidInput("HeatGeodesics: face " + std::to_string(f) + " refers to vertex " + std::to_string(F(f, k)) +
                             " of a mesh with " + std::to_string(n) + " vertices");
    LaplaceOperator lap = cotan_laplacian(P, F);
    W = std::move(lap.W);
    mass = std::move(lap.mass);
    G = gradient_operator(P, F);
    D = divergence_operator(P, F);
    graph = edge_graph(W, P);
    h = graph.lengths.empty() ? 0.0
                              : std::accumulate(graph.lengths.begin(), graph.lengths.end(), 0.0) / graph.lengths.size();
  }

  void factor_heat(int doublings, double t) {
    // (M − t·W) is SPD when every vertex has mass; a vertex without non-degenerate faces has an empty row,
    // so give it a mass (it is its own component: u there is δ/mass and its distance is 0 or +∞).
    const double fallback_mass = mass.sum() > 0 ? mass.sum() / n : 1.0;
    SparseMatrix A = -t * W;
    Eigen::VectorXd diag = mass;
    for (int i = 0; i < n; ++i)
      if (!(diag[i] > 0)) diag[i] = fallback_mass;
    A += SparseMatrix(diag.asDiagonal());
    try {
      heat.factor(A);
    } catch (const SolverError& e) {
      // M > 0 and −W >= 0, so this is a numerical breakdown (e.g. coordinates of wildly different scales).
      throw SolverError("HeatGeodesics: factoring the heat operator M - tW failed near vertex " +
                            std::to_string(e.index()) + "; try a larger time_factor",
                        e.index());
    }
    heat_doublings = doublings;
  }

  Eigen::VectorXd distance(const std::vector<int>& sources) {
    Eigen::VectorXd phi = Eigen::VectorXd::Constant(n, kInf);
    if (sources.empty()) return phi;
    std::vector<char> is_source(n, 0);
    std::vector<int> unique_sources;
    for (int s : sources) {
      if (s < 0 || s >= n)
        throw InvalidInput("HeatGeodesics::distance: source vertex " + std::to_string(s) + " out of range [0, " +
                           std::to_string(n) + ")");
      if (!is_source[s]) unique_sources.push_back(s);
      is_source[s] = 1;
    }
    const Eigen::VectorXd graph_dist = graph_distance(graph, unique_sources);
    double reach = 0;
    for (int i = 0; i < n; ++i)
      if (std::isfinite(graph_dist[i])) reach = std::max(reach, graph_dist[i]);

    // Time step: m·h², doubled until the farthest reachable vertex is within kMaxStepsOfSqrtT·√t.
    double t = options.time_factor * h * h;
    int doublings = 0;
    while (t > 0 && reach > kMaxStepsOfSqrtT * std::sqrt(t) && doublings < 200) {
      t *= 2;
      ++doublings;
    }
    if (doublings != heat_doublings) factor_heat(doublings, t);
    t_last = t;

    // 1. Heat flow from the sources.
    Eigen::MatrixXd delta = Eigen::MatrixXd::Zero(n, 1), u;
    for (int s : unique_sources) delta(s, 0) = 1.0;
    heat.solve(delta, u);

    // 2. Normalised negative gradient per face.
    Eigen::VectorXd X = G * u.col(0);
    const Eigen::Index nf = X.size() / 3;
    parallel_for_chunks(nf, [&](long b, long e) {
      for (long f = b; f < e; ++f) {
        auto g = X.segment<3>(3 * f);
        // Scale before normalising: far from the sources u is ~1e-200, and squaring that underflows.
        const double largest = g.cwiseAbs().maxCoeff();
        if (largest > 0 && std::isfinite(largest)) {
          g /= largest;
          g = -g / g.norm();
        } else {
          g.setZero();
        }
      }
    });

    // 3. Poisson problem W φ = div X, φ = 0 on the sources; unreachable vertices are pinned too (their
    // component has no Dirichlet value) and reported as +∞.
    std::vector<int> known = unique_sources;
    for (int i = 0; i < n; ++i)
      if (!std::isfinite(graph_dist[i])) known.push_back(i);
    const Eigen::MatrixXd divergence = D * X;
    ConstrainedQuadratic poisson;
    try {
      poisson.prepare(-W, known);
    } catch (const SolverError& e) {
      throw SolverError("HeatGeodesics: the Poisson system is singular at vertex " + std::to_string(e.index()) +
                            " (its edges all have zero cotan weight, e.g. its faces are degenerate)",
                        e.index());
    }
    Eigen::MatrixXd x;
    poisson.solve(Eigen::MatrixXd::Zero(known.size(), 1), x, &divergence);
    for (int i = 0; i < n; ++i) {
      if (!std::isfinite(graph_dist[i]))
        phi[i] = kInf;
      else if (is_source[i])
        phi[i] = 0;
      else if (!std::isfinite(x(i, 0)))
        throw SolverError("HeatGeodesics: non-finite distance at vertex " + std::to_string(i), i);
      else
        phi[i] = std::max(0.0, x(i, 0));
    }
    return phi;
  }
};

HeatGeodesics::HeatGeodesics(const Positions& P, const Faces& F, HeatGeodesicsOptions options)
    : impl_(std::make_unique<Impl>(P, F, options)) {}
HeatGeodesics::~HeatGeodesics() = default;
HeatGeodesics::HeatGeodesics(HeatGeodesics&&) noexcept = default;
HeatGeodesics& HeatGeodesics::operator=(HeatGeodesics&&) noexcept = default;

Eigen::VectorXd HeatGeodesics::distance(const std::vector<int>& sources) { return impl_->distance(sources); }
double HeatGeodesics::mean_edge_length() const { return impl_->h; }
double HeatGeodesics::last_time_step() const { return impl_->t_last; }

Eigen::VectorXd geodesic_distance(const Positions& P, const Faces& F, const std::vector<int>& sources,
                                  HeatGeodesicsOptions options) {
  HeatGeodesics solver(P, F, options);
  return solver.distance(sources);
}

// ---------------------------------------------------------------------------------------------------
// Fields

namespace {

//! #V by h raw fields: exactly 1 on handle k in column k, exactly 0 on fixed vertices and other handles.
Eigen::MatrixXd raw_fields(const Positions& P, const Faces& F, const Region& region, PropagationField field,
                           const HeatGeodesicsOptions& heat) {
  const int n = static_cast<int>(P.rows()), nh = region.num_handles();
  Eigen::MatrixXd S(n, nh);
  switch (field) {
    case PropagationField::Harmonic: {
      // (9.2): minimise the Dirichlet energy ½ sᵀ(−W)s with s fixed on the constrained vertices; its
      // minimiser satisfies (W s)_i = 0, i.e. Δs = 0, at every free vertex.
      if (nh == 1 && region.fixed_vertices().empty()) {
        S.setOnes();  // nothing to blend towards: the exact solution, without round-off
        break;
      }
      const std::vector<int> constrained = region.constrained_vertices();
      Eigen::MatrixXd values = Eigen::MatrixXd::Zero(constrained.size(), nh);
      for (size_t c = 0; c < constrained.size(); ++c) {
        const int k = region.handle_of(constrained[c]);
        if (k >= 0) values(c, k) = 1.0;
      }
      ConstrainedQuadratic laplace;
      try {
        laplace.prepare(-cotan_laplacian(P, F).W, constrained);
      } catch (const SolverError& e) {
        throw SolverError("propagate (harmonic field): the Laplace system is singular at vertex " +
                              std::to_string(e.index()) + " (a free vertex whose faces all have zero area?)",
                          e.index());
      }
      laplace.solve(values, S);
      break;
    }
    case PropagationField::Euclidean:
    case PropagationField::Geodesic: {
      // Distances to the fixed part (column 0) and to every handle (column 1 + j).
      Eigen::MatrixXd dist(n, nh + 1);
      std::vector<std::vector<int>> sets = {region.fixed_vertices()};
      for (int j = 0; j < nh; ++j) sets.push_back(region.handle_vertices(j));
      if (field == PropagationField::Euclidean) {
        for (size_t c = 0; c < sets.size(); ++c) dist.col(c) = euclidean_distance(P, sets[c]);
      } else {
        HeatGeodesics geodesics(P, F, heat);
        for (size_t c = 0; c < sets.size(); ++c) dist.col(c) = geodesics.distance(sets[c]);
      }
      // (9.1) per handle k, with dist_F = distance to fixed ∪ other handles = min of their distances.
      parallel_for_chunks(n, [&](long b, long e) {
        for (long i = b; i < e; ++i)
          for (int k = 0; k < nh; ++k) {
            double to_zero = dist(i, 0);
            for (int j = 0; j < nh; ++j)
              if (j != k) to_zero = std::min(to_zero, dist(i, 1 + j));
            const double to_handle = dist(i, 1 + k);
            double s;
            if (std::isinf(to_zero))
              s = 1.0;  // nothing holds this part back (or nothing at all is reachable)
            else if (std::isinf(to_handle))
              s = 0.0;
            else if (to_zero + to_handle > 0)
              s = to_zero / (to_zero + to_handle);
            else
              s = 0.5;  // a vertex on top of both a handle and a zero-set vertex
            S(i, k) = s;
          }
      });
      break;
    }
    default:
      throw InvalidInput("propagate: unknown PropagationField value " + std::to_string(static_cast<int>(field)));
  }
  if (!S.allFinite()) throw SolverError("propagate: the propagation field is not finite (ill-conditioned system)");
  // Clamp (round-off and, for the harmonic field, the maximum principle's failure where cotan weights are
  // negative), then impose the constraints exactly.
  S = S.cwiseMax(0.0).cwiseMin(1.0);
  for (int i = 0; i < n; ++i)
    if (!region.is_free(i)) {
      S.row(i).setZero();
      const int k = region.handle_of(i);
      if (k >= 0) S(i, k) = 1.0;
    }
  return S;
}

}  // namespace

Eigen::VectorXd propagation_field(const Positions& P, const Faces& F, const Region& region, PropagationField field,
                                  int handle) {
  check_mesh_arrays(P, F, "propagation_field");
  region.validate(static_cast<int>(P.rows()), &F);
  if (handle < 0 || handle >= region.num_handles())
    throw InvalidInput("propagation_field: handle " + std::to_string(handle) + " requested, the region has " +
                       std::to_string(region.num_handles()) + " handle(s)");
  return raw_fields(P, F, region, field, HeatGeodesicsOptions{}).col(handle);
}

// ---------------------------------------------------------------------------------------------------
// Deformer

TransformationPropagation::TransformationPropagation(PropagationOptions options) : options_(std::move(options)) {
  if (options_.transfer == PropagationTransfer::Custom && !options_.custom_transfer)
    throw InvalidInput("propagate: transfer is PropagationTransfer::Custom but custom_transfer is empty");
  if (options_.transfer != PropagationTransfer::Custom && options_.custom_transfer)
    throw InvalidInput("propagate: custom_transfer is set but transfer is not PropagationTransfer::Custom; set "
                       "transfer = Custom to use it");
  if (options_.transfer != PropagationTransfer::Linear && options_.transfer != PropagationTransfer::SmoothStep &&
      options_.transfer != PropagationTransfer::Custom)
    throw InvalidInput("propagate: unknown PropagationTransfer value");
  if (options_.blend != PropagationBlend::Matrix && options_.blend != PropagationBlend::Decomposed)
    throw InvalidInput("propagate: unknown PropagationBlend value");
  if (!(options_.geodesic.time_factor > 0) || !std::isfinite(options_.geodesic.time_factor))
    throw InvalidInput("propagate: geodesic.time_factor must be positive and finite (got " +
                       std::to_string(options_.geodesic.time_factor) + ")");
}

void TransformationPropagation::do_prepare(const Positions& P, const Faces& F, const Region& region) {
  const int n = static_cast<int>(P.rows()), nh = region.num_handles();
  Eigen::MatrixXd S = raw_fields(P, F, region, options_.field, options_.geodesic);

  // Transfer function on free vertices only: constrained vertices keep exactly 1 / 0.
  if (options_.transfer != PropagationTransfer::Linear) {
    for (int i = 0; i < n; ++i) {
      if (!region.is_free(i)) continue;
      for (int k = 0; k < nh; ++k) {
        const double s = S(i, k);
        double v;
        if (options_.transfer == PropagationTransfer::SmoothStep) {
          v = s * s * (3.0 - 2.0 * s);
        } else {
          v = options_.custom_transfer(s);
          if (!(v >= 0.0 && v <= 1.0))
            throw InvalidInput("propagate: custom_transfer(" + std::to_string(s) + ") = " + std::to_string(v) +
                               " at vertex " + std::to_string(i) + " (handle " + std::to_string(k) +
                               "); a transfer function must map [0, 1] into [0, 1]");
        }
        S(i, k) = v;
      }
    }
  }
  // Keep every vertex a combination of p and the T_k(p) with weights summing to at most 1.
  for (int i = 0; i < n; ++i) {
    const double sum = S.row(i).sum();
    if (sum > 1.0) S.row(i) /= sum;
  }

  std::vector<Vec3> centroids(nh, Vec3::Zero());
  std::vector<int> counts(nh, 0);
  for (int i = 0; i < n; ++i) {
    const int k = region.handle_of(i);
    if (k < 0) continue;
    centroids[k] += P.row(i).transpose();
    ++counts[k];
  }
  for (int k = 0; k < nh; ++k) centroids[k] /= counts[k];  // validate() guarantees non-empty handles

  rest_ = P;
  weights_ = std::move(S);
  centroids_ = std::move(centroids);
  frames_.assign(nh, HandleFrame{});
}

void TransformationPropagation::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  const int nh = static_cast<int>(transforms.size());
  const bool decomposed = options_.blend == PropagationBlend::Decomposed;
  for (int k = 0; k < nh; ++k) {
    HandleFrame& f = frames_[k];
    const Mat3 A = transforms[k].topLeftCorner<3, 3>();
    f.linear_minus_identity = A - Mat3::Identity();
    f.translation = transforms[k].topRightCorner<3, 1>();
    if (!decomposed) continue;
    f.centroid = centroids_[k];
    f.centroid_motion = A * f.centroid + f.translation - f.centroid;
    if (A == Mat3::Identity()) {
      f.stretch_minus_identity.setZero();
      f.axis = Vec3::UnitX();
      f.angle = 0;
      continue;
    }
    // Polar decomposition A = R S from the SVD A = U Σ Vᵀ; Σ is sorted decreasingly, so flipping the last
    // singular direction turns a reflection into the nearest rotation and leaves the sign in S.
    const Eigen::JacobiSVD<Mat3> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Mat3& U = svd.matrixU();
    const Mat3& V = svd.matrixV();
    Vec3 sigma = svd.singularValues();
    Mat3 flip = Mat3::Identity();
    if ((U * V.transpose()).determinant() < 0) {
      flip(2, 2) = -1;
      sigma[2] = -sigma[2];
    }
    const Mat3 R = U * flip * V.transpose();
    f.stretch_minus_identity = V * sigma.asDiagonal() * V.transpose() - Mat3::Identity();
    const Eigen::AngleAxisd rotation(R);  // angle in [0, π]: the shortest arc, as slerp takes it
    f.axis = rotation.axis();
    f.angle = rotation.angle();
  }

  const Eigen::Index n = rest_.rows();
  parallel_for_chunks(n, [&](long b, long e) {
    for (long i = b; i < e; ++i) {
      const Vec3 p = rest_.row(i).transpose();
      Vec3 d = Vec3::Zero();
      for (int k = 0; k < nh; ++k) {
        const double s = weights_(i, k);
        if (s == 0.0) continue;
        const HandleFrame& f = frames_[k];
        if (s == 1.0) {
          d += f.linear_minus_identity * p + f.translation;  // T(p) − p, exactly T on the handle
        } else if (!decomposed) {
          d += s * (f.linear_minus_identity * p + f.translation);  // s·T(p) + (1 − s)·p − p
        } else {
          const Vec3 r = p - f.centroid;
          const Vec3 w = r + s * (f.stretch_minus_identity * r);
          // slerp(I, R, s) applied to w: rotation by s·θ about the axis (Rodrigues).
          const double phi = s * f.angle, c = std::cos(phi), sn = std::sin(phi);
          const Vec3 rotated = c * w + sn * f.axis.cross(w) + ((1.0 - c) * f.axis.dot(w)) * f.axis;
          d += s * f.centroid_motion + (rotated - r);
        }
      }
      out.row(i) = (p + d).transpose();
    }
  });
}

}  // namespace msd
