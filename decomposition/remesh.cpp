// The one translation unit of decomposition/ that includes CGAL (about 1 GB of compiler memory).

#include "msdeform/decomposition/remesh.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"

namespace msd {
namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;
// 25°: a turn of the outline that remeshing keeps. Not 360°/n for any n, so no regular polygon has its
// corners at the threshold, where rounding would keep some and cut others (a 12-gon at 30°: 4 of 12 kept).
constexpr double kCornerTurn = 0.4363323129985824;
}  // namespace

void check_remesh_size(const Positions& P, const Faces& F, double target_edge_length,
                       const std::string& who) {
  // Equilateral triangles of the target edge cover the area in about area / (√3/4 · edge²) of them.
  double area = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    if (F.row(f).minCoeff() >= 0 && F.row(f).maxCoeff() < P.rows())
      area += 0.5 * (P.row(F(f, 1)) - P.row(F(f, 0))).cross(P.row(F(f, 2)) - P.row(F(f, 0))).norm();
  const double expected = area / (0.4330127018922193 * target_edge_length * target_edge_length);
  if (expected > kMaxRemeshTriangles) {
    char text[200];
    std::snprintf(text, sizeof text, ": edge length %g would make about %.3g triangles (at most %.3g are allowed); "
                  "use an edge length of at least %.3g", target_edge_length, expected, kMaxRemeshTriangles,
                  std::sqrt(area / (0.4330127018922193 * kMaxRemeshTriangles)));
    throw InvalidInput(who + text);
  }
}

RemeshResult remesh_isotropic(const Positions& P, const Faces& F, double target_edge_length, int iterations) {
  const std::string who = "remesh_isotropic";
  if (!(target_edge_length > 0) || !std::isfinite(target_edge_length))
    throw InvalidInput(who + ": target edge length " + format_number(target_edge_length) +
                       " must be finite and positive");
  if (iterations < 0)
    throw InvalidInput(who + ": iterations " + std::to_string(iterations) + " must be >= 0");
  check_finite(P, who.c_str(), "the mesh");
  check_remesh_size(P, F, target_edge_length, who);

  SurfaceMesh mesh;
  mesh.reserve(static_cast<SurfaceMesh::size_type>(P.rows()),
               static_cast<SurfaceMesh::size_type>(3 * F.rows()),
               static_cast<SurfaceMesh::size_type>(F.rows()));
  // The vertices the faces use (one that no face uses has no surface to remesh: left out, not kept as an
  // isolated vertex of the result).
  std::vector<SurfaceMesh::Vertex_index> vertex(P.rows(), SurfaceMesh::null_vertex());
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int i = F(f, k);
      if (i < 0 || i >= P.rows())
        throw InvalidInput(who + ": face " + std::to_string(f) + " has vertex index " + std::to_string(i) +
                           " out of range [0, " + std::to_string(P.rows()) + ")");
      if (vertex[i] == SurfaceMesh::null_vertex())
        vertex[i] = mesh.add_vertex(Kernel::Point_3(P(i, 0), P(i, 1), P(i, 2)));
    }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
    if (a == b || b == c || c == a)
      throw InvalidInput(who + ": face " + std::to_string(f) + " repeats a vertex");
    if (mesh.add_face(vertex[a], vertex[b], vertex[c]) == SurfaceMesh::null_face())
      throw InvalidInput(who + ": face " + std::to_string(f) + " (" + std::to_string(a) + ", " +
                         std::to_string(b) + ", " + std::to_string(c) +
                         ") makes the surface non-manifold or is oriented against a neighbour");
  }

  try {
    // The border: its edges are constrained (never flipped, their vertices not moved by smoothing) but split
    // and collapsed towards the target like the others, so the outline is resampled from its own vertices
    // (kept at the input's spacing, the survey plane's 800 outline vertices beside edges 20 times longer
    // left 211 zero-area triangles in a base the shell could not solve on). Its corners, where the outline
    // turns by more than kCornerTurn, are constrained vertices and stay.
    auto constrained = mesh.add_property_map<SurfaceMesh::Edge_index, bool>("e:msd_constrained", false).first;
    auto corner = mesh.add_property_map<SurfaceMesh::Vertex_index, bool>("v:msd_corner", false).first;
    for (SurfaceMesh::Halfedge_index h : mesh.halfedges()) {
      if (!mesh.is_border(h)) continue;
      constrained[mesh.edge(h)] = true;
      // h runs along the hole; the turn at its target is between h and the next border halfedge.
      const SurfaceMesh::Halfedge_index next = mesh.next(h);
      const Kernel::Vector_3 in = mesh.point(mesh.target(h)) - mesh.point(mesh.source(h));
      const Kernel::Vector_3 out = mesh.point(mesh.target(next)) - mesh.point(mesh.source(next));
      const double lengths = std::sqrt(in.squared_length() * out.squared_length());
      if (!(in * out > std::cos(kCornerTurn) * lengths)) corner[mesh.target(h)] = true;
    }
    PMP::isotropic_remeshing(mesh.faces(), target_edge_length, mesh,
                             CGAL::parameters::number_of_iterations(static_cast<unsigned>(iterations))
                                 .edge_is_constrained_map(constrained)
                                 .vertex_is_constrained_map(corner));
    mesh.remove_property_map(constrained);
    mesh.remove_property_map(corner);
  } catch (const CGAL::Failure_exception& e) {
    throw SolverError(who + ": CGAL failed: " + e.what());
  }
  mesh.collect_garbage();

  RemeshResult out;
  out.P.resize(static_cast<Eigen::Index>(mesh.number_of_vertices()), 3);
  for (SurfaceMesh::Vertex_index v : mesh.vertices()) {
    const Kernel::Point_3& p = mesh.point(v);
    out.P.row(static_cast<Eigen::Index>(v.idx())) << p.x(), p.y(), p.z();
  }
  out.F.resize(static_cast<Eigen::Index>(mesh.number_of_faces()), 3);
  for (SurfaceMesh::Face_index f : mesh.faces()) {
    int k = 0;
    for (SurfaceMesh::Vertex_index v : CGAL::vertices_around_face(mesh.halfedge(f), mesh))
      out.F(static_cast<Eigen::Index>(f.idx()), k++) = static_cast<int>(v.idx());
  }
  return out;
}

}  // namespace msd
