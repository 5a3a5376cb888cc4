#include <catch2/catch.hpp>

#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/region.h"
#include "msdeform/core/scenes.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

TEST_CASE("sel, dmat and def files round-trip", "[core][region]") {
  test::TempDir tmp;
  Region r(10);
  r.set_fixed({0, 1});
  r.set_handle({8, 9}, 0);
  r.set_handle({5}, 1);
  write_sel(r, tmp.file("a.sel"));
  const Region back = read_sel(tmp.file("a.sel"), 10);
  CHECK(back.codes() == r.codes());
  CHECK(back.num_handles() == 2);
  CHECK(back.handle_vertices(1) == std::vector<int>{5});
  CHECK(back.free_vertices() == std::vector<int>{2, 3, 4, 6, 7});

  Mat4 T = Mat4::Identity();
  T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  T.topRightCorner<3, 1>() = Vec3(0.1, -2, 1e-7);
  write_def({T, Mat4::Identity()}, tmp.file("a.def"));
  const auto defs = read_def(tmp.file("a.def"));
  REQUIRE(defs.size() == 2);
  CHECK((defs[0] - T).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("write_sel refuses what validate refuses: a handle code skipped", "[core][region]") {
  // Third break test: codes 0, 1, 3 were written, and every deform then refused the file.
  test::TempDir tmp;
  const std::string path = tmp.file("gap.sel");
  CHECK_THROWS_WITH(write_sel(Region::from_codes({0, 1, 3}), path),
                    Contains("gap.sel") && Contains("handle 0 (selection code 2) has no vertex") &&
                        Contains("nothing was written"));
  CHECK_FALSE(std::filesystem::exists(path));
  CHECK_THROWS_WITH(Region::from_codes({0, 1, 5}),
                    Contains("vertex 2 has selection code 5") && Contains("3 vertices carry codes up to 4"));
}

TEST_CASE("real selections load: knight groups and CGAL's cactus benchmark", "[core][region][real]") {
  const Mesh knight = load_mesh(test::shared_data("decimated-knight.off"));
  const Region groups = read_dmat_groups(test::shared_data("decimated-knight-selection.dmat"), 502);
  CHECK(groups.num_handles() == 3);
  CHECK_FALSE(groups.free_vertices().empty());
  const Faces knight_faces = faces(knight);
  groups.validate(502, &knight_faces);

  const Mesh cactus = load_mesh(test::cgal_mesh("cactus.off"));
  const Region sel = read_sel(test::cgal_deformation_data("cactus.sel"), static_cast<int>(cactus.n_vertices()));
  CHECK(sel.fixed_vertices().size() == 68);
  CHECK(sel.free_vertices().size() == 465);
  CHECK(sel.handle_vertices(0).size() == 87);
  const Faces cactus_faces = faces(cactus);
  sel.validate(static_cast<int>(cactus.n_vertices()), &cactus_faces);
  const auto def = read_def(test::cgal_deformation_data("cactus.def"));
  REQUIRE(def.size() == 1);
  CHECK(def[0](0, 0) == Approx(0.999641));
  CHECK(def[0](2, 3) == Approx(0.821073));
}

TEST_CASE("geometric predicates select the right vertices", "[core][region]") {
  Positions P(4, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 1;
  CHECK(select_box(P, Vec3(-0.5, -0.5, -0.5), Vec3(1.5, 0.5, 0.5)) == std::vector<int>{0, 1});
  // Corners the wrong way round said "selects no vertex" in the tool.
  CHECK_THROWS_WITH(select_box(P, Vec3(1, 1, 1), Vec3(-1, 1, 1)),
                    Contains("the box's x range is empty (1 > -1)"));
  CHECK(select_sphere(P, Vec3(0, 0, 0), 1.0) == std::vector<int>{0, 1, 2});
  CHECK(select_halfspace(P, Vec3(0.5, 0, 0), Vec3(1, 0, 0)) == std::vector<int>{1, 3});
}

TEST_CASE("bad selection and transform files give specific errors", "[core][region][bad-input]") {
  test::TempDir tmp;
  const auto write = [&](const std::string& name, const std::string& text) { return tmp.write(name, text); };
  CHECK_THROWS_WITH(read_sel(tmp.file("missing.sel"), 3), Contains("cannot open") && Contains("missing.sel"));
  CHECK_THROWS_WITH(read_sel(write("short.sel", "0\n1\n"), 3), Contains("has 2 labels but the mesh has 3 vertices"));
  CHECK_THROWS_WITH(read_sel(write("neg.sel", "0\n-1\n2\n"), 3), Contains("line 2") && Contains("label -1"));
  // Issue 14, kind 2: a huge label is refused by line before anything is sized by it (it allocated 8.4 GB
  // in decompose), and .dmat ids beyond int are not wrapped into handle 0 or free.
  CHECK_THROWS_WITH(read_sel(write("huge.sel", "0\n2147483647\n2\n"), 3),
                    Contains("line 2") && Contains("label 2147483647 for vertex 1 is out of range"));
  CHECK_THROWS_WITH(read_sel(write("five.sel", "0\n1\n5\n"), 3), Contains("line 3") && Contains("at most 3 handles"));
  CHECK_THROWS_WITH(read_dmat_groups(write("big.dmat", "1 3\n-1\n4294967296\n0\n"), 3),
                    Contains("line 3") && Contains("group 4294967296 is out of range"));
  CHECK_THROWS_WITH(read_dmat_groups(write("big2.dmat", "1 3\n-1\n4294967295\n0\n"), 3),
                    Contains("line 3") && Contains("out of range"));
  CHECK_THROWS_WITH(Region::from_codes({0, 1, 2147483647}), Contains("vertex 2 has selection code 2147483647"));
  // A folder given as a selection is named as one (it read as "0 labels").
  CHECK_THROWS_WITH(read_sel(tmp.path.string(), 3), Contains("is a folder"));
  // CR-only line ends with comments (the scene command's own .sel starts with '#' lines).
  CHECK(read_sel(write("cr.sel", "# three\r# labels\r0\r1\r2\r"), 3).codes() == std::vector<int>{0, 1, 2});
  CHECK_THROWS_WITH(read_sel(write("crbad.sel", "# c\r0\rx\r2\r"), 3), Contains("line 3"));
  // Devices are not files (/dev/zero read forever).
  CHECK_THROWS_WITH(read_sel("/dev/zero", 3), Contains("is a device"));
  // A byte-order mark is not part of the first label.
  CHECK(read_sel(write("bom.sel", "\xEF\xBB\xBF" "0\n1\n2\n"), 3).codes() == std::vector<int>{0, 1, 2});
  CHECK_THROWS_WITH(read_sel(write("word.sel", "0\nx\n2\n"), 3), Contains("line 2") && Contains("found 'x'"));
  CHECK_THROWS_WITH(read_def(write("bad.def", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0\n")),
                    Contains("line 4: 3 numbers starting at entry 12 of matrix 0"));
  CHECK_THROWS_WITH(read_def(write("short.def", "1 0 0 0\n0 1 0 0\n0 0 1 0\n")),
                    Contains("12 numbers") && Contains("4x4"));
  // Twelve on one line was "12 numbers; expected one 4x4 matrix" without its line.
  CHECK_THROWS_WITH(read_def(write("twelve.def", "1 0 0 0 0 1 0 0 0 0 1 0\n")), Contains("line 1: 12 numbers"));
  CHECK_THROWS_WITH(read_def(write("proj.def", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n")), Contains("not affine"));
  // A row split over lines (3 numbers, then 5) was read as if the line breaks were not there.
  CHECK_THROWS_WITH(
      read_def(write("split.def", "1 0 0\n0 0 1 0 0\n0 0 1 0\n0 0 0 1\n")),
      Contains("line 1: 3 numbers starting at entry 0 of matrix 0") && Contains("4 numbers per line"));
  CHECK(read_def(write("one-line.def", "1 0 0 0.5 0 1 0 0 0 0 1 0 0 0 0 1\n"))[0](0, 3) == 0.5);
  CHECK_THROWS_WITH(read_def(write("nan.def", "1 0 0 0\n0 nan 0 0\n0 0 1 0\n0 0 0 1\n")), Contains("line 2"));
  CHECK_THROWS_WITH(read_dmat_groups(write("two.dmat", "2 3\n0 0 0 1 1 1\n"), 3), Contains("one column"));
  // A selection with far more labels than vertices stops at the first one too many (it read them all).
  std::string many = "0\n1\n2\n";
  for (int i = 0; i < 1000000; ++i) many += "1\n";
  CHECK_THROWS_WITH(read_sel(write("many.sel", many), 3),
                    Contains("line 4") && Contains("more than 3 values (expected one label per vertex"));
  // Two labels on one line: the line is named (it said only "line 4: more than 3 values", the file's last).
  CHECK_THROWS_WITH(read_sel(write("two.sel", "0\n1 2\n1\n"), 3),
                    Contains("two.sel line 3: more than 3 values") && Contains("line 2 holds more than one"));
  CHECK_THROWS_WITH(read_sel(write("short.sel", "0 1\n1\n"), 4),
                    Contains("has 3 labels but the mesh has 4 vertices; line 1 holds more than one"));
  CHECK(read_sel(write("row.sel", "0 1 2\n"), 3).handle_of(2) == 0);  // the count right: read as it is
  CHECK_THROWS_WITH(read_dmat_groups(write("many.dmat", "1 3\n" + many), 3),
                    Contains("line 5") && Contains("more than 5 values"));
}

TEST_CASE("region validation names an unconstrained free component", "[core][region][bad-input]") {
  // Two separate triangles: the second is entirely free.
  Positions P(6, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 0, 0, 6, 0, 0, 5, 1, 0;
  Faces F(2, 3);
  F << 0, 1, 2, 3, 4, 5;
  Region r(6);
  r.set_fixed({0});
  r.set_handle({1}, 0);
  CHECK_THROWS_AS(r.validate(6, &F), TopologyError);
  CHECK_THROWS_WITH(r.validate(6, &F), Contains("free component 1") && Contains("3 vertices") && Contains("vertex 3"));
  r.set_fixed({4});
  CHECK_NOTHROW(r.validate(6, &F));
  CHECK_THROWS_WITH(Region(5).validate(6, &F), Contains("5 vertex labels but the mesh has 6"));
  Region gap(6);
  gap.set_handle({0, 3}, 1);  // handle 0 empty
  CHECK_THROWS_WITH(gap.validate(6, &F), Contains("handle 0") && Contains("no vertex"));
  r.set_free({4});
  CHECK_NOTHROW(r.validate(6));  // without faces (a space method) components are not checked
}

TEST_CASE("region validation refuses a handle that no face reaches", "[core][region][bad-input]") {
  // The break test's grid with one vertex that no face uses as the handle: exit 0, handle error 0, and
  // the surface left at rest.
  Positions P(4, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 100, 100, 100;
  Faces F(1, 3);
  F << 0, 1, 2;
  Region r(4);
  r.set_fixed({0});
  r.set_handle({1}, 0);
  r.set_handle({3}, 1);
  CHECK_THROWS_AS(r.validate(4, &F), TopologyError);
  CHECK_THROWS_WITH(r.validate(4, &F),
                    Contains("handle 1") && Contains("vertex 3") && Contains("no face uses"));
  CHECK_NOTHROW(r.validate(4));  // a space method deforms space around it
  r.set_handle({2, 3}, 1);       // with a vertex on the surface it moves the surface
  CHECK_NOTHROW(r.validate(4, &F));
  // The second break test: a fixed part of such vertices only let the whole surface translate.
  Region loose(4);
  loose.set_fixed({3});
  loose.set_handle({1}, 0);
  CHECK_THROWS_WITH(loose.validate(4, &F),
                    Contains("the fixed part") && Contains("vertex 3") && Contains("hold"));
  CHECK_NOTHROW(loose.validate(4));
  loose.set_fixed({0, 3});
  CHECK_NOTHROW(loose.validate(4, &F));
  // Third break test: through faces the surface methods leave out (zero area) only, likewise.
  Faces two(2, 3);
  two << 0, 1, 2, 1, 3, 2;  // the second face stands for a zero-area one
  const std::vector<char> usable = {1, 0};
  Region through(4);
  through.set_fixed({0});
  through.set_handle({3}, 0);
  CHECK_NOTHROW(through.validate(4, &two));
  CHECK_THROWS_WITH(through.validate(4, &two, &usable),
                    Contains("handle 0") && Contains("no face of nonzero area uses") && Contains("vertex 3"));
}
