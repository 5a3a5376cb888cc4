#include <catch2/catch.hpp>

#include <fstream>

#include "core/errors.h"
#include "core/mesh_info.h"
#include "core/mesh_io.h"
#include "core/scenes.h"
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
    CHECK(report.duplicated_vertices == 0);
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

TEST_CASE("polygons are triangulated, non-manifold faces are detached and reported", "[core][io]") {
  test::TempDir tmp;
  std::ofstream(tmp.file("quad.obj")) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
  LoadReport report;
  const Mesh quad = load_mesh(tmp.file("quad.obj"), &report);
  CHECK(quad.n_faces() == 2);
  CHECK(report.polygons_triangulated == 1);
  // Three triangles on one edge.
  std::ofstream(tmp.file("fin.off")) << "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n";
  LoadReport fin;
  const Mesh m = load_mesh(tmp.file("fin.off"), &fin);
  CHECK(m.n_faces() == 3);
  CHECK(fin.nonmanifold_faces == 1);
  CHECK(fin.duplicated_vertices == 3);
  CHECK(m.n_vertices() == 8);
  CHECK(mesh_info(m, &fin).nonmanifold_faces == 1);
}

TEST_CASE("a detached face's vertex copies hold the original coordinates", "[core][io][bad-input]") {
  // One triangle wound against its neighbour: OpenMesh cannot add it, so it is detached with vertex copies.
  // The copies once read freed memory (a point passed by reference into a reallocating add_vertex).
  test::TempDir tmp;
  std::ofstream(tmp.file("miswound.off")) << "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 3 2\n";
  for (int repeat = 0; repeat < 20; ++repeat) {  // reallocation happens at varying capacities
    const Mesh m = load_mesh(tmp.file("miswound.off"));
    REQUIRE(m.n_vertices() >= 4);
    const Positions P = positions(m);
    REQUIRE(P.allFinite());
    for (int i = 4; i < P.rows(); ++i) {
      double nearest = 1e300;
      for (int j = 0; j < 4; ++j) nearest = std::min(nearest, (P.row(i) - P.row(j)).norm());
      CHECK(nearest == 0.0);  // every copy sits exactly on an original vertex
    }
  }
}

TEST_CASE("a corpus of bad mesh files gives specific errors, never a crash", "[core][io][bad-input]") {
  test::TempDir tmp;
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(tmp.file(name), std::ios::binary) << text;
    return tmp.file(name);
  };
  CHECK_THROWS_WITH(load_mesh(tmp.file("missing.off")), Contains("cannot open") && Contains("missing.off"));
  std::string garbage;
  for (int i = 0; i < 4096; ++i) garbage.push_back(static_cast<char>((i * 7919 + 13) % 256));
  CHECK_THROWS_WITH(load_mesh(write("garbage.off", garbage)), Contains("not an OFF file"));
  CHECK_THROWS_WITH(load_mesh(write("garbage.ply", garbage)), Contains("not a PLY file"));
  CHECK_THROWS_WITH(load_mesh(write("garbage.stl", garbage)), Contains("not an STL file"));
  CHECK_THROWS_AS(load_mesh(write("garbage.obj", garbage)), InvalidInput);
  CHECK_THROWS_WITH(load_mesh(write("empty.off", "OFF\n0 0 0\n")), Contains("no vertices"));
  CHECK_THROWS_WITH(load_mesh(write("nofaces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n")), Contains("no faces"));
  CHECK_THROWS_WITH(load_mesh(write("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n")),
                    Contains("line 4") && Contains("non-finite"));
  CHECK_THROWS_WITH(load_mesh(write("inf.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n")),
                    Contains("line 2") && Contains("non-finite"));
  CHECK_THROWS_WITH(load_mesh(write("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")),
                    Contains("line 6") && Contains("index 7 out of range"));
  CHECK_THROWS_WITH(load_mesh(write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")),
                    Contains("line 4") && Contains("out of range"));
  CHECK_THROWS_WITH(load_mesh(write("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n")), Contains("file ends after 2 of 3 vertices"));
  CHECK_THROWS_WITH(load_mesh(write("word.off", "OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n")),
                    Contains("line 4") && Contains("'zero'"));
  CHECK_THROWS_WITH(load_mesh(write("mesh.xyz", "1 2 3\n")), Contains("unknown format"));
  CHECK_THROWS_WITH(load_mesh(tmp.path.string() + "/"), Contains("unknown format"));
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
