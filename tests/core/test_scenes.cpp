#include <catch2/catch.hpp>

#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/scenes.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

TEST_CASE("bumpy plane and bar have about the requested size and a valid region", "[core][scenes]") {
  for (int res : {1000, 10000}) {
    SceneOptions o;
    o.resolution = res;
    for (SceneShape shape : {SceneShape::Plane, SceneShape::Bar}) {
      const Scene s = make_surface(shape, o);
      INFO(s.name << " " << res);
      CHECK(s.P.rows() > res / 2);
      CHECK(s.P.rows() < res * 2);
      CHECK_NOTHROW(s.region.validate(static_cast<int>(s.P.rows()), &s.F));
      CHECK(s.region.num_handles() == 1);
      CHECK(s.heights.maxCoeff() == Approx(s.bump_height).epsilon(0.05));
      CHECK(s.heights.minCoeff() >= 0.0);
      // Faces are oriented like the analytic normals (outwards on the bar, +z on the plane).
      const Positions N = vertex_normals(s.smooth, s.F);
      CHECK(N.cwiseProduct(s.smooth_normals).rowwise().sum().minCoeff() > 0.9);
      // The fine surface is a uniform Loop refinement of the coarse one.
      CHECK(s.refinement.faces.rows() == s.coarse_F.rows() * (1L << (2 * s.refinement.levels)));
      const Eigen::VectorXd row_sums = s.refinement.loop * Eigen::VectorXd::Ones(s.coarse_P.rows());
      CHECK((row_sums.array() - 1.0).abs().maxCoeff() <= 1e-12);
    }
  }
}

TEST_CASE("scene transforms: lift translates, twist and bend are rigid, bend follows the arc", "[core][scenes]") {
  SceneOptions o;
  o.resolution = 1000;
  const Scene lift = make_scene("lift", o);
  CHECK((lift.transforms[0].topRightCorner<3, 1>() - Vec3(0, 0, 0.3)).norm() == 0.0);
  for (const std::string name : {"bend120", "twist135", "bar-bend120", "bar-twist135"}) {
    const Scene s = make_scene(name, o);
    const Mat3 R = s.transforms[0].topLeftCorner<3, 3>();
    CHECK((R.transpose() * R - Mat3::Identity()).norm() <= 1e-12);
    CHECK(R.determinant() == Approx(1.0));
  }
  // Bend: the handle's inner edge (x = 0.8, z = 0) lands on the arc end, with the tangent rotated by 120°.
  const Scene bend = make_scene("bend120", o);
  const double theta = 120.0 * M_PI / 180, R = 0.6 / theta;
  const Vec3 end = transform_point(bend.transforms[0], Vec3(0.8, 0.3, 0));
  CHECK((end - Vec3(0.2 + R * std::sin(theta), 0.3, R - R * std::cos(theta))).norm() <= 1e-12);
  const Vec3 tangent = bend.transforms[0].topLeftCorner<3, 3>() * Vec3::UnitX();
  CHECK((tangent - Vec3(std::cos(theta), 0, std::sin(theta))).norm() <= 1e-12);
}

TEST_CASE("scenes are written as off + sel + def and read back identically", "[core][scenes]") {
  test::TempDir tmp;
  SceneOptions o;
  o.resolution = 500;
  const Scene s = make_scene("bar-twist135", o);
  write_scene(s, tmp.file("out"));
  const Mesh m = load_mesh(tmp.file("out/bar-twist135.off"));
  CHECK(positions(m) == s.P);
  CHECK(read_sel(tmp.file("out/bar-twist135.sel"), static_cast<int>(m.n_vertices())).codes() == s.region.codes());
  CHECK((read_def(tmp.file("out/bar-twist135.def"))[0] - s.transforms[0]).norm() == 0.0);
}

TEST_CASE("unknown scene names and bad resolutions are reported", "[core][scenes][bad-input]") {
  CHECK_THROWS_WITH(make_scene("lfit"), Contains("unknown scene 'lfit'") && Contains("bend120"));
  CHECK(parse_resolution("100k") == 100000);
  CHECK(parse_resolution("1M") == 1000000);
  CHECK(parse_resolution("2500") == 2500);
  CHECK_THROWS_AS(parse_resolution("many"), InvalidInput);
  CHECK_THROWS_AS(parse_resolution("10"), InvalidInput);
  CHECK_THROWS_AS(parse_resolution("5x"), InvalidInput);
  // Decimal only: hexadecimal, white space, signs, inf and nan were read by std::stod.
  CHECK(parse_resolution("2.5k") == 2500);
  for (const char* bad : {"0x10", " 100", "+100", "inf", "nan", "1e400", "", "k"})
    CHECK_THROWS_WITH(parse_resolution(bad), Contains("expected a vertex count"));
}
