#include "core/mesh_info.h"

#include <numeric>
#include <vector>

#include "core/laplacian.h"

namespace msd {

MeshInfo mesh_info(const Mesh& mesh, const LoadReport* report) {
  MeshInfo info;
  info.vertices = static_cast<int>(mesh.n_vertices());
  info.faces = static_cast<int>(mesh.n_faces());
  info.edges = static_cast<int>(mesh.n_edges());
  info.euler_characteristic = info.vertices - info.edges + info.faces;
  const Positions P = positions(mesh);
  if (info.vertices > 0) {
    info.bbox_min = P.colwise().minCoeff();
    info.bbox_max = P.colwise().maxCoeff();
  }
  // Components by union-find over edges of faces.
  std::vector<int> parent(info.vertices);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  double total_length = 0;
  for (auto e : mesh.edges()) {
    const auto h = mesh.halfedge_handle(e, 0);
    const int a = mesh.from_vertex_handle(h).idx(), b = mesh.to_vertex_handle(h).idx();
    parent[find(a)] = find(b);
    total_length += mesh.calc_edge_length(e);
  }
  if (info.edges > 0) info.mean_edge_length = total_length / info.edges;
  for (auto v : mesh.vertices()) {
    if (mesh.is_isolated(v)) {
      ++info.isolated_vertices;
      continue;
    }
    if (find(v.idx()) == v.idx()) ++info.components;
    if (!mesh.is_manifold(v)) ++info.nonmanifold_vertices;
  }
  // Boundary loops: walk each unvisited boundary halfedge cycle.
  std::vector<char> seen(mesh.n_halfedges(), 0);
  for (auto h : mesh.halfedges()) {
    if (!h.is_boundary() || seen[h.idx()]) continue;
    ++info.boundary_loops;
    for (auto g = h; !seen[g.idx()]; g = g.next()) seen[g.idx()] = 1;
  }
  info.degenerate_faces = cotan_laplacian(P, faces(mesh)).degenerate_faces;
  if (report) info.nonmanifold_faces = report->nonmanifold_faces;
  return info;
}

}  // namespace msd
