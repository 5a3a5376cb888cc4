// Seams (issue 14, kind 5): a mesh split along coincident boundary vertices is detected, and welding
// joins it for a method while the file's vertices stay the file's.

#include <catch2/catch.hpp>

#include "msdeform/core/edit_case.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_info.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/surface_check.h"
#include "msdeform/core/weld.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {
// The bumpy plane cut along x = 0.5: the faces right of the cut get their own copies of the cut's
// vertices (appended), as a converter that splits by material would leave it.
EditCase split_plane() {
  EditCase c = scene_case("lift", 2000);
  const Eigen::Index n = c.P.rows();
  std::vector<int> copy(static_cast<size_t>(n), -1);
  std::vector<Vec3> extra;
  for (Eigen::Index f = 0; f < c.F.rows(); ++f) {
    double cx = 0;
    for (int k = 0; k < 3; ++k) cx += c.P(c.F(f, k), 0) / 3;
    if (cx < 0.5) continue;
    for (int k = 0; k < 3; ++k) {
      const int v = c.F(f, k);
      if (std::abs(c.P(v, 0) - 0.5) > 1e-3) continue;  // not on the cut
      if (copy[v] < 0) {
        copy[v] = static_cast<int>(n + static_cast<Eigen::Index>(extra.size()));
        extra.push_back(c.P.row(v).transpose());
      }
      c.F(f, k) = copy[v];
    }
  }
  c.P.conservativeResize(n + static_cast<Eigen::Index>(extra.size()), 3);
  std::vector<int> codes = c.region.codes();
  for (size_t i = 0; i < extra.size(); ++i) c.P.row(n + static_cast<Eigen::Index>(i)) = extra[i].transpose();
  for (Eigen::Index v = 0; v < n; ++v)
    if (copy[v] >= 0) codes.push_back(codes[v]);
  c.region = Region::from_codes(codes);
  return c;
}
}  // namespace

TEST_CASE("mesh_info: a seam written with rounding is reported as near-seam vertices with the distance to weld",
          "[core][weld]") {
  // A seam whose copies were jittered by 1e-7 (a float round trip) read "seam vertices 0" and no hint.
  EditCase split = split_plane();
  const int copies = static_cast<int>(split.P.rows() - scene_case("lift", 2000).P.rows());
  for (Eigen::Index v = split.P.rows() - copies; v < split.P.rows(); ++v) split.P(v, 1) += 1e-7;
  const MeshInfo info = mesh_info(split.P, split.F);
  CHECK(info.seam_vertices == 0);
  CHECK(info.near_seam_vertices == 2 * copies);
  CHECK(info.near_seam_distance == Approx(1e-3 * info.mean_edge_length));
  CHECK(weld_case(split, info.near_seam_distance).weld->merged == copies);
  const MeshInfo intact = mesh_info(scene_case("lift", 2000).P, scene_case("lift", 2000).F);
  CHECK(intact.near_seam_vertices == 0);  // the plane's own boundary has no near pair
}

TEST_CASE("weld: a plane split along a seam is counted, welded for the method and unwelded for the file",
          "[core][weld]") {
  const EditCase plane = scene_case("lift", 2000);
  CHECK(count_seam_vertices(plane.P, plane.F) == 0);
  const EditCase split = split_plane();
  const int copies = static_cast<int>(split.P.rows() - plane.P.rows());
  REQUIRE(copies > 10);
  CHECK(count_seam_vertices(split.P, split.F) == 2 * copies);  // each cut vertex and its copy
  Faces oriented = split.F;
  CHECK(check_surface(split.P, oriented).components == 2);  // it deforms as two pieces

  const EditCase welded = weld_case(split, 0);
  CHECK(welded.weld->merged == copies);
  CHECK(welded.P.rows() == plane.P.rows());
  CHECK(welded.seam_vertices == 0);
  CHECK(welded.surface_problem.empty());
  CHECK(welded.file_F == split.F);
  oriented = welded.F;
  CHECK(check_surface(welded.P, oriented).components == 1);
  CHECK(welded.region.num_handles() == split.region.num_handles());
  // Back on the file's vertices: same count and order; every copy at its original's position.
  Positions moved = welded.P;
  moved.col(2).array() += 1;
  const Positions back = welded.weld->unweld(moved);
  REQUIRE(back.rows() == split.P.rows());
  CHECK((back - split.P).col(2).array().abs().maxCoeff() == Approx(1));
  CHECK((back.leftCols(2) - split.P.leftCols(2)).cwiseAbs().maxCoeff() == 0);
  CHECK_THROWS_AS(welded.weld->unweld(split.P), InvalidInput);
}

TEST_CASE("weld: messages about the welded mesh name the file's vertices", "[core][weld]") {
  // Two triangles split along a seam: file vertices 1 and 4 repeat 0 and 2, so welded vertices 0, 1, 2, 3
  // are the file's 0, 2, 3, 5 (--weld named the welded numbers before, which point at other vertices of the
  // file).
  Positions P(6, 3);
  P << 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 0, -1, 0;
  Faces F(2, 3);
  F << 0, 2, 3, 4, 1, 5;
  const Weld w = weld_vertices(P, F, 0);
  REQUIRE(w.P.rows() == 4);
  CHECK(w.welded_of == std::vector<int>{0, 0, 1, 2, 1, 3});
  CHECK(w.file_vertex(2) == 3);
  CHECK(w.in_file_numbering("shell: singular near vertex 2; vertices 0, 1, 2 moved; vertex 7 and 12 vertices") ==
        "shell: singular near vertex 3; vertices 0, 2, 3 moved; vertex 7 and 12 vertices");
  CHECK_THROWS_AS(w.file_vertex(4), InvalidInput);
}

TEST_CASE("weld: only seams are welded, twins inside the surface stay apart", "[core][weld]") {
  // Two closed tetrahedra touching at a corner, each with its own copy of it (CGAL's cow has such a pair
  // of interior vertices, 44 and 2903): no seam, and welding the corners would pinch the surface into a
  // non-manifold vertex (before: merged, and every surface method then refused the mesh).
  Positions P(8, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, -1, 0, 0, 0, -1, 0, 0, 0, -1;
  Faces F(8, 3);
  F << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 4, 5, 6, 4, 7, 5, 4, 6, 7, 5, 7, 6;
  CHECK(count_seam_vertices(P, F) == 0);
  const Weld w = weld_vertices(P, F, 0);
  CHECK(w.merged == 0);
  CHECK(w.F == F);
}

TEST_CASE("weld: pieces touching at a point are no seam (welding would pinch them)", "[core][weld]") {
  // Two triangles whose corners 1 and 3 coincide, and no edge does (CGAL's elephant-with-holes has 65
  // such points where holes meet); then a copy of the edge 1-2, which is a seam.
  Positions P(6, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 2, 0, 0, 2, -1, 0;
  Faces F(2, 3);
  F << 0, 1, 2, 3, 5, 4;
  CHECK(count_seam_vertices(P, F) == 0);
  Positions Q(7, 3);
  Q << P, 0, 1, 0;  // vertex 6 is a copy of vertex 2: the edges 1-2 and 3-6 coincide
  Faces G(3, 3);
  G << F, 3, 6, 5;
  CHECK(count_seam_vertices(Q, G) == 4);  // 1 and its copy 3, 2 and its copy 6
}

TEST_CASE("weld: a distance joins near vertices, conflicting labels and bad distances are refused", "[core][weld]") {
  Positions P(4, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1e-7, 0, 0;
  Faces F(2, 3);
  F << 0, 1, 2, 3, 2, 1;  // vertex 3 is a near copy of vertex 0
  CHECK(count_seam_vertices(P, F) == 0);
  CHECK(count_seam_vertices(P, F, 1e-6) == 2);
  const Weld exact = weld_vertices(P, F, 0);
  CHECK(exact.merged == 0);
  const Weld near = weld_vertices(P, F, 1e-6);
  CHECK(near.merged == 1);
  CHECK(near.welded_of == std::vector<int>{0, 1, 2, 0});
  // A distance beyond the edges chained the whole boundary into one point (a 21 x 21 grid at 0.051 for
  // edges of 0.05: 80 vertices into one, 80 faces dropped, exit 0).
  CHECK_THROWS_WITH(weld_vertices(P, F, 10), Contains("joins vertices 0 and 1, the two ends of an edge of length 1"));
  CHECK_THROWS_WITH(weld_vertices(P, F, -1), Contains("finite and >= 0"));
  F(1, 0) = 9;
  CHECK_THROWS_WITH(weld_vertices(P, F, 0), Contains("face 1 of the mesh has vertex index 9"));

  EditCase c;
  c.P = P;
  c.F.resize(2, 3);
  c.F << 0, 1, 2, 3, 2, 1;
  c.region = Region::from_codes({0, 1, 2, 2});
  CHECK_THROWS_WITH(weld_case(c, 1e-6), Contains("vertices 0 and 3 are welded") && Contains("labels 0 and 2"));
}
