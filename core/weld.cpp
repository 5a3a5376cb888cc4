#include "msdeform/core/weld.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <regex>
#include <string>
#include <unordered_map>

#include "msdeform/core/checks.h"
#include "msdeform/core/disjoint_sets.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"

namespace msd {
namespace {

void check(const Positions& P, const Faces& F, double eps, const char* who) {
  if (!(eps >= 0) || !std::isfinite(eps))
    throw InvalidInput(std::string(who) + ": the distance must be finite and >= 0, got " + format_number(eps));
  check_faces(F, P.rows(), who, "the mesh");
}

// Joins the listed vertices that lie within eps of each other: a hash grid of cells of size eps (exact
// coordinates when eps is 0), each point compared with the points of its 27 neighbouring cells.
void join_close(const Positions& P, const std::vector<int>& ids, double eps, DisjointSets& groups) {
  using Cell = std::array<std::int64_t, 3>;
  struct Hash {
    size_t operator()(const Cell& c) const {
      // Unsigned arithmetic: the products wrap (the cells of far points overflowed a signed multiply).
      const auto u = [](std::int64_t x) { return static_cast<std::uint64_t>(x); };
      return static_cast<size_t>((u(c[0]) * 73856093u) ^ (u(c[1]) * 19349663u) ^ (u(c[2]) * 83492791u));
    }
  };
  std::unordered_map<Cell, std::vector<int>, Hash> grid;
  const auto cell_of = [&](int v) {
    Cell c;
    for (int k = 0; k < 3; ++k) {
      if (eps > 0) {
        const double q = std::floor(P(v, k) / eps);
        c[k] = std::abs(q) < 4e18 ? static_cast<std::int64_t>(q) : 0;  // far out: one cell, compared exactly
      } else {
        const double x = P(v, k) + 0.0;  // -0 and +0 are one coordinate
        std::memcpy(&c[k], &x, sizeof x);
      }
    }
    return c;
  };
  for (int v : ids) grid[cell_of(v)].push_back(v);
  const double eps2 = eps * eps;
  for (int v : ids) {
    const Cell c = cell_of(v);
    const int reach = eps > 0 ? 1 : 0;
    for (int dx = -reach; dx <= reach; ++dx)
      for (int dy = -reach; dy <= reach; ++dy)
        for (int dz = -reach; dz <= reach; ++dz) {
          const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (int w : it->second)
            if (w < v && (P.row(v) - P.row(w)).squaredNorm() <= eps2) groups.unite(v, w);
        }
  }
}

std::uint64_t edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
}

// Edges of exactly one face, as (lower, higher) vertex pairs packed by edge_key.
std::vector<std::uint64_t> boundary_edges(const Faces& F) {
  std::unordered_map<std::uint64_t, int> edge_faces;
  edge_faces.reserve(static_cast<size_t>(3 * F.rows()));
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++edge_faces[edge_key(F(f, k), F(f, (k + 1) % 3))];
  std::vector<std::uint64_t> out;
  for (const auto& [e, n] : edge_faces)
    if (n == 1) out.push_back(e);
  return out;
}

// Per vertex: 1 on an open seam (count_seam_vertices).
std::vector<char> seam_vertices(const Positions& P, const Faces& F, double eps) {
  const std::vector<std::uint64_t> edges = boundary_edges(F);
  const auto first = [](std::uint64_t e) { return static_cast<int>(e >> 32); };
  const auto second = [](std::uint64_t e) { return static_cast<int>(e & 0xffffffffu); };
  std::vector<char> on(static_cast<size_t>(P.rows()), 0);
  for (const std::uint64_t e : edges) on[first(e)] = on[second(e)] = 1;
  std::vector<int> boundary;
  for (int v = 0; v < static_cast<int>(on.size()); ++v)
    if (on[v]) boundary.push_back(v);
  DisjointSets groups(static_cast<int>(P.rows()));
  join_close(P, boundary, eps, groups);
  std::vector<int> size(static_cast<size_t>(P.rows()), 0);
  for (int v : boundary) ++size[groups.find(v)];
  // A seam runs along boundary edges that lie on another boundary edge (both ends coincide). Boundary
  // vertices that meet another only at a point (holes touching at a vertex) are no seam: welding them
  // would make the vertex non-manifold.
  std::unordered_map<std::uint64_t, int> coinciding;
  for (const std::uint64_t e : edges) ++coinciding[edge_key(groups.find(first(e)), groups.find(second(e)))];
  std::vector<char> seam(static_cast<size_t>(P.rows()), 0);
  for (const std::uint64_t e : edges)
    if (coinciding[edge_key(groups.find(first(e)), groups.find(second(e)))] > 1)
      for (const int v : {first(e), second(e)})
        if (size[groups.find(v)] > 1) seam[v] = 1;
  return seam;
}

}  // namespace

int count_seam_vertices(const Positions& P, const Faces& F, double eps) {
  check(P, F, eps, "count_seam_vertices");
  const std::vector<char> seam = seam_vertices(P, F, eps);
  return static_cast<int>(std::count(seam.begin(), seam.end(), 1));
}

Weld weld_vertices(const Positions& P, const Faces& F, double eps) {
  check(P, F, eps, "weld_vertices");
  std::vector<int> all(static_cast<size_t>(P.rows())), seams;
  std::iota(all.begin(), all.end(), 0);
  const std::vector<char> seam = seam_vertices(P, F, eps);
  for (int v : all)
    if (seam[v]) seams.push_back(v);
  DisjointSets groups(static_cast<int>(P.rows()));
  join_close(P, seams, eps, groups);
  // A distance at or above the edges along a seam chains each vertex to its neighbour on the same side,
  // and the whole boundary loop became one point (a 21 x 21 grid at 0.051 for edges of 0.05).
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      if (a != b && groups.find(a) == groups.find(b))
        throw InvalidInput("weld_vertices: the distance " + format_number(eps) + " joins vertices " +
                           std::to_string(a) + " and " + std::to_string(b) + ", the two ends of an edge of length " +
                           format_number((P.row(a) - P.row(b)).norm()) +
                           " (face " + std::to_string(f) + "): it must stay below the mesh's edges along the seam, "
                           "e.g. a tenth of the shortest");
    }
  Weld w;
  w.welded_of.assign(all.size(), -1);
  int n = 0;
  for (int v : all)
    w.welded_of[v] = groups.find(v) == v ? n++ : w.welded_of[groups.find(v)];
  w.P.resize(n, 3);
  for (int v : all)
    if (groups.find(v) == v) w.P.row(w.welded_of[v]) = P.row(v);
  w.merged = static_cast<int>(P.rows()) - n;
  w.F.resize(F.rows(), 3);  // no face loses a corner: the ends of an edge are never joined (above)
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) w.F(f, k) = w.welded_of[F(f, k)];
  return w;
}

Positions Weld::unweld(const Positions& welded) const {
  if (welded.rows() != P.rows())
    throw InvalidInput("Weld::unweld: " + std::to_string(welded.rows()) + " rows given, the welded mesh has " +
                       std::to_string(P.rows()) + " vertices");
  Positions out(static_cast<Eigen::Index>(welded_of.size()), 3);
  for (size_t v = 0; v < welded_of.size(); ++v) out.row(static_cast<Eigen::Index>(v)) = welded.row(welded_of[v]);
  return out;
}

int Weld::file_vertex(int w) const {
  if (w < 0 || w >= P.rows())
    throw InvalidInput("Weld::file_vertex: vertex " + std::to_string(w) + " is not in the welded mesh's [0, " +
                       std::to_string(P.rows()) + ")");
  // The group's lowest member is the first v with welded_of[v] == w (O(#V): for messages, not loops).
  return static_cast<int>(std::find(welded_of.begin(), welded_of.end(), w) - welded_of.begin());
}

std::string Weld::in_file_numbering(const std::string& message) const {
  static const std::regex named(R"((\bvertex |\bvertices )(\d+(?:, \d+)*))");
  static const std::regex number(R"(\d+)");
  std::string out;
  auto last = message.cbegin();
  for (std::sregex_iterator m(message.begin(), message.end(), named), end; m != end; ++m) {
    out.append(last, (*m)[2].first);
    const std::string list = (*m)[2].str();
    auto from = list.cbegin();
    for (std::sregex_iterator n(list.begin(), list.end(), number); n != end; ++n) {
      out.append(from, (*n)[0].first);
      const long w = std::stol((*n)[0].str());
      out += w < P.rows() ? std::to_string(file_vertex(static_cast<int>(w))) : (*n)[0].str();
      from = (*n)[0].second;
    }
    out.append(from, list.cend());
    last = (*m)[2].second;
  }
  out.append(last, message.cend());
  return out;
}

}  // namespace msd
