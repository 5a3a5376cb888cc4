#include "msdeform/core/surface_check.h"

#include <algorithm>
#include <array>
#include <numeric>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/disjoint_sets.h"
#include "msdeform/core/errors.h"

namespace msd {
namespace {

std::string join_ids(const std::vector<int>& ids, size_t shown) {
  std::string s;
  for (size_t i = 0; i < std::min(shown, ids.size()); ++i) s += (i ? ", " : "") + std::to_string(ids[i]);
  if (ids.size() > shown) s += ", ...";
  return s;
}

std::string more(size_t count, const char* what) {
  return count > 1 ? " (" + std::to_string(count) + " " + what + " in all)" : "";
}

}  // namespace

std::string SurfaceCheck::problem() const {
  if (vertices == 0) return "no vertices";
  if (faces == 0) return "no faces (a point cloud)";
  if (!degenerate_faces.empty())
    return "face " + std::to_string(degenerate_faces[0]) + " repeats a vertex index" +
           more(degenerate_faces.size(), "such faces");
  if (!duplicate_faces.empty())
    return "faces " + std::to_string(duplicate_faces[0].first) + " and " +
           std::to_string(duplicate_faces[0].second) + " have the same three vertices" +
           more(duplicate_faces.size(), "duplicate faces");
  if (!nonmanifold_edges.empty()) {
    const NonManifoldEdge& e = nonmanifold_edges[0];
    return "edge (" + std::to_string(e.a) + ", " + std::to_string(e.b) + ") is shared by " +
           std::to_string(e.faces.size()) + " faces (" + join_ids(e.faces, 8) + "), a non-manifold edge" +
           more(nonmanifold_edges.size(), "non-manifold edges");
  }
  if (!nonmanifold_vertices.empty())
    return "vertex " + std::to_string(nonmanifold_vertices[0]) +
           " joins separate fans of faces (a non-manifold vertex, like the tips of two cones touching)" +
           more(nonmanifold_vertices.size(), "non-manifold vertices");
  if (!nonorientable_faces.empty())
    return "component " + std::to_string(nonorientable_components[0]) + " (the faces connected to face " +
           std::to_string(nonorientable_faces[0]) + ") is not orientable, like a Moebius strip" +
           more(nonorientable_faces.size(), "non-orientable patches");
  return "";
}

SurfaceCheck check_surface(const Positions& P, Faces& F) {
  const int nv = static_cast<int>(P.rows());
  const int nf = static_cast<int>(F.rows());
  SurfaceCheck r;
  r.vertices = nv;
  r.faces = nf;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= nv)
        throw InvalidInput("check_surface: face " + std::to_string(f) + " has vertex index " +
                           std::to_string(F(f, k)) + " out of range [0, " + std::to_string(nv) + ")");

  // Faces left out of the surface: those repeating an index, and every copy of a vertex set but the first.
  std::vector<char> excluded(nf, 0);
  {
    std::vector<std::array<int, 4>> keys;  // sorted corners, then the face
    keys.reserve(nf);
    for (int f = 0; f < nf; ++f) {
      std::array<int, 4> key = {F(f, 0), F(f, 1), F(f, 2), f};
      std::sort(key.begin(), key.begin() + 3);
      if (key[0] == key[1] || key[1] == key[2]) {
        r.degenerate_faces.push_back(f);
        excluded[f] = 1;
      } else {
        keys.push_back(key);
      }
    }
    std::sort(keys.begin(), keys.end());
    for (size_t i = 1, first = 0; i < keys.size(); ++i) {
      if (std::equal(keys[i].begin(), keys[i].begin() + 3, keys[first].begin())) {
        r.duplicate_faces.emplace_back(keys[first][3], keys[i][3]);
        excluded[keys[i][3]] = 1;
      } else {
        first = i;
      }
    }
    std::sort(r.duplicate_faces.begin(), r.duplicate_faces.end());
  }

  // Half-edge h = 3f + k runs from F(f, k) to F(f, k + 1). Bucketed by the smaller end (a counting sort),
  // then sorted by the larger one inside each bucket: equal runs are the edges, in O(#F) plus tiny sorts.
  auto from = [&](int h) { return F(h / 3, h % 3); };
  auto to = [&](int h) { return F(h / 3, (h % 3 + 1) % 3); };
  auto lo = [&](int h) { return std::min(from(h), to(h)); };
  auto hi = [&](int h) { return std::max(from(h), to(h)); };
  std::vector<int> bucket(nv + 1, 0);
  for (int f = 0; f < nf; ++f)
    if (!excluded[f])
      for (int k = 0; k < 3; ++k) ++bucket[lo(3 * f + k) + 1];
  std::partial_sum(bucket.begin(), bucket.end(), bucket.begin());
  std::vector<int> halfedges(bucket[nv]);
  {
    std::vector<int> fill(bucket.begin(), bucket.end() - 1);
    for (int f = 0; f < nf; ++f)
      if (!excluded[f])
        for (int k = 0; k < 3; ++k) halfedges[fill[lo(3 * f + k)]++] = 3 * f + k;
  }
  // The other half-edge across a manifold edge, -1 on a boundary or non-manifold edge.
  std::vector<int> opposite(3 * static_cast<size_t>(nf), -1);
  // Corners c = 3f + k (face f at F(f, k)) joined across the edges they share: a vertex is manifold when
  // its corners form one set (one fan).
  DisjointSets fans(3 * nf);
  auto corner_at = [&](int h, int v) { return from(h) == v ? h : 3 * (h / 3) + (h % 3 + 1) % 3; };
  for (int v = 0; v < nv; ++v) {
    const auto first = halfedges.begin() + bucket[v], last = halfedges.begin() + bucket[v + 1];
    std::sort(first, last, [&](int a, int b) { return hi(a) < hi(b) || (hi(a) == hi(b) && a < b); });
    for (auto run = first; run != last;) {
      auto end = run + 1;
      while (end != last && hi(*end) == hi(*run)) ++end;
      const long n = end - run;
      ++r.edges;
      if (n == 1) ++r.boundary_edges;
      if (n == 2) opposite[run[0]] = run[1], opposite[run[1]] = run[0];
      if (n > 2) {
        NonManifoldEdge e{v, hi(*run), {}};
        for (auto h = run; h != end; ++h) e.faces.push_back(*h / 3);  // ascending: the run is sorted by h
        r.nonmanifold_edges.push_back(std::move(e));
      }
      for (auto h = run + 1; h != end; ++h) {
        fans.unite(corner_at(*run, v), corner_at(*h, v));
        fans.unite(corner_at(*run, hi(*run)), corner_at(*h, hi(*run)));
      }
      run = end;
    }
  }

  // Fans per vertex, components through shared vertices, unreferenced vertices.
  std::vector<int> fan_count(nv, 0);
  std::vector<char> referenced(nv, 0);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) referenced[F(f, k)] = 1;
    if (excluded[f]) continue;
    for (int k = 0; k < 3; ++k)
      if (fans.find(3 * f + k) == 3 * f + k) ++fan_count[F(f, k)];
  }
  for (int v = 0; v < nv; ++v) {
    r.unreferenced_vertices += !referenced[v];
    if (fan_count[v] > 1) r.nonmanifold_vertices.push_back(v);
  }
  const std::vector<int> component = vertex_components(F, nv);  // in the order of their first face
  for (int c : component) r.components = std::max(r.components, c + 1);

  // Orientation: a breadth-first search per patch of faces joined across manifold edges. Across such an
  // edge the two half-edges must run opposite ways; side[f] = -1 marks a face to turn over.
  std::vector<signed char> side(nf, 0);
  std::vector<int> patch;
  for (int root = 0; root < nf; ++root) {
    if (excluded[root] || side[root] != 0) continue;
    patch.assign(1, root);
    side[root] = 1;
    bool orientable = true;
    for (size_t i = 0; i < patch.size(); ++i) {
      const int f = patch[i];
      for (int k = 0; k < 3; ++k) {
        const int h = 3 * f + k, o = opposite[h];
        if (o < 0) continue;
        const int g = o / 3;
        const signed char wanted = from(h) == from(o) ? -side[f] : side[f];
        if (side[g] == 0) {
          side[g] = wanted;
          patch.push_back(g);
        } else if (side[g] != wanted) {
          orientable = false;
        }
      }
    }
    if (!orientable) {
      r.nonorientable_faces.push_back(root);
      r.nonorientable_components.push_back(component[F(root, 0)]);
      continue;
    }
    const long against = std::count_if(patch.begin(), patch.end(), [&](int f) { return side[f] < 0; });
    const signed char turn = 2 * against > static_cast<long>(patch.size()) ? 1 : -1;  // fewer turns
    for (int f : patch)
      if (side[f] == turn) {
        std::swap(F(f, 1), F(f, 2));
        ++r.flipped_faces;
      }
  }
  return r;
}

}  // namespace msd
