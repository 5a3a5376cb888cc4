#include "msdeform/core/mesh_info.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/surface_check.h"
#include "msdeform/core/weld.h"

namespace msd {

MeshInfo mesh_info(const Positions& P, const Faces& F) {
  MeshInfo info;
  Faces oriented = F;
  const SurfaceCheck check = check_surface(P, oriented);
  info.vertices = check.vertices;
  info.faces = check.faces;
  info.components = check.components;
  info.unreferenced_vertices = check.unreferenced_vertices;
  info.seam_vertices = count_seam_vertices(P, oriented);
  info.nonmanifold_edges = static_cast<int>(check.nonmanifold_edges.size());
  info.nonmanifold_vertices = static_cast<int>(check.nonmanifold_vertices.size());
  info.nonorientable_components = static_cast<int>(check.nonorientable_faces.size());
  info.flipped_faces = check.flipped_faces;
  info.surface_problem = check.problem();
  if (info.vertices > 0) {
    info.bbox_min = P.colwise().minCoeff();
    info.bbox_max = P.colwise().maxCoeff();
  }
  // Distinct edges as sorted (min, max) keys: their lengths, and the boundary ones joined into loops.
  std::vector<std::uint64_t> keys;
  keys.reserve(3 * static_cast<size_t>(F.rows()));
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const auto [a, b] = std::minmax(F(f, k), F(f, (k + 1) % 3));
      if (a != b) keys.push_back(std::uint64_t(a) << 32 | std::uint64_t(b));
    }
  std::sort(keys.begin(), keys.end());
  std::vector<int> parent(info.vertices);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  std::vector<char> on_boundary(info.vertices, 0);
  double total_length = 0;
  for (size_t i = 0; i < keys.size();) {
    size_t j = i + 1;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    const int a = static_cast<int>(keys[i] >> 32), b = static_cast<int>(keys[i] & 0xffffffffu);
    total_length += (P.row(a) - P.row(b)).stableNorm();  // no overflow of the squares at 1e200
    ++info.edges;
    if (j - i == 1) {
      ++info.boundary_edges;
      parent[find(a)] = find(b);
      on_boundary[a] = on_boundary[b] = 1;
    }
    i = j;
  }
  if (info.edges > 0) info.mean_edge_length = total_length / info.edges;
  if (info.vertices > 0) {
    try {
      check_extent(P, "sizes");
    } catch (const InvalidInput& e) {
      info.size_problem = e.what();
    }
  }
  if (info.seam_vertices == 0 && info.boundary_edges > 0 && info.mean_edge_length > 0 &&
      std::isfinite(info.near_seam_distance = 1e-3 * info.mean_edge_length)) {
    info.near_seam_vertices = count_seam_vertices(P, oriented, info.near_seam_distance);
  }
  info.euler_characteristic = info.vertices - info.edges + info.faces;
  for (int v = 0; v < info.vertices; ++v) info.boundary_loops += on_boundary[v] && find(v) == v;
  if (F.rows() > 0) info.degenerate_faces = cotan_laplacian(P, F).degenerate_faces;
  return info;
}

MeshInfo mesh_info(const Mesh& mesh) { return mesh_info(positions(mesh), faces(mesh)); }

}  // namespace msd
