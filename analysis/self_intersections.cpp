// The one translation unit of msdeform that includes CGAL (about 1 GB of compiler memory): keep it small.

// TBB is linked through msd::core; CGAL only enables its parallel code paths when told so, and the
// CGAL::TBB_support target would do no more than this definition.
#ifndef CGAL_LINKED_WITH_TBB
#define CGAL_LINKED_WITH_TBB
#endif

#include "msdeform/analysis/self_intersections.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <iterator>
#include <string>

#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"

namespace msd {
namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using FaceIndex = SurfaceMesh::Face_index;
}  // namespace

int count_self_intersections(const Positions& P, const Faces& F, std::vector<std::pair<int, int>>* pairs,
                             int* degenerate_faces) {
  const char* who = "count_self_intersections";
  check_mesh_arrays(P, F, who);

  SurfaceMesh mesh;
  mesh.reserve(static_cast<SurfaceMesh::size_type>(P.rows()),
               static_cast<SurfaceMesh::size_type>(3 * F.rows()),
               static_cast<SurfaceMesh::size_type>(F.rows()));
  std::vector<SurfaceMesh::Vertex_index> vertex(P.rows());
  for (Eigen::Index v = 0; v < P.rows(); ++v)
    vertex[v] = mesh.add_vertex(Kernel::Point_3(P(v, 0), P(v, 1), P(v, 2)));

  // Row of F for each CGAL face (faces that repeat an index are left out, so the numbering can differ).
  std::vector<int> row_of_face;
  row_of_face.reserve(F.rows());
  int degenerate = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
    if (a == b || b == c || c == a) {
      ++degenerate;
      continue;
    }
    const FaceIndex added = mesh.add_face(vertex[a], vertex[b], vertex[c]);
    if (added == SurfaceMesh::null_face())
      throw InvalidInput(std::string(who) + ": face " + std::to_string(f) + " (" + std::to_string(a) + ", " +
                         std::to_string(b) + ", " + std::to_string(c) +
                         ") makes the surface non-manifold or is oriented against a neighbour");
    row_of_face.push_back(static_cast<int>(f));
  }

  std::vector<std::pair<FaceIndex, FaceIndex>> found;
  CGAL::Polygon_mesh_processing::self_intersections<CGAL::Parallel_if_available_tag>(
      mesh, std::back_inserter(found));

  std::vector<std::pair<int, int>> result;
  result.reserve(found.size());
  for (const auto& [f, g] : found) {
    // CGAL reports each degenerate (collinear) face once as the pair (f, f).
    if (f == g) {
      ++degenerate;
      continue;
    }
    const int a = row_of_face[static_cast<size_t>(f)], b = row_of_face[static_cast<size_t>(g)];
    result.emplace_back(std::min(a, b), std::max(a, b));
  }
  std::sort(result.begin(), result.end());
  result.erase(std::unique(result.begin(), result.end()), result.end());
  if (degenerate_faces) *degenerate_faces = degenerate;
  const int count = static_cast<int>(result.size());
  if (pairs) *pairs = std::move(result);
  return count;
}

AddedSelfIntersections::AddedSelfIntersections(const Positions& rest, const Faces& F) : F_(F) {
  constexpr int kMostFaces = 10000;
  std::vector<int> around(static_cast<size_t>(rest.rows()), 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) >= 0 && F(f, k) < rest.rows())
        ++around[static_cast<size_t>(F(f, k))];  // bad ones: the count's error
  const auto most = std::max_element(around.begin(), around.end());
  if (most != around.end() && *most > kMostFaces)
    throw InvalidInput(
        "vertex " + std::to_string(most - around.begin()) + " lies on " + std::to_string(*most) +
        " faces, which CGAL would test pairwise (minutes to hours per count); remesh so that no "
        "vertex has thousands of neighbours, or skip the count");
  std::vector<std::pair<int, int>> pairs;
  rest_pairs_ = count_self_intersections(rest, F, &pairs);
  // The faces of a contact at rest and those within two rings of them (sharing a vertex, twice), where the
  // contact slides under an edit.
  near_contact_.assign(static_cast<size_t>(F.rows()), 0);
  for (const auto& [f, g] : pairs) near_contact_[f] = near_contact_[g] = 1;
  std::vector<char> vertex(static_cast<size_t>(rest.rows()));
  for (int ring = 0; ring < 2 && !pairs.empty(); ++ring) {
    std::fill(vertex.begin(), vertex.end(), 0);
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      if (near_contact_[f])
        for (int k = 0; k < 3; ++k) vertex[F(f, k)] = 1;
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      near_contact_[f] = near_contact_[f] || vertex[F(f, 0)] || vertex[F(f, 1)] || vertex[F(f, 2)];
  }
}

int AddedSelfIntersections::count(const Positions& result, std::vector<int>* faces) const {
  std::vector<std::pair<int, int>> pairs;
  count_self_intersections(result, F_, &pairs);
  int added = 0;
  if (faces) faces->clear();
  for (const auto& [f, g] : pairs) {
    if (near_contact_[f] && near_contact_[g]) continue;
    ++added;
    if (faces) faces->push_back(f), faces->push_back(g);
  }
  return added;
}

}  // namespace msd
