#include "msdeform/core/geodesics.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <queue>
#include <string>
#include <utility>

#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/solver.h"

namespace msd {

std::string check_time_factor(double time_factor) {
  if (time_factor >= 1e-6 && time_factor <= 1e6) return {};
  return "the time factor m (t = m h^2) must be in [1e-6, 1e6], got " + format_number(time_factor) +
         " (1 is Crane et al.'s choice; beyond the range the heat operator's factorisation breaks down)";
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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
    if (std::string why = check_time_factor(o.time_factor); !why.empty())
      throw InvalidInput("HeatGeodesics: " + why);
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
      if (e.index() < 0) throw SolverError(std::string("HeatGeodesics: ") + e.what());  // not singular: e.g. out of memory
      // M > 0 and −W >= 0, so this is a numerical breakdown (e.g. coordinates of wildly different scales):
      // a larger m smooths over bad triangles, until tW drowns M.
      throw SolverError(
          "HeatGeodesics: factoring the heat operator M - tW failed near vertex " +
              std::to_string(e.index()) + "; try a " + (options.time_factor < 1e3 ? "larger" : "smaller") +
              " time factor (--geodesic-time-factor, Python geodesic_time_factor; 1 is Crane et al.'s)",
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
      if (e.index() < 0) throw SolverError(std::string("HeatGeodesics: ") + e.what());  // not singular: e.g. out of memory
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

}  // namespace msd
