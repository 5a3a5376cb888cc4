#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <set>

#include "analysis/render.h"
#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/mesh_io.h"
#include "core/scenes.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

Scene plane(int resolution = 5000) {
  SceneOptions o;
  o.resolution = resolution;
  return make_surface(SceneShape::Plane, o);
}

// The documented background of row y, as 8-bit values.
Eigen::Vector3i background_at(const RenderOptions& o, int y) {
  const double t = static_cast<double>(y) / (o.height - 1);
  const Vec3 c = (1 - t) * o.background_top + t * o.background_bottom;
  return (c * 255).array().round().cast<int>();
}

Eigen::Vector3i at(const Image& image, int x, int y) {
  const std::uint8_t* p = image.pixel(x, y);
  return Eigen::Vector3i(p[0], p[1], p[2]);
}

double covered_fraction(const Image& image, const RenderOptions& o) {
  long differ = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      if ((at(image, x, y) - background_at(o, y)).cwiseAbs().maxCoeff() > 2) ++differ;
  return static_cast<double>(differ) / (static_cast<double>(image.width) * image.height);
}

double mean_brightness(const Image& image) {
  double sum = 0;
  for (std::uint8_t c : image.rgb) sum += c;
  return sum / static_cast<double>(image.rgb.size());
}

}  // namespace

TEST_CASE("render: the bumpy plane fills the view, is lit, and is written as PNG", "[analysis][render]") {
  const Scene s = plane();
  RenderOptions o;
  o.width = 400;
  o.height = 300;
  const Image image = render(s.P, s.F, o);
  REQUIRE(image.width == 400);
  REQUIRE(image.height == 300);
  REQUIRE(image.rgb.size() == 3u * 400 * 300);
  CHECK(covered_fraction(image, o) > 0.2);
  const double brightness = mean_brightness(image);
  CHECK(brightness > 60);
  CHECK(brightness < 235);
  // The corners are background: the whole bounding sphere is in view.
  for (int y : {0, o.height - 1})
    for (int x : {0, o.width - 1}) CHECK((at(image, x, y) - background_at(o, y)).cwiseAbs().maxCoeff() <= 1);

  test::TempDir dir;
  const std::string path = dir.file("plane.png");
  write_png(image, path);
  const std::string png = read_file(path, "test");
  REQUIRE(png.size() > 1000);
  CHECK(png.substr(0, 8) == std::string("\x89PNG\r\n\x1a\n", 8));
  render_png(s.P, s.F, dir.file("again.png"), o);
  CHECK(read_file(dir.file("again.png"), "test") == png);  // deterministic
}

TEST_CASE("render: a scalar field is colour-mapped with a legend", "[analysis][render]") {
  const Scene s = plane();
  RenderOptions o;
  o.width = 400;
  o.height = 300;
  o.vertex_scalar = &s.heights;
  o.scalar_label = "height";
  const Image image = render(s.P, s.F, o);
  std::set<int> colours;
  for (size_t i = 0; i < image.rgb.size(); i += 3)
    colours.insert(image.rgb[i] << 16 | image.rgb[i + 1] << 8 | image.rgb[i + 2]);
  CHECK(colours.size() > 500);
  // Viridis is green-blue in the middle, never grey: some pixels are clearly coloured.
  long coloured = 0;
  for (size_t i = 0; i < image.rgb.size(); i += 3)
    if (image.rgb[i + 1] > image.rgb[i] + 40) ++coloured;
  CHECK(coloured > 2000);

  // An explicit range is used as given; the plain render differs from the coloured one.
  o.scalar_min = -1;
  o.scalar_max = 1;
  CHECK(render(s.P, s.F, o).rgb != image.rgb);
}

TEST_CASE("render: framing keeps the whole mesh in view", "[analysis][render]") {
  const Scene s = plane(2000);
  RenderOptions o;
  o.width = 200;
  o.height = 150;
  o.samples_per_axis = 1;
  const double tight = covered_fraction(render(s.P, s.F, o), o);
  o.framing = Framing::BoundingSphere;
  const Image sphere_image = render(s.P, s.F, o);
  const double sphere = covered_fraction(sphere_image, o);
  CHECK(sphere > 0.1);
  CHECK(sphere < tight);
  // Nothing touches the border: the mesh is entirely inside the frame.
  for (int x = 0; x < o.width; ++x)
    for (int y : {0, o.height - 1})
      REQUIRE((at(sphere_image, x, y) - background_at(o, y)).cwiseAbs().maxCoeff() <= 1);
  // A given sphere twice as large draws the mesh at half the size: about a quarter of the pixels.
  o.sphere_center = Vec3(0.5, 0.5, 0);
  o.sphere_radius = 2 * (s.P.rowwise() - o.sphere_center.transpose()).rowwise().norm().maxCoeff();
  const double far = covered_fraction(render(s.P, s.F, o), o);
  CHECK(far > 0.15 * sphere);
  CHECK(far < 0.35 * sphere);
}

TEST_CASE("render: degenerate faces and a flat view do not break the picture", "[analysis][render]") {
  Positions P;
  Faces F;
  test::icosphere(2, P, F);
  Faces with_degenerate(F.rows() + 2, 3);
  with_degenerate.topRows(F.rows()) = F;
  with_degenerate.row(F.rows()) << 0, 0, 1;  // repeated index
  with_degenerate.row(F.rows() + 1) << 0, 1, 0;
  RenderOptions o;
  o.width = 120;
  o.height = 90;
  const Image image = render(P, with_degenerate, o);
  CHECK(covered_fraction(image, o) > 0.3);
  const double brightness = mean_brightness(image);
  CHECK(brightness > 60);
  CHECK(brightness < 235);
}

TEST_CASE("render: bad input is named", "[analysis][render]") {
  const Scene s = plane(500);
  RenderOptions o;
  o.width = 64;
  o.height = 48;
  const Eigen::VectorXd short_scalar = Eigen::VectorXd::Zero(5);
  o.vertex_scalar = &short_scalar;
  CHECK_THROWS_WITH(render(s.P, s.F, o), Contains("vertex_scalar"));
  o.vertex_scalar = nullptr;
  o.samples_per_axis = 0;
  CHECK_THROWS_AS(render(s.P, s.F, o), InvalidInput);
  o.samples_per_axis = 1;
  o.view_direction = Vec3::Zero();
  CHECK_THROWS_AS(render(s.P, s.F, o), InvalidInput);
  o.view_direction = Vec3(0, 0, 1);  // parallel to up: another up axis is chosen
  CHECK(covered_fraction(render(s.P, s.F, o), o) > 0.2);
  CHECK_THROWS_AS(render(s.P, Faces(0, 3), o), InvalidInput);
  CHECK_THROWS_AS(write_png(Image(), "unused.png"), InvalidInput);
}

TEST_CASE("render: a soup's faces look alike whichever way they are wound", "[analysis][render]") {
  Positions P;
  Faces F;
  test::icosphere(3, P, F);
  Faces mixed = F;
  for (Eigen::Index f = 0; f < F.rows(); f += 3) std::swap(mixed(f, 1), mixed(f, 2));  // a third flipped
  RenderOptions o;
  o.width = 160;
  o.height = 120;
  const Image consistent = render(P, F, o), soup = render(P, mixed, o);
  long differ = 0;
  int largest = 0;
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const int d = (at(consistent, x, y) - at(soup, x, y)).cwiseAbs().maxCoeff();
      largest = std::max(largest, d);
      differ += d > 3;
    }
  INFO("pixels differing by more than 3: " << differ << ", largest difference " << largest);
  CHECK(differ == 0);
}

TEST_CASE("robust scalar range and colour map", "[analysis][render]") {
  Eigen::VectorXd errors = Eigen::VectorXd::LinSpaced(1000, 0.001, 1.0);
  errors[999] = 1000;  // an outlier does not stretch the range
  auto [lo, hi] = robust_scalar_range(errors);
  CHECK(lo == 0);
  CHECK(hi == Approx(0.99).epsilon(1e-12));
  const Eigen::VectorXd signed_values = Eigen::VectorXd::LinSpaced(101, -1, 1);
  std::tie(lo, hi) = robust_scalar_range(signed_values);
  CHECK(lo == Approx(-0.98));
  CHECK(hi == Approx(0.98));
  std::tie(lo, hi) = robust_scalar_range(Eigen::VectorXd::Zero(10));
  CHECK(hi > lo);
  CHECK_THROWS_AS(robust_scalar_range(Eigen::VectorXd()), InvalidInput);

  CHECK(viridis(0).isApprox(Vec3(0.267004, 0.004874, 0.329415)));
  CHECK(viridis(1).isApprox(Vec3(0.993248, 0.906157, 0.143936)));
  CHECK(viridis(-3) == viridis(0));
  CHECK(viridis(7) == viridis(1));
  // Lightness grows monotonically along the map (the point of a perceptual map).
  double previous = -1;
  for (int i = 0; i <= 64; ++i) {
    const Vec3 c = viridis(i / 64.0);
    const double luma = 0.2126 * c.x() + 0.7152 * c.y() + 0.0722 * c.z();
    CHECK(luma > previous);
    previous = luma;
  }
}

TEST_CASE("text and contact sheets", "[analysis][render]") {
  Image canvas(100, 20, Vec3(1, 1, 1));
  draw_text(canvas, 2, 2, "Ab-0.5%", Vec3::Zero(), 2);
  long dark = 0;
  for (std::uint8_t c : canvas.rgb) dark += c == 0;
  CHECK(dark > 3 * 40);
  CHECK(text_width("Ab-0.5%", 2) == 2 * (7 * 6 - 1));
  CHECK(text_height(2) == 14);
  draw_text(canvas, 90, 15, "clipped at the border", Vec3::Zero(), 3);  // must not write out of bounds

  const Image red(30, 20, Vec3(1, 0, 0)), blue(40, 10, Vec3(0, 0, 1));
  const Image sheet = tile_images({red, blue, red}, 2, {"a", "b", "c"});
  CHECK(sheet.width > 2 * 40);
  CHECK(sheet.height > 2 * 20);
  CHECK(at(sheet, sheet.width / 4, 4 + 10) == Eigen::Vector3i(255, 0, 0));
  CHECK_THROWS_AS(tile_images({}, 2), InvalidInput);
  CHECK_THROWS_AS(tile_images({red}, 0), InvalidInput);
  CHECK_THROWS_WITH(tile_images({red, blue}, 2, {"only one"}), Contains("labels"));
}

// Pictures for a person to look at: run with MSD_RENDER_DIR=/some/folder test_analysis "[.look]".
TEST_CASE("render: pictures of the test meshes", "[.look]") {
  const char* dir = std::getenv("MSD_RENDER_DIR");
  REQUIRE(dir);
  const std::string out(dir);
  const Scene s = make_surface(SceneShape::Plane, SceneOptions{});
  render_png(s.P, s.F, out + "/plane.png");
  RenderOptions coloured;
  coloured.vertex_scalar = &s.heights;
  coloured.scalar_label = "bump height";
  render_png(s.P, s.F, out + "/plane-heights.png", coloured);

  RenderOptions y_up;
  y_up.up = Vec3(0, 1, 0);
  y_up.view_direction = Vec3(0.5, 0.35, 1.0);
  const Mesh knight = load_mesh(test::shared_data("decimated-knight.off"));
  render_png(positions(knight), faces(knight), out + "/knight.png", y_up);
  const Mesh cactus = load_mesh(test::cgal_mesh("cactus.off"));
  render_png(positions(cactus), faces(cactus), out + "/cactus.png", y_up);
  const Positions cactus_P = positions(cactus);
  const Eigen::VectorXd y = cactus_P.col(1);
  RenderOptions cactus_coloured = y_up;
  cactus_coloured.vertex_scalar = &y;
  cactus_coloured.scalar_label = "y";
  const Image a = render(positions(knight), faces(knight), y_up),
              b = render(cactus_P, faces(cactus), cactus_coloured);
  write_png(tile_images({a, b}, 2, {"knight 502 V", "cactus: y (0-100%)"}), out + "/sheet.png");
}
