#include <catch2/catch.hpp>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <tuple>

#include "msdeform/core/edit_case.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_info.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/region.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/surface_check.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

TEST_CASE("save/load round trips keep vertex order exactly", "[core][io]") {
  SceneOptions o;
  o.resolution = 500;
  const Scene s = make_scene("twist135", o);
  test::TempDir tmp;
  for (const char* ext : {".off", ".obj", ".ply"}) {
    const std::string path = tmp.file(std::string("m") + ext);
    save_mesh(s.P, s.F, path);
    const Mesh m = load_mesh(path);
    INFO(ext);
    REQUIRE(m.n_vertices() == static_cast<size_t>(s.P.rows()));
    CHECK((positions(m) - s.P).cwiseAbs().maxCoeff() == 0.0);  // shortest round-trip decimal
    CHECK(faces(m) == s.F);
  }
  // STL stores triangles only (single precision): geometry and counts survive, the order need not.
  save_mesh(s.P, s.F, tmp.file("m.stl"));
  const Mesh stl = load_mesh(tmp.file("m.stl"));
  CHECK(stl.n_faces() == static_cast<size_t>(s.F.rows()));
  CHECK(stl.n_vertices() == static_cast<size_t>(s.P.rows()));
}

TEST_CASE("binary little-endian PLY loads in double precision, extra properties skipped", "[core][io]") {
  test::TempDir tmp;
  std::string data =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
      "property double z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\n"
      "property float quality\nend_header\n";
  const double xyz[3][3] = {{0.1, 0.2, 0.3}, {1.0 / 3.0, 0, 0}, {0, 1, 1e-17}};
  for (const auto& p : xyz) {
    data.append(reinterpret_cast<const char*>(p), sizeof(p));
    data.push_back('\x7f');
  }
  data.push_back(3);
  const int idx[3] = {0, 1, 2};
  data.append(reinterpret_cast<const char*>(idx), sizeof(idx));
  const float q = 0.5f;
  data.append(reinterpret_cast<const char*>(&q), sizeof(q));
  std::ofstream(tmp.file("b.ply"), std::ios::binary) << data;
  const Positions P = positions(load_mesh(tmp.file("b.ply")));
  REQUIRE(P.rows() == 3);
  CHECK(P(1, 0) == 1.0 / 3.0);
  CHECK(P(2, 2) == 1e-17);
  data.resize(data.size() - 6);
  std::ofstream(tmp.file("cut.ply"), std::ios::binary) << data;
  CHECK_THROWS_WITH(load_mesh(tmp.file("cut.ply")), Contains("ends inside the binary data"));
}

TEST_CASE("PLY triangle strips load as triangles, other elements listing corners are refused", "[core][io]") {
  // A tristrips element loaded as a point cloud without a word, and a space method wrote it back faceless.
  test::TempDir tmp;
  const std::string vertices = "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string points = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n";
  const std::string ascii = "ply\nformat ascii 1.0\n" + vertices +
                            "element tristrips 1\nproperty list int int vertex_indices\nend_header\n" +
                            points + "8 0 1 3 2 -1 1 4 2\n";  // two strips: the square, then one triangle
  const TriangleSoup a = load_soup(tmp.write("strips.ply", ascii));
  REQUIRE(a.F.rows() == 3);
  CHECK(a.F.row(0) == Eigen::RowVector3i(0, 1, 3));
  CHECK(a.F.row(1) == Eigen::RowVector3i(3, 1, 2));  // every other one turned: both face +z
  CHECK(a.F.row(2) == Eigen::RowVector3i(1, 4, 2));
  std::string binary = "ply\nformat binary_little_endian 1.0\n" + vertices +
                       "element tristrips 1\nproperty list uchar int vertex_indices\nend_header\n";
  for (const float p : {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0})
    binary.append(reinterpret_cast<const char*>(&p), 4);
  binary.push_back(7);
  for (const int i : {0, 1, 3, 2, -1, 1, 4}) binary.append(reinterpret_cast<const char*>(&i), 4);
  // An index out of range is named as the strip's (it was "face 0", the first triangle of the split).
  std::string out_of_range = ascii;
  out_of_range.replace(out_of_range.find(" 1 4 2\n"), 7, " 1 9 2\n");
  CHECK_THROWS_WITH(load_soup(tmp.write("strips-far.ply", out_of_range)),
                    Contains("tristrips 0 has vertex index 9 out of range [0, 5)"));
  // In an unsigned list the restart is the largest value (it was refused as index 4.29497e+09).
  std::string unsigned_strips = ascii;
  unsigned_strips.replace(unsigned_strips.find("list int int"), 12, "list int uint");
  unsigned_strips.replace(unsigned_strips.find(" -1 "), 4, " 4294967295 ");
  CHECK(load_soup(tmp.write("strips-u.ply", unsigned_strips)).F == a.F);
  const TriangleSoup b = load_soup(tmp.write("strips-b.ply", binary));
  CHECK(b.F.rows() == 2);  // the second strip, 1 4, is too short for a triangle
  CHECK_THROWS_WITH(
      load_soup(tmp.write("lines.ply", "ply\nformat ascii 1.0\n" + vertices +
                                           "element polyline 1\nproperty list int int vertex_indices\n"
                                           "end_header\n" +
                                           points + "3 0 1 2\n")),
      Contains("element 'polyline' lists vertex indices, which msdeform reads only from a 'face' element"));
}

TEST_CASE("STL refuses coordinates beyond single precision instead of writing inf", "[core][io][bad-input]") {
  // 1e39 lies within msdeform's sizes (up to 1e70) but not within float's: the file held inf, exit 0,
  // and msdeform's own reader refused it.
  test::TempDir tmp;
  Positions P(3, 3);
  P << 0, 0, 0, 1e39, 0, 0, 0, 1, 0;
  const Faces F = (Faces(1, 3) << 0, 1, 2).finished();
  CHECK_THROWS_WITH(save_mesh(P, F, tmp.file("big.stl")),
                    Contains("vertex 1 has a coordinate of 1e+39, beyond the single precision STL stores"));
  CHECK_FALSE(std::filesystem::exists(tmp.file("big.stl")));
  P(1, 0) = 3e38;
  save_mesh(P, F, tmp.file("ok.stl"));
  CHECK(load_soup(tmp.file("ok.stl")).P.allFinite());
  // A mesh 1e-50 across was written as one point (float flushed it to 0), exit 0.
  P(1, 0) = 3;
  CHECK_THROWS_WITH(
      save_mesh(P * 1e-50, F, tmp.file("tiny.stl")),
      Contains("the largest coordinate is 3e-50, too small for the single precision STL stores"));
  CHECK_FALSE(std::filesystem::exists(tmp.file("tiny.stl")));
  // Far from the origin single precision joins nearby vertices (a unit triangle at 3e7 came back as one
  // point).
  Positions far = P;
  far.rowwise() += Eigen::RowVector3d(3e7, 3e7, 3e7);
  CHECK_THROWS_WITH(save_mesh(far, F, tmp.file("far.stl")),
                    Contains("round to one point in the single precision STL stores"));
  CHECK_FALSE(std::filesystem::exists(tmp.file("far.stl")));
}

TEST_CASE("real meshes load with the right counts", "[core][io][real]") {
  struct Case {
    std::string path;
    size_t vertices, faces;
  };
  const std::vector<Case> cases = {
      {test::shared_data("decimated-knight.off"), 502, 1000},
      {test::shared_data("bumpy.off"), 1250, 2496},
      {test::shared_data("planexy.off"), 25, 32},
      {test::shared_data("bump-domain.obj"), 4172, 8058},
      {test::cgal_mesh("cactus.off"), 620, 1236},
  };
  for (const auto& c : cases) {
    INFO(c.path);
    LoadReport report;
    const Mesh m = load_mesh(c.path, &report);
    CHECK(m.n_vertices() == c.vertices);
    CHECK(m.n_faces() == c.faces);
    CHECK(report.faces_flipped == 0);
    CHECK(report.duplicate_faces_dropped == 0);
  }
  // The first vertex of the knight, as written in the file.
  const Positions knight = positions(load_mesh(test::shared_data("decimated-knight.off")));
  std::ifstream in(test::shared_data("decimated-knight.off"));
  std::string head;
  long nv, nf, ne;
  double x, y, z;
  in >> head >> nv >> nf >> ne >> x >> y >> z;
  CHECK(knight.row(0) == Eigen::RowVector3d(x, y, z));
}

TEST_CASE("polygons are triangulated, duplicate and repeated-index faces dropped and counted", "[core][io]") {
  test::TempDir tmp;
  std::ofstream(tmp.file("quad.obj")) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
  LoadReport report;
  const Mesh quad = load_mesh(tmp.file("quad.obj"), &report);
  CHECK(quad.n_faces() == 2);
  CHECK(report.polygons_triangulated == 1);
  // Face 2 repeats face 0's vertices (wound the other way), face 3 repeats index 1, face 4 is face 1 again.
  std::ofstream(tmp.file("dup.off")) << "OFF\n4 5 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n3 2 1 0\n"
                                        "3 1 1 3\n3 0 2 3\n";
  LoadReport dup;
  const TriangleSoup soup = load_soup(tmp.file("dup.off"), &dup);
  CHECK(soup.P.rows() == 4);
  REQUIRE(soup.F.rows() == 2);
  CHECK(soup.F.row(0) == Eigen::RowVector3i(0, 1, 2));
  CHECK(soup.F.row(1) == Eigen::RowVector3i(0, 2, 3));
  CHECK(dup.duplicate_faces_dropped == 2);
  CHECK(dup.degenerate_faces_skipped == 1);
  LoadReport mesh_report;
  CHECK(load_mesh(tmp.file("dup.off"), &mesh_report).n_faces() == 2);
  CHECK(mesh_report.duplicate_faces_dropped == 2);
}

TEST_CASE("a corner listed twice in a row is read once, other repeats drop the face", "[core][io]") {
  // Break test: `4 0 1 2 2` (a triangle written as a quad with its last corner repeated, as some exporters
  // do) was dropped as repeating a vertex, leaving a hole in the surface.
  test::TempDir tmp;
  std::ofstream(tmp.file("rep.off")) << "OFF\n5 5 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 2 0\n"
                                        "4 0 1 2 2\n4 0 2 3 0\n5 1 4 4 4 2\n4 0 1 0 3\n4 1 1 1 1\n";
  LoadReport report;
  const TriangleSoup soup = load_soup(tmp.file("rep.off"), &report);
  REQUIRE(soup.F.rows() == 3);
  CHECK(soup.F.row(0) == Eigen::RowVector3i(0, 1, 2));  // the first corner kept, orientation kept
  CHECK(soup.F.row(1) == Eigen::RowVector3i(0, 2, 3));  // first and last corner the same
  CHECK(soup.F.row(2) == Eigen::RowVector3i(1, 4, 2));  // a run of three
  CHECK(report.repeated_corners_merged == 3);
  CHECK(report.degenerate_faces_skipped == 2);  // 0 1 0 3 (not in a row) and 1 1 1 1
  CHECK_THAT(faces_changed_on_load(report),
             Contains("3 faces listing a corner twice in a row read without the repetition") &&
                 Contains("2 faces repeating a vertex dropped"));
}

TEST_CASE("a concave polygon is split into triangles that cover it once, a convex one into its fan",
          "[core][io]") {
  // Break test: the pentagon below (its reflex corner is the 4th) became a fan from its first corner with
  // one triangle turned over and overlapping the others, and `info` called the mesh manifold and oriented.
  test::TempDir tmp;
  const auto check_cover = [](const TriangleSoup& soup, double area) {
    double total = 0;
    for (Eigen::Index f = 0; f < soup.F.rows(); ++f) {
      const Vec3 p0 = soup.P.row(soup.F(f, 0)), p1 = soup.P.row(soup.F(f, 1)), p2 = soup.P.row(soup.F(f, 2));
      const double z = (p1 - p0).cross(p2 - p0).z() / 2;
      INFO("triangle " << f);
      CHECK(z > 0);  // every triangle turns the polygon's way (it runs counter-clockwise about +z)
      total += z;
    }
    CHECK(total == Approx(area).epsilon(1e-12));  // so they cover it once
  };
  std::ofstream(tmp.file("concave.obj")) << "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 1 0.5 0\nv 0 2 0\nf 2 3 4 5 1\n";
  LoadReport report;
  const TriangleSoup concave = load_soup(tmp.file("concave.obj"), &report);
  REQUIRE(concave.F.rows() == 3);
  check_cover(concave, 2.5);  // the square of side 2 less the notch (area 1.5)
  CHECK(report.polygons_triangulated == 1);
  CHECK(report.polygons_split_otherwise == 1);
  // Every start: the reflex corner first, last, in the middle; and an L of eight corners (area 3).
  for (int shift = 0; shift < 5; ++shift) {
    std::string face = "f";
    for (int k = 0; k < 5; ++k) face += " " + std::to_string((shift + k) % 5 + 1);
    std::ofstream(tmp.file("turned.obj")) << "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 1 0.5 0\nv 0 2 0\n"
                                          << face << "\n";
    INFO(face);
    check_cover(load_soup(tmp.file("turned.obj")), 2.5);
  }
  std::ofstream(tmp.file("l.off")) << "OFF\n8 1 0\n0 0 0\n1 0 0\n2 0 0\n2 1 0\n1 1 0\n1 2 0\n0 2 0\n0 1 0\n"
                                      "8 3 4 5 6 7 0 1 2\n";
  check_cover(load_soup(tmp.file("l.off")), 3);
  // A convex polygon keeps the fan from its first corner (the faces every mesh tool reads).
  std::ofstream(tmp.file("hexagon.off"))
      << "OFF\n6 1 0\n2 0 0\n1 1.7 0\n-1 1.7 0\n-2 0 0\n-1 -1.7 0\n1 -1.7 0\n"
         "6 0 1 2 3 4 5\n";
  LoadReport convex;
  const TriangleSoup hexagon = load_soup(tmp.file("hexagon.off"), &convex);
  REQUIRE(hexagon.F.rows() == 4);
  for (int k = 0; k < 4; ++k) CHECK(hexagon.F.row(k) == Eigen::RowVector3i(0, k + 1, k + 2));
  CHECK(convex.polygons_split_otherwise == 0);
  // A polygon that crosses itself (a bow tie) has no such split: refused, with its line and face.
  for (const char* bowtie :
       {"0 0 0\n2 2 0\n2 0 0\n0 1 0\n", "0 0 0\n1 1 0\n1 0 0\n0 1 0\n"}) {  // lobes unequal, equal
    std::ofstream(tmp.file("bowtie.off")) << "OFF\n4 1 0\n" << bowtie << "4 0 1 2 3\n";
    CHECK_THROWS_WITH(load_soup(tmp.file("bowtie.off")),
                      Contains("bowtie.off line 7: face 0 is a polygon of 4 corners that crosses itself"));
  }
}

TEST_CASE("polygons with a corner of nearly 180 degrees split without slivers", "[core][io]") {
  // Break test: two hexagons (3 x 2 corners each) sharing the chain 4-5-6, its middle raised by 0.05. The
  // fan from the first corner has a flat triangle, and ear clipping cut the nearly straight corner 5 off
  // both hexagons: the same sliver twice, one dropped as a duplicate, edge (3, 5) in three faces, the mesh
  // refused. On a curved mesh of quads and merged quads such slivers overlapped (12 self-intersections).
  test::TempDir tmp;
  for (const double lift : {0.05, -0.05, 1e-6}) {
    std::ofstream(tmp.file("hex2.obj"))
        << "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 " << lift
        << "\nv 2 1 0\nv 0 2 0\nv 1 2 0\nv 2 2 0\nf 1 2 3 6 5 4\nf 4 5 6 9 8 7\n";
    INFO("middle corner raised by " << lift);
    LoadReport report;
    TriangleSoup soup = load_soup(tmp.file("hex2.obj"), &report);
    REQUIRE(soup.F.rows() == 8);
    CHECK(report.duplicate_faces_dropped == 0);
    CHECK(check_surface(soup.P, soup.F).problem().empty());
    for (Eigen::Index f = 0; f < soup.F.rows(); ++f) {
      const Vec3 p0 = soup.P.row(soup.F(f, 0)), p1 = soup.P.row(soup.F(f, 1)), p2 = soup.P.row(soup.F(f, 2));
      INFO("triangle " << f);
      CHECK((p1 - p0).cross(p2 - p0).z() >= 0.99);  // twice the area: every triangle a half square
    }
  }
  // Two non-planar hexagons sharing a chain raised like a roof (27 degrees): each closed the chain with
  // the chord (0, 3), over the same lens, so that edge had 4 faces.
  std::ofstream(tmp.file("roof.obj")) << "v 0 0 0\nv 0.333333 0 0.25\nv 0.666667 0 0.25\nv 1 0 0\nv 1 0.5 0\n"
                                         "v 0 0.5 0\nv 0 -0.5 0\nv 1 -0.5 0\nf 1 2 3 4 5 6\nf 4 3 2 1 7 8\n";
  TriangleSoup roof = load_soup(tmp.file("roof.obj"));
  CHECK(roof.F.rows() == 8);
  CHECK(check_surface(roof.P, roof.F).problem().empty());
  // Steeper, each split alone would still take the chord: two quads sharing a chain whose middle is raised
  // by 0.3 were both split along (0, 2) (an edge in 3 faces after the duplicate was dropped).
  std::ofstream(tmp.file("ridge.obj")) << "v 0 0 0\nv 0.5 0 0.3\nv 1 0 0\nv 0.5 0.5 0\nv 0.5 -0.5 0\n"
                                          "f 1 2 3 4\nf 3 2 1 5\n";
  LoadReport ridge_report;
  TriangleSoup ridge = load_soup(tmp.file("ridge.obj"), &ridge_report);
  CHECK(ridge.F.rows() == 4);
  CHECK(ridge_report.duplicate_faces_dropped == 0);
  CHECK(check_surface(ridge.P, ridge.F).problem().empty());
  // A square whose sides carry three corners each, bulged out by 1e-9: every fan had a sliver (shape 4e-10),
  // and the shell refused the mesh as singular.
  std::ostringstream square;
  square << "OFF\n16 1 0\n";
  for (int side = 0; side < 4; ++side)
    for (int k = 0; k < 4; ++k) {
      const double t = k / 4.0, bulge = 1e-9 * std::sin(M_PI * t);
      const Vec3 p = side == 0   ? Vec3(t, -bulge, 0)
                     : side == 1 ? Vec3(1 + bulge, t, 0)
                     : side == 2 ? Vec3(1 - t, 1 + bulge, 0)
                                 : Vec3(-bulge, 1 - t, 0);
      square << p.x() << " " << p.y() << " 0\n";
    }
  square << "16";
  for (int k = 0; k < 16; ++k) square << " " << k;
  std::ofstream(tmp.file("bulged.off")) << std::setprecision(17) << square.str() << "\n";
  LoadReport bulged_report;
  const TriangleSoup bulged = load_soup(tmp.file("bulged.off"), &bulged_report);
  REQUIRE(bulged.F.rows() == 14);
  CHECK(bulged_report.polygons_split_otherwise == 1);
  for (Eigen::Index f = 0; f < bulged.F.rows(); ++f) {
    const Vec3 p0 = bulged.P.row(bulged.F(f, 0)), p1 = bulged.P.row(bulged.F(f, 1)),
               p2 = bulged.P.row(bulged.F(f, 2));
    const double longest =
        std::max({(p1 - p0).squaredNorm(), (p2 - p1).squaredNorm(), (p0 - p2).squaredNorm()});
    INFO("triangle " << f);
    CHECK((p1 - p0).cross(p2 - p0).z() / longest >= 0.1);  // no sliver
  }
  // The concave pentagon at any size and far from the origin: 1e-100 across it had no normal and was fanned
  // folded, 1e80 across it was refused as crossing itself.
  for (const double size : {1e-100, 1e-60, 1.0, 1e60, 1e80})
    for (const double offset : {0.0, 1e8 * size}) {
      INFO("size " << size << ", offset " << offset);
      std::ostringstream pentagon;
      pentagon << std::setprecision(17);
      for (const auto& [x, y] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.5, 0.2}, {0.0, 1.0}})
        pentagon << "v " << offset + size * x << " " << offset + size * y << " " << offset << "\n";
      std::ofstream(tmp.file("scaled.obj")) << pentagon.str() << "f 1 2 3 4 5\n";
      const TriangleSoup scaled = load_soup(tmp.file("scaled.obj"));
      REQUIRE(scaled.F.rows() == 3);
      double area = 0;
      for (Eigen::Index f = 0; f < 3; ++f) {
        const Vec3 p0 = scaled.P.row(scaled.F(f, 0)), p1 = scaled.P.row(scaled.F(f, 1)),
                   p2 = scaled.P.row(scaled.F(f, 2));
        const double z = ((p1 - p0) / size).cross((p2 - p0) / size).z() / 2;
        CHECK(z > 0);
        area += z;
      }
      CHECK(area == Approx(0.6).epsilon(1e-6));  // the unit square less the notch (0.4)
    }
  // A side of zero length: named as such (it was "a polygon that crosses itself").
  std::ofstream(tmp.file("coincident.off")) << "OFF\n5 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n1 0 0\n5 0 1 4 2 3\n";
  CHECK_THROWS_WITH(
      load_soup(tmp.file("coincident.off")),
      Contains("face 0 is a polygon whose corners 1 and 2 (vertices 1 and 4) are at the same point"));
  // A convex quad keeps its first corner's fan even when the other diagonal is a little better.
  std::ofstream(tmp.file("quad.obj")) << "v 0 0 0\nv 1 0 0\nv 1.2 1 0\nv 0 1 0\nf 1 2 3 4\n";
  const TriangleSoup quad = load_soup(tmp.file("quad.obj"));
  REQUIRE(quad.F.rows() == 2);
  CHECK(quad.F.row(0) == Eigen::RowVector3i(0, 1, 2));
  CHECK(quad.F.row(1) == Eigen::RowVector3i(0, 2, 3));
}

TEST_CASE("two triangles wound against each other keep the file's 4 vertices, one face turned over",
          "[core][io]") {
  // The example. The loader once detached the second face with private vertex copies.
  test::TempDir tmp;
  std::ofstream(tmp.file("miswound.off")) << "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 3 2\n";
  TriangleSoup soup = load_soup(tmp.file("miswound.off"));
  REQUIRE(soup.P.rows() == 4);
  REQUIRE(soup.F.rows() == 2);
  CHECK(soup.F.row(1) == Eigen::RowVector3i(0, 3, 2));  // load_soup leaves the winding alone
  CHECK(check_surface(soup.P, soup.F).flipped_faces == 1);
  LoadReport report;
  const Mesh m = load_mesh(tmp.file("miswound.off"), &report);
  CHECK(m.n_vertices() == 4);
  CHECK(m.n_faces() == 2);
  CHECK(report.faces_flipped == 1);
  CHECK(positions(m) == soup.P);
  CHECK(faces(m) == soup.F);  // the same repair
  for (auto f : m.faces()) CHECK(m.calc_face_normal(f)[2] == Approx(1.0));
}

TEST_CASE("a third face on an edge: load_mesh refuses it by the edge's ids, load_soup keeps it",
          "[core][io]") {
  test::TempDir tmp;
  std::ofstream(tmp.file("fin.off"))
      << "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n";
  CHECK_THROWS_AS(load_mesh(tmp.file("fin.off")), TopologyError);
  CHECK_THROWS_WITH(load_mesh(tmp.file("fin.off")), Contains("fin.off") && Contains("edge (0, 1)") &&
                                                        Contains("faces (0, 1, 2)") && Contains("lattice") &&
                                                        Contains("rbf"));
  const TriangleSoup soup = load_soup(tmp.file("fin.off"));
  CHECK(soup.P.rows() == 5);
  CHECK(soup.F.rows() == 3);
  // Two cones touching at their tips: a non-manifold vertex, refused by its id.
  std::string cones = "OFF\n7 6 0\n0 0 0\n1 0 1\n0 1 1\n-1 -1 1\n1 0 -1\n0 1 -1\n-1 -1 -1\n";
  cones += "3 0 1 2\n3 0 2 3\n3 0 3 1\n3 0 5 4\n3 0 6 5\n3 0 4 6\n";
  std::ofstream(tmp.file("cones.off")) << cones;
  CHECK_THROWS_WITH(load_mesh(tmp.file("cones.off")),
                    Contains("vertex 0") && Contains("non-manifold vertex"));
  CHECK(load_soup(tmp.file("cones.off")).P.rows() == 7);
}

TEST_CASE("point clouds load with no faces from OFF, PLY and OBJ, and save back", "[core][io]") {
  test::TempDir tmp;
  std::ofstream(tmp.file("cloud.off")) << "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0.5\n";
  std::ofstream(tmp.file("cloud.ply"))
      << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
         "property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0.5\n";
  std::ofstream(tmp.file("cloud.obj")) << "# points\nv 0 0 0\nv 1 0 0\nv 0 1 0.5\nvn 0 0 1\n";
  for (const char* name : {"cloud.off", "cloud.ply", "cloud.obj"}) {
    INFO(name);
    const TriangleSoup soup = load_soup(tmp.file(name));
    REQUIRE(soup.P.rows() == 3);
    CHECK(soup.F.rows() == 0);
    CHECK(soup.P(2, 2) == 0.5);
    CHECK_THROWS_WITH(load_mesh(tmp.file(name)), Contains("no faces") && Contains("space methods"));
  }
  Positions P(100, 3);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (Eigen::Index i = 0; i < P.rows(); ++i) P.row(i) << u(rng), u(rng), u(rng) / 3;
  const Faces none(0, 3);
  for (const char* ext : {".off", ".obj", ".ply"}) {
    INFO(ext);
    save_mesh(P, none, tmp.file(std::string("round") + ext));
    const TriangleSoup back = load_soup(tmp.file(std::string("round") + ext));
    CHECK(back.P == P);
    CHECK(back.F.rows() == 0);
  }
  CHECK_THROWS_WITH(save_mesh(P, none, tmp.file("round.stl")), Contains("STL") && Contains("point cloud"));
  CHECK_FALSE(std::filesystem::exists(tmp.file("round.stl")));
}

TEST_CASE("soups keep their vertices through save and load, STL included", "[core][io]") {
  // A fin (three faces on edge 0-1), an unused vertex, and a face wound against its neighbour.
  Positions P(7, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 5, 5, 5, 1, 1, 0;
  Faces F(4, 3);
  F << 0, 1, 2, 1, 0, 3, 0, 1, 4, 1, 2, 6;
  test::TempDir tmp;
  for (const char* ext : {".off", ".obj", ".ply"}) {
    INFO(ext);
    save_mesh(P, F, tmp.file(std::string("soup") + ext));
    const TriangleSoup back = load_soup(tmp.file(std::string("soup") + ext));
    CHECK(back.P == P);
    CHECK(back.F == F);
  }
  // STL: the vertices are the distinct corners in order of first appearance; the unused one is lost.
  save_mesh(P, F, tmp.file("soup.stl"));
  const TriangleSoup stl = load_soup(tmp.file("soup.stl"));
  CHECK(stl.P.rows() == 6);
  CHECK(stl.F.rows() == 4);
  CHECK(stl.F.row(0) == Eigen::RowVector3i(0, 1, 2));
  CHECK(stl.F.row(3) == Eigen::RowVector3i(1, 2, 5));
  CHECK(stl.P.row(5) == P.row(6));
  const StlReadBack read_back = stl_read_back(P, F);
  CHECK(read_back.vertices == 6);
  CHECK(read_back.unused == 1);
  CHECK(read_back.merged == 0);
  CHECK(read_back.renumbered);
  // What comes back from an STL is kept by the next; a point shared by two vertices is joined.
  CHECK_FALSE(stl_read_back(stl.P, stl.F).renumbered);
  Positions twin = stl.P;
  twin.row(5) = twin.row(0);
  CHECK(stl_read_back(twin, stl.F).merged == 1);
  CHECK(stl_read_back(twin, stl.F).vertices == 5);
  // ASCII STL, with a repeated facet.
  std::ofstream(tmp.file("a.stl"))
      << "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
         "vertex 0 1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\n"
         "vertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\n"
         "facet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\n"
         "endloop\nendfacet\nendsolid t\n";
  LoadReport report;
  const Mesh a = load_mesh(tmp.file("a.stl"), &report);
  CHECK(a.n_vertices() == 4);
  CHECK(a.n_faces() == 2);
  CHECK(report.duplicate_faces_dropped == 1);
  std::ofstream(tmp.file("bad.stl")) << "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 zero\n";
  CHECK_THROWS_WITH(load_soup(tmp.file("bad.stl")), Contains("line 4") && Contains("'zero'"));
}

TEST_CASE("every mesh in shared/data loads with the file's vertex count", "[core][io][real]") {
  struct Case {
    const char* name;
    int vertices, faces;
  };
  // Counts as the loader gave them before it built on load_soup: the files are manifold and oriented.
  const Case cases[] = {
      {"bumpy.off", 1250, 2496},
      {"decimated-knight.off", 502, 1000},
      {"planexy.off", 25, 32},
      {"bump-domain.obj", 4172, 8058},
      {"survey/bar.off", 6084, 12106},
      {"survey/bar-laplacian_editing.off", 6084, 12106},
      {"survey/cactus.off", 5261, 10518},
      {"survey/cactus-laplacian_editing.off", 5261, 10518},
      {"survey/cylinder.off", 4802, 9600},
      {"survey/cylinder-laplacian_editing.off", 4802, 9600},
      {"survey/plane.off", 40401, 80000},
      {"survey/plane-laplacian_editing.off", 40401, 80000},
      {"libigl/decimated-max.obj", 5272, 10540},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const std::string path = test::shared_data(c.name);
    TriangleSoup soup = load_soup(path);
    CHECK(soup.P.rows() == c.vertices);
    CHECK(soup.F.rows() == c.faces);
    const SurfaceCheck check = check_surface(soup.P, soup.F);
    CHECK(check.problem() == "");
    CHECK(check.flipped_faces == 0);
    const Mesh m = load_mesh(path);
    CHECK(positions(m) == soup.P);
    CHECK(faces(m) == soup.F);
  }
}

TEST_CASE("an edit case keeps any input and says why a surface method cannot take it", "[core][io]") {
  test::TempDir tmp;
  std::ofstream(tmp.file("cloud.off")) << "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n";
  std::ofstream(tmp.file("cloud.sel")) << "0\n1\n2\n";
  const EditCase cloud = load_edit_case(tmp.file("cloud.off"), tmp.file("cloud.sel"));
  CHECK(cloud.P.rows() == 3);
  CHECK(cloud.F.rows() == 0);
  CHECK(cloud.region.num_handles() == 1);
  CHECK(cloud.surface_problem == "no faces (a point cloud)");
  CHECK_THROWS_AS(require_surface(cloud, "shell"), InvalidInput);
  CHECK_THROWS_WITH(require_surface(cloud, "shell"),
                    Contains("shell is a surface method") && Contains("cloud.off") &&
                        Contains("point cloud") &&
                        Contains("--method lattice, cage-mvc, cage-harmonic or rbf"));
  std::ofstream(tmp.file("miswound.off")) << "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 3 2\n";
  const EditCase repaired = load_edit_case(tmp.file("miswound.off"));
  CHECK(repaired.surface_problem.empty());
  CHECK(repaired.F.row(1) == Eigen::RowVector3i(0, 2, 3));
  CHECK_NOTHROW(require_surface(repaired, "shell"));
  CHECK_NOTHROW(require_surface(scene_case("lift", 300), "shell"));
  // A gap in the handle codes is named as such (the handles were counted as the largest code − 1 against
  // the .def: "defines 3 handle(s)" for one handle, coded 4).
  std::ofstream(tmp.file("gap.sel")) << "0\n1\n4\n";
  std::ofstream(tmp.file("one.def")) << "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  CHECK_THROWS_WITH(load_edit_case(tmp.file("cloud.off"), tmp.file("gap.sel"), tmp.file("one.def")),
                    Contains("gap.sel") && Contains("handle 0 (selection code 2) has no vertex"));
}

TEST_CASE("a corpus of bad mesh files gives specific errors, never a crash", "[core][io][bad-input]") {
  test::TempDir tmp;
  const auto write = [&](const std::string& name, const std::string& text) { return tmp.write(name, text); };
  CHECK_THROWS_WITH(load_mesh(tmp.file("missing.off")), Contains("cannot open") && Contains("missing.off"));
  std::string garbage;
  for (int i = 0; i < 4096; ++i) garbage.push_back(static_cast<char>((i * 7919 + 13) % 256));
  CHECK_THROWS_WITH(load_mesh(write("garbage.off", garbage)), Contains("not an OFF file"));
  CHECK_THROWS_WITH(load_mesh(write("garbage.ply", garbage)), Contains("not a PLY file"));
  CHECK_THROWS_WITH(load_mesh(write("garbage.stl", garbage)), Contains("not an STL file"));
  CHECK_THROWS_AS(load_mesh(write("garbage.obj", garbage)), InvalidInput);
  CHECK_THROWS_WITH(load_mesh(write("empty.off", "OFF\n0 0 0\n")), Contains("no vertices"));
  CHECK_THROWS_WITH(load_mesh(write("nofaces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n")), Contains("no faces"));
  // Positions spelled otherwise than x, y, z (or one missing) would read as zeros: refused by name.
  CHECK_THROWS_WITH(load_soup(write("upper.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float X\n"
                                                 "property float Y\nproperty float Z\nend_header\n1 2 3\n")),
                    Contains("line 7") && Contains("no property 'x'"));
  CHECK_THROWS_WITH(load_soup(write("noz.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                               "property float y\nend_header\n1 2\n")),
                    Contains("no property 'z'"));
  CHECK_THROWS_WITH(load_mesh(write("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n")),
                    Contains("line 4") && Contains("non-finite"));
  CHECK_THROWS_WITH(load_mesh(write("inf.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n")),
                    Contains("line 2") && Contains("non-finite"));
  CHECK_THROWS_WITH(load_mesh(write("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")),
                    Contains("line 6") && Contains("index 7 out of range"));
  CHECK_THROWS_WITH(load_mesh(write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")),
                    Contains("line 4") && Contains("out of range"));
  CHECK_THROWS_WITH(load_mesh(write("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n")), Contains("declares 3 vertices and 1 faces, but only 12 bytes follow"));
  // 4OFF's w was read as a colour (a bounding box twice too large); nOFF was "missing the face count".
  CHECK_THROWS_WITH(load_soup(write("h.off", "4OFF\n3 1 0\n0 0 0 2\n2 0 0 2\n0 2 0 2\n3 0 1 2\n")),
                    Contains("'4OFF' (homogeneous or n-dimensional coordinates) is not supported"));
  CHECK_THROWS_WITH(load_soup(write("n.off", "nOFF\n3\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")),
                    Contains("'nOFF'"));
  // Colours, normals and the like are read past and reported: a COFF's (they were dropped without a word),
  // then OBJ's and PLY's (only OFF's were); plain files report none.
  {
    const std::string head =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    const std::string tail = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const std::vector<std::tuple<std::string, std::string, int>> cases = {
        {"colours.off", "COFF\n3 1 0\n0 0 0\n1 0 0 0.9 0 0 1\n0 1 0\n3 0 1 2 1 0 0\n", 4},
        {"face-colour.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 1 0 0\n", 6},
        {"plain.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 0},
        {"vc.obj", "v 0 0 0\nv 1 0 0 1 0 0\nv 0 1 0\nf 1 2 3\n", 2},
        {"w.obj", "v 0 0 0 1\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n", 4},  // a lone w is no colour
        {"plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 0},
        {"c.ply", head + "property uchar red\n" + tail + "0 0 0 9\n1 0 0 9\n0 1 0 9\n3 0 1 2\n", 7},
        {"p.ply", head + tail + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 0}};
    for (const auto& [name, text, line] : cases) {
      LoadReport report;
      load_soup(write(name, text), &report);
      INFO(name);
      CHECK(report.first_attribute_line == line);
    }
  }
  // The longest header prefix, texture coordinates, colours and normals: read past (it was "not an OFF
  // file").
  {
    LoadReport report;
    const TriangleSoup soup = load_soup(write("stcn.off",
                                              "STCNOFF\n3 1 0\n0 0 0 0 0 1 0 0 1 0 0 1\n1 0 0 1 0 1 0 0 1 0 "
                                              "0 1\n0 1 0 0 1 1 0 0 1 0 0 1\n3 0 1 2\n"),
                                        &report);
    CHECK(soup.P.rows() == 3);
    CHECK(report.first_attribute_line == 3);
  }
  CHECK_THROWS_WITH(load_soup(write("stc4.off", "STC4OFF\n3 1 0\n0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n")),
                    Contains("(homogeneous or n-dimensional coordinates) is not supported"));
  // Words after a record are not colours: refused by name (they were dropped without a word).
  CHECK_THROWS_WITH(
      load_soup(write("face-junk.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 trailing junk\n")),
      Contains("line 6") && Contains("'trailing' after face 0's indices is not a number"));
  CHECK_THROWS_WITH(load_soup(write("vertex-junk.off", "OFF\n3 1 0\n0 0 0\n1 0 0 7 x\n0 1 0\n3 0 1 2\n")),
                    Contains("line 4") && Contains("'x' after vertex 1's coordinates is not a number"));
  // A whole file on one line: the records after the counts are named (it said "only 0 bytes follow").
  CHECK_THROWS_WITH(load_soup(write("one-line.off", "OFF 3 1 0 0 0 0 1 0 0 0 1 0 3 0 1 2\n")),
                    Contains("line 1") && Contains("the counts line goes on after the vertex, face and edge "
                                                   "counts with '0'"));
  CHECK_THROWS_WITH(load_soup(write("one-line2.off", "OFF\n3 1 0 0 0 0 1 0 0 0 1 0 3 0 1 2\n")),
                    Contains("line 2") && Contains("goes on after"));
  CHECK(load_soup(write("counts-comment.off", "OFF\n3 1 0 # counts\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"))
            .P.rows() == 3);
  // A face with two corners is named, not taken for a short file (the byte count assumed 3 corners).
  CHECK_THROWS_WITH(load_mesh(write("two.off", "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n2 1 3\n3 1 3 2\n")),
                    Contains("face 1 has 2 corners"));
  CHECK_THROWS_WITH(load_mesh(write("short2.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n\n\n\n\n\n\n\n\n\n\n\n\n\n")),
                    Contains("file ends after 2 of 3 vertices"));
  CHECK_THROWS_WITH(load_mesh(write("word.off", "OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n")),
                    Contains("line 4") && Contains("'zero'"));
  CHECK_THROWS_WITH(load_mesh(write("mesh.xyz", "1 2 3\n")), Contains("unknown format"));
  CHECK_THROWS_WITH(load_mesh(tmp.path.string() + "/"), Contains("is a folder; give a mesh file name"));
  CHECK_THROWS_WITH(load_mesh(tmp.path.string()), Contains("is a folder; give a mesh file name"));  // "unknown format ''"
}

// Issue 14, kind 2: counts are checked against the bytes that follow, headers are parsed strictly, and a
// reader stops at the first bad line without reading the rest of the file.
TEST_CASE("readers refuse counts the file cannot hold and stop at the first bad line", "[core][io][bad-input]") {
  test::TempDir tmp;
  const auto write = [&](const std::string& name, const std::string& text) { return tmp.write(name, text); };
  const std::string ply = "ply\nformat ascii 1.0\n";
  // A vertex count of 4e9 (no data): refused, not 1.5 GB/s of growth.
  CHECK_THROWS_WITH(load_soup(write("huge.ply", ply + "element vertex 4000000000\nproperty float x\nproperty float y\n"
                                                    "property float z\nend_header\n")),
                    Contains("element 'vertex' declares 4000000000 items, which need at least 24000000000 bytes, "
                             "but only 0 bytes follow"));
  // An element without properties and a huge count: skipped, not looped over forever.
  const Mesh junk = load_mesh(write("junk.ply", ply + "element junk 9000000000000000000\nelement vertex 3\n"
                                                      "property float x\nproperty float y\nproperty float z\n"
                                                      "element face 1\nproperty list uchar int vertex_indices\n"
                                                      "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  CHECK(junk.n_vertices() == 3);
  CHECK(junk.n_faces() == 1);
  // A count with trailing junk, a word too many, an unknown keyword: strict header.
  CHECK_THROWS_WITH(load_soup(write("tj.ply", ply + "element vertex 3abc\nproperty float x\nend_header\n")),
                    Contains("line 3") && Contains("bad element count '3abc'"));
  CHECK_THROWS_WITH(load_soup(write("extra.ply", ply + "element vertex 3 4\nend_header\n")),
                    Contains("line 3") && Contains("unexpected '4'"));
  CHECK_THROWS_WITH(load_soup(write("key.ply", ply + "elemnt vertex 3\nend_header\n")),
                    Contains("line 3") && Contains("unknown PLY header keyword 'elemnt'"));
  // OFF counts the rest of the file cannot hold.
  CHECK_THROWS_WITH(load_soup(write("huge.off", "OFF\n2000000000 0 0\n0 0 0\n")),
                    Contains("declares 2000000000 vertices and 0 faces, but only 6 bytes follow"));
  CHECK_THROWS_WITH(load_soup(write("faces.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n1000000000 0 1 2\n")),
                    Contains("line 6") && Contains("1000000000 corners, more than the file holds"));
  // Binary data as OBJ: stops at the first statement that is not a word (before: skipped it all).
  std::string binary = "v 0 0 0\n";
  for (long i = 0; i < 1 << 20; ++i) binary.push_back(static_cast<char>((i * 7919 + 13) % 256));
  // (byte 0 is a CR: line 2 is empty)
  CHECK_THROWS_WITH(load_soup(write("binary.obj", binary)), Contains("line 3") && Contains("not an OBJ statement"));
  // An STL with no triangles is not a point cloud.
  CHECK_THROWS_WITH(load_soup(write("empty.stl", "solid x\nendsolid x\n")), Contains("has no triangles"));
  CHECK_THROWS_WITH(load_soup(write("empty-binary.stl", std::string(84, '\0'))), Contains("has no triangles"));
  // A folder is named as one.
  std::filesystem::create_directory(tmp.file("folder.off"));
  CHECK_THROWS_WITH(load_soup(tmp.file("folder.off")), Contains("is a folder"));
}

// Issue 14, kind 9: what the PLY fuzzer found (a list count of 1.8e25 read as a float overflowed the
// conversion to an integer), the big-endian PLY it showed was refused, and the header and data
// leniencies it reached.
TEST_CASE("PLY: big-endian data reads, and headers and items that disagree are refused by line", "[core][io][bad-input]") {
  test::TempDir tmp;
  const auto write = [&](const std::string& name, const std::string& text) { return tmp.write(name, text); };
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string vertices = "0 0 0\n1 0 0\n0 1 0\n";
  REQUIRE(load_soup(write("ok.ply", head + vertices + "3 0 1 2\n")).F.rows() == 1);
  // The face line missing: the message said "element 'face' declares 1 items, but only 18 bytes follow the
  // header", as if the face alone had 18 bytes; it counts what the elements before it take too.
  CHECK_THROWS_WITH(load_soup(write("cut.ply", head + vertices)),
                    Catch::Contains("element 'face' declares 1 items, which with the elements before it need at "
                                    "least 20 bytes, but only 18 bytes follow the header"));

  // Big-endian binary: doubles and an int index list, byte-swapped.
  std::string big = "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                    "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  auto put_big = [&](auto v) {
    char bytes[sizeof(v)];
    std::memcpy(bytes, &v, sizeof(v));
    std::reverse(bytes, bytes + sizeof(v));
    big.append(bytes, sizeof(v));
  };
  const double xyz[3][3] = {{0.1, 0.2, 0.3}, {1.0 / 3.0, 0, 0}, {0, 1, -1e-17}};
  for (const auto& p : xyz)
    for (double x : p) put_big(x);
  big.push_back(3);
  for (int i : {0, 2, 1}) put_big(i);
  const TriangleSoup soup = load_soup(write("big.ply", big));
  REQUIRE(soup.P.rows() == 3);
  CHECK(soup.P(1, 0) == 1.0 / 3.0);
  CHECK(soup.P(2, 2) == -1e-17);
  CHECK(soup.F.row(0) == Eigen::RowVector3i(0, 2, 1));

  // The header: a list count must be an integer type (the fuzzer's input), one format, names once.
  std::string float_count = head;
  float_count.replace(float_count.find("uchar int"), 5, "float");
  CHECK_THROWS_WITH(load_soup(write("fc.ply", float_count + vertices + "3 0 1 2\n")),
                    Contains("line 8") && Contains("list count of type 'float'"));
  CHECK_THROWS_WITH(load_soup(write("first.ply", "ply junk\n" + head.substr(4) + vertices + "3 0 1 2\n")),
                    Contains("line 1") && Contains("'ply' alone"));
  CHECK_THROWS_WITH(load_soup(write("noformat.ply", "ply\n" + head.substr(head.find("element")) + vertices + "3 0 1 2\n")),
                    Contains("no 'format' line"));
  CHECK_THROWS_WITH(load_soup(write("twoformats.ply", "ply\nformat ascii 1.0\n" + head.substr(4) + vertices + "3 0 1 2\n")),
                    Contains("line 3") && Contains("second 'format'"));
  std::string twice = head;
  twice.insert(twice.find("property float z"), "property float y\n");
  CHECK_THROWS_WITH(load_soup(write("twice.ply", twice + vertices + "3 0 1 2\n")),
                    Contains("line 6") && Contains("two properties named 'y'"));
  std::string other_list = head;
  other_list.replace(other_list.find("vertex_indices"), 14, "corners");
  CHECK_THROWS_WITH(load_soup(write("otherlist.ply", other_list + vertices + "3 0 1 2\n")),
                    Contains("line 9") && Contains("no list property 'vertex_indices'"));
  std::string end_junk = head;
  end_junk.insert(end_junk.size() - 1, " junk");
  CHECK_THROWS_WITH(load_soup(write("endjunk.ply", end_junk + vertices + "3 0 1 2\n")),
                    Contains("line 9") && Contains("unexpected 'junk'"));
  // The data: one item per line, integer indices; data after the last element is reported.
  CHECK_THROWS_WITH(load_soup(write("extra.ply", head + vertices + "3 0 1 2 7\n")),
                    Contains("line 13") && Contains("face 0 has more values than the header's 1 properties ('7"));
  CHECK_THROWS_WITH(load_soup(write("extrav.ply", head + "0 0 0 5\n1 0 0\n0 1 0\n3 0 1 2\n")),
                    Contains("vertex 0 has more values"));
  CHECK_THROWS_WITH(load_soup(write("short.ply", head + "0 0\n0 1 0 0\n0 1 0\n3 0 1 2\n")),
                    Contains("line 10") && Contains("the line ends before the item's last value"));
  CHECK_THROWS_WITH(load_soup(write("wrapped.ply", head + vertices + "3 0 1\n2\n")),
                    Contains("line 13") && Contains("the line ends before"));
  LoadReport report;
  CHECK(load_soup(write("after.ply", head + vertices + "3 0 1 2\n3 0 2 1\n"), &report).F.rows() == 1);
  CHECK(report.first_ignored_line == 14);
  CHECK_THROWS_WITH(load_soup(write("half.ply", head + vertices + "3 0 1.5 2\n")),
                    Contains("vertex index 1.5, not an integer"));
  CHECK_THROWS_WITH(load_soup(write("neg.ply", head + vertices + "3 0 -5 2\n")),
                    Contains("line 13") && Contains("index -5 out of range"));
  CHECK_THROWS_WITH(load_soup(write("two.ply", head + vertices + "2 0 1\n")),
                    Contains("face 0 has a list of 2 items"));
  // CI's fuzzer: a list count far beyond any integer was converted to long long for the message (UB).
  for (const std::string count : {"1.6e35", "nan", "inf", "3.5", "-1e300"})
    CHECK_THROWS_WITH(load_soup(write("count.ply", head + vertices + count + " 0 1 2\n")),
                      Contains("face 0 has a list of") && Contains("(a face needs 3 to 2^20 corners)"));
}

// Issue 14, break test: OBJ indices are reported in the file's numbering, corner fields must be numbers,
// and the line where an OFF holds more than its header counts is reported (the extra faces were dropped
// silently).
TEST_CASE("OBJ and OFF: indices named as the file numbers them, malformed corners refused, uncounted faces reported",
          "[core][io][bad-input]") {
  test::TempDir tmp;
  const auto write = [&](const std::string& name, const std::string& text) { return tmp.write(name, text); };
  const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  CHECK(load_soup(write("later.obj", "f 1 2 3\n" + v)).F.rows() == 1);  // a face may name later vertices
  CHECK(load_soup(write("fields.obj", v + "vt 0 0\nvn 0 0 1\nf 1/1/1 2//1 3/1\n")).F.rows() == 1);
  CHECK_THROWS_WITH(load_soup(write("range.obj", v + "f 1 2 4\n")),
                    Contains("line 4") && Contains("vertex index 4, out of range: the file has 3 vertices"));
  CHECK_THROWS_WITH(load_soup(write("huge.obj", v + "f 1 2 9999999999\n")),
                    Contains("line 4") && Contains("9999999999 is out of range"));
  CHECK_THROWS_WITH(load_soup(write("back.obj", v + "f -1 -2 -4\n")),
                    Contains("line 4") && Contains("-4 reaches before the first vertex (3 vertices so far)"));
  CHECK_THROWS_WITH(load_soup(write("x.obj", v + "f 1/x 2 3\n")), Contains("line 4") && Contains("found 'x'"));
  CHECK_THROWS_WITH(load_soup(write("slash.obj", v + "f 1/ 2 3\n")), Contains("missing a texture or normal index"));
  // Third break test: a word after a vertex's coordinates was read without a word; colours still load.
  CHECK_THROWS_WITH(load_soup(write("word.obj", "v 0 0 0 abc\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")),
                    Contains("line 1") && Contains("found 'abc'"));
  CHECK(load_soup(write("colour.obj", "v 0 0 0 1 0.5 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).P.rows() == 3);
  // And a PLY's uint index beyond int is named as the file has it (it was named 2147483647).
  CHECK_THROWS_WITH(load_soup(write("uint.ply",
                                    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                    "property float y\nproperty float z\nelement face 1\n"
                                    "property list uchar uint vertex_indices\nend_header\n0 0 0\n"
                                    "1 0 0\n0 1 0\n3 0 1 4294967295\n")),
                    Contains("line 13") && Contains("vertex index 4294967295, out of range"));
  // CGAL's prim.off counts 7 faces and holds 8: read as counted (as CGAL does), and reported.
  LoadReport report;
  CHECK(load_soup(write("extra.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n"), &report).F.rows() == 1);
  CHECK(report.first_ignored_line == 7);
  CHECK(load_soup(write("blank.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n\n# end\n\n"), &report).F.rows() == 1);
  CHECK(report.first_ignored_line == 0);
}

// Issue 14, second break test: a bad file costs what is read of it even when its bad line is huge (a
// 2 GB file of NUL bytes was scanned whole for a line break, 2.1 GB resident), a binary STL whose header
// starts with "solid" is reported as binary, and numbers out of range are called that.
TEST_CASE("huge bad lines fail within a bounded read, and binary STL behind 'solid' is named", "[core][io][bad-input]") {
  test::TempDir tmp;
  const auto write = [&](const std::string& name, const std::string& text) { return tmp.write(name, text); };
  const std::string nul(65 << 20, '\0');  // 65 MiB without a line break
  CHECK_THROWS_WITH(load_soup(write("nul.off", "OFF\n3 1 0\n" + nul)),
                    Contains("line 3") && Contains("no line break within 64 MiB"));
  CHECK_THROWS_WITH(load_soup(write("nul.obj", "v 0 0 0\n" + nul)), Contains("line 2") && Contains("64 MiB"));
  CHECK_THROWS_WITH(load_soup(write("nul.ply", "ply\n" + nul)), Contains("line 2") && Contains("64 MiB"));
  const std::string ply = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                          "property float z\nend_header\n";
  CHECK_THROWS_WITH(load_soup(write("long.ply", ply + std::string(1000, '7'))), Contains("a value of 400 bytes or more"));
  CHECK_THROWS_WITH(read_sel(write("long.sel", std::string(1000, '1')), 3), Contains("line 1") && Contains("found '111"));
  // Binary STL with a "solid" header and a count that does not match the size.
  std::string stl = "solid but binary";
  stl.resize(80, '\0');
  const std::uint32_t count = 5;
  stl.append(reinterpret_cast<const char*>(&count), 4);
  stl.append(2 * 50, '\0');
  CHECK_THROWS_WITH(load_soup(write("lie.stl", stl)),
                    Contains("binary size 184 bytes does not match its 5 triangles (334 bytes)"));
  CHECK_THROWS_WITH(load_soup(write("big.off", "OFF\n3 1 0\n0 0 1e400\n1 0 0\n0 1 0\n3 0 1 2\n")),
                    Contains("line 3") && Contains("a coordinate '1e400' is out of range"));
}

// Issue 14, kind 7: files that other tools write and read read right, and messages point at the fault.
TEST_CASE("glued OFF headers, wrapped records, CR line ends and byte-order marks read right", "[core][io]") {
  test::TempDir tmp;
  const auto write = [&](const std::string& name, const std::string& text) { return tmp.write(name, text); };
  const auto check_square = [](const TriangleSoup& s) {
    REQUIRE(s.P.rows() == 4);
    CHECK(s.P.row(2) == Eigen::RowVector3d(1, 1, 0));
    REQUIRE(s.F.rows() == 2);
    CHECK(s.F.row(1) == Eigen::RowVector3i(0, 2, 3));
  };
  const std::string vertices = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n", faces = "3 0 1 2\n3 0 2 3\n";
  check_square(load_soup(write("glued.off", "OFF4 2 0\n" + vertices + faces)));  // ModelNet's header
  check_square(load_soup(write("wrapped.off", "OFF\n4 2 0\n0 0\n0\n1 0 0\n1 1\n0\n0 1 0\n3 0 1\n2\n3\n0 2 3\n")));
  // A line missing a number is not a wrapped record: the next record's numbers are left over. This tet
  // read with vertex 3 taken from the first face line, shifted faces, and exit 0.
  CHECK_THROWS_WITH(load_soup(write("short-vertex.off", "OFF\n4 4 0\n0 0 0\n1 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n"
                                                        "3 0 3 2\n3 1 2 3\n3 1 2 3\n")),
                    Contains("line 5: vertex 1 starts on line 4 with too few numbers") &&
                        Contains("is a number missing on line 4?"));
  CHECK_THROWS_WITH(load_soup(write("short-face.off", "OFF\n4 2 0\n" + vertices + "3 0 1\n3 0 2 3\n# (long enough for the counts)\n")),
                    Contains("line 8: face 0 starts on line 7"));
  std::string cr = "OFF\n4 2 0\n" + vertices + faces;
  std::replace(cr.begin(), cr.end(), '\n', '\r');
  check_square(load_soup(write("cr.off", cr)));
  std::string crlf;
  for (char c : "OFF\n4 2 0\n" + vertices + faces) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  check_square(load_soup(write("crlf.off", crlf)));
  const std::string bom = "\xEF\xBB\xBF";
  check_square(load_soup(write("bom.obj", bom + "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")));  // dropped v 1 before
  check_square(load_soup(write("bom.off", bom + "OFF\n4 2 0\n" + vertices + faces)));
  // Vertices packed several per line are read one per line: the message says so.
  CHECK_THROWS_WITH(load_soup(write("packed.off", "OFF\n4 0 0\n0 0 0 1 0 0\n1 1 0 0 1 0\n\n\n\n\n\n\n\n\n\n\n\n\n")),
                    Contains("file ends after 2 of 4 vertices") && Contains("line 3 has more than three numbers"));
  // A header counting two vertices too many: the first face lines were read as vertices, and the message
  // only said the file ended early in the faces.
  CHECK_THROWS_WITH(
      load_soup(write("toomany.off", "OFF\n6 2 0\n" + vertices + faces + "\n")),
      Contains("file ends after 0 of 2 faces (vertices 0 to 3 have three numbers, vertex 4 on line 7 "
               "more: if the header's vertex count 6 is too large"));
  CHECK_THROWS_WITH(load_soup(write("word.off", "OFFICE\n")), Contains("not OFF followed by counts"));
  // Bytes that are not text are shown as \xHH.
  CHECK_THROWS_WITH(load_soup(write("bad.obj", "v 0 0 0\n\x01\x02 1 2\n")), Contains("'\\x01\\x02'"));
}

TEST_CASE("saving is atomic: a failed save leaves the old file untouched", "[core][io]") {
  test::TempDir tmp;
  Positions P(3, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  Faces F(1, 3);
  F << 0, 1, 2;
  const std::string path = tmp.file("keep.off");
  save_mesh(P, F, path);
  const Mesh before = load_mesh(path);
  Positions bad = P;
  bad(1, 1) = std::nan("");
  CHECK_THROWS_WITH(save_mesh(bad, F, path), Contains("NaN") && Contains("nothing written"));
  CHECK(positions(load_mesh(path)) == positions(before));
  CHECK_THROWS_WITH(save_mesh(P, F, tmp.file("no/such/folder/x.off")), Contains("cannot write"));
  Eigen::VectorXd scalar(2);
  SaveOptions with_scalar;
  with_scalar.vertex_scalar = &scalar;
  CHECK_THROWS_WITH(save_mesh(P, F, tmp.file("s.ply"), with_scalar), Contains("2 scalars for 3 vertices"));
  CHECK_THROWS_WITH(save_mesh(P, F, tmp.file("s.off"), with_scalar), Contains(".ply"));
  // Nothing but the finished file is left in the folder.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(tmp.path)) files += e.is_regular_file();
  CHECK(files == 1);
}

TEST_CASE("PLY vertex properties read back by name, ASCII and binary", "[core][io]") {
  test::TempDir dir;
  Positions P(4, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Faces F(2, 3);
  F << 0, 1, 2, 0, 2, 3;
  Eigen::VectorXd h(4);
  h << 0.5, -1.25, 1e-300, 3;
  SaveOptions save;
  save.vertex_scalar = &h;
  save.scalar_name = "detail";
  const std::string path = dir.file("m.ply");
  save_mesh(P, F, path, save);
  CHECK(load_vertex_property(path, "detail") == h);
  CHECK(load_vertex_property(path, "x") == P.col(0));
  CHECK_THROWS_WITH(load_vertex_property(path, "quality"),
                    Contains("has no vertex property 'quality'") && Contains("x, y, z, detail"));
  // Binary: a float property between the coordinates.
  const std::string binary = dir.write("b.ply", std::string("ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
                                                            "property float x\nproperty float h\nproperty float y\n"
                                                            "property float z\nend_header\n") +
                                                    std::string(32, '\0'));  // 2 vertices of 4 floats
  CHECK(load_vertex_property(binary, "h") == Eigen::Vector2d::Zero());
  save_mesh(P, F, dir.file("m.off"));
  CHECK_THROWS_WITH(load_vertex_property(dir.file("m.off"), "detail"), Contains("read from PLY files"));
  CHECK_THROWS_WITH(load_vertex_property(path, ""), Contains("no property name"));
  // A list property by that name is there, but not one value per vertex (it was called missing).
  const std::string lists = dir.write("l.ply",
                                      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                      "property float y\nproperty float z\nproperty list uchar float lst\n"
                                      "end_header\n0 0 0 2 1 2\n");
  CHECK_THROWS_WITH(load_vertex_property(lists, "lst"), Contains("the vertex property 'lst' is a list"));
}
