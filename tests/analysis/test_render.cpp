#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <set>
#include <utility>
#include <vector>

#include "msdeform/analysis/render.h"
#include "msdeform/core/atomic_file.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/scenes.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

constexpr double kPi = 3.14159265358979323846;

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

TEST_CASE("render: the picture does not depend on the mesh's size or place", "[analysis][render]") {
  // A break test: at sizes below about 1e-15 or beyond 1e19 the picture was the background alone (exit 0),
  // from 1e15 its shading striped: Embree's single-precision products of coordinates under- and overflowed.
  const Scene s = plane(2000);
  RenderOptions o;
  o.width = 160;
  o.height = 120;
  const Image reference = render(s.P, s.F, o);
  REQUIRE(covered_fraction(reference, o) > 0.2);
  for (const double scale : {1e-60, 1e-15, 1e15, 1e20, 1e60}) {
    for (const double offset : {0.0, 1e6}) {
      CAPTURE(scale, offset);
      const Positions P = (s.P.array() + offset) * scale;
      const Image image = render(P, s.F, o);
      long differ = 0;
      for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x)
          if ((at(image, x, y) - at(reference, x, y)).cwiseAbs().maxCoeff() > 2) ++differ;
      CHECK(differ <= o.width * o.height / 200);  // 0.5 %: rounding at the outline
    }
  }
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
  CHECK_THROWS_AS(render(Positions(0, 3), Faces(0, 3), o), InvalidInput);  // nothing to draw
  o.point_radius = -1;
  CHECK_THROWS_WITH(render(s.P, Faces(0, 3), o), Contains("point_radius"));
  o.point_radius = 0;
  CHECK_THROWS_AS(write_png(Image(), "unused.png"), InvalidInput);
}

namespace {

// A 3×3 grid of points at x, y ∈ {−1, 0, 1}, z = 0, looked at straight down in a square image.
Positions point_grid() {
  Positions P(9, 3);
  for (int i = 0; i < 9; ++i) P.row(i) << i % 3 - 1.0, i / 3 - 1.0, 0.0;
  return P;
}

RenderOptions top_view(int size) {
  RenderOptions o;
  o.width = o.height = size;
  o.view_direction = Vec3(0, 0, 1);
  o.up = Vec3(0, 1, 0);
  o.samples_per_axis = 1;
  o.legend = false;
  return o;
}

bool is_background(const Image& image, const RenderOptions& o, int x, int y) {
  return (at(image, x, y) - background_at(o, y)).cwiseAbs().maxCoeff() <= 1;
}

// Runs [first, last] of non-background pixels along row y (along_row) or column y of the image.
std::vector<std::pair<int, int>> covered_runs(const Image& image, const RenderOptions& o, int line,
                                              bool along_row) {
  std::vector<std::pair<int, int>> runs;
  const int n = along_row ? image.width : image.height;
  for (int i = 0; i < n; ++i) {
    const bool covered = along_row ? !is_background(image, o, i, line) : !is_background(image, o, line, i);
    if (!covered) continue;
    if (!runs.empty() && runs.back().second == i - 1)
      runs.back().second = i;
    else
      runs.emplace_back(i, i);
  }
  return runs;
}

// The picture of the 3×3 grid: centres of its columns (pixels) and rows, and the discs' mean diameter.
struct GridPicture {
  std::vector<double> columns, rows;
  double diameter = 0;
};

// Finds the grid in the image through its middle row and column, which cross the middle point; checks
// that each holds exactly three discs.
GridPicture find_grid(const Image& image, const RenderOptions& o) {
  GridPicture g;
  for (bool along_row : {true, false}) {
    const auto runs = covered_runs(image, o, (along_row ? image.height : image.width) / 2, along_row);
    REQUIRE(runs.size() == 3);
    for (const auto& [first, last] : runs) {
      (along_row ? g.columns : g.rows).push_back(0.5 * (first + last + 1));
      g.diameter += (last - first + 1) / 6.0;
    }
  }
  return g;
}

}  // namespace

TEST_CASE("render: a point cloud is drawn as spheres where the points are, background between them",
          "[analysis][render][points]") {
  const Positions P = point_grid();
  RenderOptions o = top_view(201);
  o.point_radius = 0.1;
  const Image image = render(P, Faces(0, 3), o);
  const GridPicture g = find_grid(image, o);
  // The grid is centred and evenly spaced (all points at one depth: the projection is linear), and the
  // discs are 2 r / spacing = 0.2 of the spacing wide.
  const double spacing = 0.5 * (g.columns[2] - g.columns[0]);
  CHECK(g.columns[1] == Approx(o.width / 2.0).margin(1));
  CHECK(g.rows[1] == Approx(o.height / 2.0).margin(1));
  CHECK(g.columns[1] - g.columns[0] == Approx(spacing).margin(1));
  CHECK(g.rows[2] - g.rows[0] == Approx(2 * spacing).margin(1));
  CHECK(g.diameter == Approx(0.2 * spacing).margin(1.5));
  CHECK(spacing > 50);  // the grid fills the frame (tight framing)
  // Every point is drawn at its place and lit; between neighbours, and off the grid, only background.
  for (double x : g.columns)
    for (double y : g.rows) {
      const int px = static_cast<int>(x), py = static_cast<int>(y);
      INFO("point at pixel (" << px << ", " << py << ")");
      CHECK_FALSE(is_background(image, o, px, py));
      CHECK(at(image, px, py).sum() > 3 * 60);
    }
  // The image's edges, and midway between neighbours.
  std::vector<int> xs = {0, o.width - 1}, ys = {0, o.height - 1};
  for (int k = 0; k < 2; ++k) {
    xs.push_back(static_cast<int>(0.5 * (g.columns[k] + g.columns[k + 1])));
    ys.push_back(static_cast<int>(0.5 * (g.rows[k] + g.rows[k + 1])));
  }
  for (int x : xs)
    for (int y : ys) {
      INFO("pixel (" << x << ", " << y << ")");
      CHECK(is_background(image, o, x, y));
    }
  for (int x : xs)
    for (double y : g.rows) CHECK(is_background(image, o, x, static_cast<int>(y)));
  for (double x : g.columns)
    for (int y : ys) CHECK(is_background(image, o, static_cast<int>(x), y));
  // Nine discs and nothing else: their area over the image's.
  const double disc = kPi * std::pow(0.5 * g.diameter, 2);
  CHECK(covered_fraction(image, o) == Approx(9 * disc / (o.width * o.height)).epsilon(0.15));

  // The radius is the option's: twice as large draws discs twice as wide.
  o.point_radius = 0.2;
  const GridPicture twice = find_grid(render(P, Faces(0, 3), o), o);
  CHECK(twice.diameter / (0.5 * (twice.columns[2] - twice.columns[0])) == Approx(0.4).margin(0.03));
}

TEST_CASE("render: a per-point scalar colours each point's sphere with the colour map",
          "[analysis][render][points]") {
  const Positions P = point_grid();
  Eigen::VectorXd value(9);
  for (int i = 0; i < 9; ++i) value[i] = 0.5 * (P(i, 0) + 1);  // by column: 0, 0.5, 1
  RenderOptions o = top_view(201);
  o.point_radius = 0.1;
  o.vertex_scalar = &value;
  o.scalar_min = 0;
  o.scalar_max = 1;
  o.shadows = false;
  const Image image = render(P, Faces(0, 3), o);
  const GridPicture g = find_grid(image, o);
  // At a sphere's centre the normal faces the eye: lit from the front, each point keeps the hue of its value.
  for (double y : g.rows) {
    const int py = static_cast<int>(y);
    const Eigen::Vector3i low = at(image, static_cast<int>(g.columns[0]), py),
                          mid = at(image, static_cast<int>(g.columns[1]), py),
                          high = at(image, static_cast<int>(g.columns[2]), py);
    INFO("row " << py << ": " << low.transpose() << " / " << mid.transpose() << " / " << high.transpose());
    CHECK(low.z() > low.y() + 40);    // viridis(0): dark violet, blue above green
    CHECK(mid.y() > mid.x() + 40);    // viridis(0.5): teal, green above red
    CHECK(high.x() > high.z() + 80);  // viridis(1): yellow, red and green far above blue
    CHECK(high.y() > high.z() + 80);
  }
  // Without the scalar every point has the base colour.
  o.vertex_scalar = nullptr;
  const Image plain = render(P, Faces(0, 3), o);
  const int py = static_cast<int>(g.rows[1]);
  const Eigen::Vector3i left = at(plain, static_cast<int>(g.columns[0]), py),
                        right = at(plain, static_cast<int>(g.columns[2]), py);
  for (const Eigen::Vector3i& c : {left, right}) {  // warm clay: red above green above blue
    CHECK(c.x() > c.y());
    CHECK(c.y() > c.z());
  }
}

TEST_CASE("render: the default point radius follows the spacing of the cloud", "[analysis][render][points]") {
  // A regular 11×11 grid of spacing h (with a repeated point, which is no neighbour): the nearest other
  // point is h away from every point, so the radius is 0.85 h exactly.
  const double h = 0.25;
  Positions P(122, 3);
  for (int i = 0; i < 121; ++i) P.row(i) << h * (i % 11), h * (i / 11), 3.0;
  P.row(121) = P.row(42);
  CHECK(default_point_radius(P) == Approx(0.85 * h).epsilon(1e-12));
  // Scaling the cloud scales the radius; a single point has radius 1; no points is an error.
  CHECK(default_point_radius(Positions(7 * P)) == Approx(0.85 * 7 * h).epsilon(1e-12));
  CHECK(default_point_radius(Positions(P.topRows(1))) == 1);
  CHECK_THROWS_AS(default_point_radius(Positions(0, 3)), InvalidInput);

  // Rendered with the default radius the grid reads as a surface: the spheres of a square grid cover it
  // without gaps (0.85 h > h / √2), so the middle of the picture is covered everywhere.
  RenderOptions o = top_view(101);
  const Image image = render(P, Faces(0, 3), o);
  long gaps = 0;
  for (int y = 30; y <= 70; ++y)
    for (int x = 30; x <= 70; ++x) gaps += is_background(image, o, x, y);
  CHECK(gaps == 0);
  CHECK(covered_fraction(image, o) > 0.6);
  // A single point is a sphere in the middle of the frame, not an empty picture.
  const Image one = render(Positions(P.topRows(1)), Faces(0, 3), o);
  CHECK_FALSE(is_background(one, o, 50, 50));
  CHECK(covered_fraction(one, o) > 0.3);
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

  // A real point cloud (CGAL's b9 scan, 22300 points) with the default radius, plain and coloured by z.
  const TriangleSoup b9 = load_soup(test::cgal_mesh("b9.ply"));
  render_png(b9.P, b9.F, out + "/b9.png");
  const Eigen::VectorXd z = b9.P.col(2);
  RenderOptions b9_coloured;
  b9_coloured.vertex_scalar = &z;
  b9_coloured.scalar_label = "z";
  render_png(b9.P, b9.F, out + "/b9-z.png", b9_coloured);
  // The knight with every third face wound the other way, as a soup may come.
  Faces mixed = faces(knight);
  for (Eigen::Index f = 0; f < mixed.rows(); f += 3) std::swap(mixed(f, 1), mixed(f, 2));
  render_png(positions(knight), mixed, out + "/knight-mixed-winding.png", y_up);
}

TEST_CASE("view axes: a flat shape is seen from above, others stand along their longest axis or on their fixed part",
          "[analysis][render][view]") {
  const Scene flat = plane(2000);  // the unit square in z = 0 with bumps
  const ViewAxes z_up = view_axes(flat.P);
  CHECK(z_up.up == Vec3::UnitZ());
  CHECK(z_up.default_direction().isApprox(RenderOptions().view_direction));  // the old default, unchanged
  CHECK(z_up.direction(31.0, 34.4).normalized().isApprox(RenderOptions().view_direction.normalized(), 2e-3));
  CHECK(z_up.side.isApprox(z_up.front.cross(z_up.up)));

  // The same plane turned to stand in y: still seen along its normal.
  Positions turned(flat.P.rows(), 3);
  turned << flat.P.col(0), flat.P.col(2), flat.P.col(1);
  CHECK(view_axes(turned).up == Vec3::UnitY());

  // The bumpy bar (a tube along x) stands along x; lying with its fixed end at x = 0, it stands on it...
  SceneOptions o;
  o.resolution = 3000;
  const Scene bar = make_surface(SceneShape::Bar, o);
  CHECK(view_axes(bar.P).up == Vec3::UnitX());
  // ... but fixed along its underside (z < -0.13 over the whole length) it lies on it: +z is up.
  std::vector<int> below;
  for (int v = 0; v < bar.P.rows(); ++v)
    if (bar.P(v, 2) < -0.13) below.push_back(v);
  REQUIRE(!below.empty());
  CHECK(edit_view_axes(bar.P, below).up == Vec3::UnitZ());
  // Fixed at its top (the x = 1 end, like a figure held by its head) it still stands along +x, not upside down.
  std::vector<int> top;
  for (int v = 0; v < bar.P.rows(); ++v)
    if (bar.P(v, 0) > 0.9) top.push_back(v);
  CHECK(edit_view_axes(bar.P, top).up == Vec3::UnitX());
  // One pinned vertex on the underside says nothing about up, unlike the whole underside above (CGAL's bear,
  // --fixed vertex:0,2, lay on its side).
  const auto pin = std::min_element(below.begin(), below.end(), [&](int a, int b) { return bar.P(a, 2) < bar.P(b, 2); });
  CHECK(view_axes(bar.P).up != Vec3::UnitZ());
  CHECK(edit_view_axes(bar.P, {*pin}).up == view_axes(bar.P).up);
  // A fixed part around the middle gives no direction: the principal axes decide.
  std::vector<int> all(bar.P.rows());
  for (int v = 0; v < bar.P.rows(); ++v) all[v] = v;
  CHECK(edit_view_axes(bar.P, all).up == view_axes(bar.P).up);
  // A flat sheet is seen from above even when fixed at one side (the survey's plane edit).
  std::vector<int> side;
  for (int v = 0; v < flat.P.rows(); ++v)
    if (flat.P(v, 0) < 0.2) side.push_back(v);
  CHECK(edit_view_axes(flat.P, side).up == Vec3::UnitZ());
  CHECK_THROWS_AS(view_axes(Positions()), InvalidInput);
  CHECK_THROWS_AS(view_axes(flat.P, Vec3::Zero()), InvalidInput);
}

TEST_CASE("view axes: a sphere's or a cube's view does not depend on its size or place",
          "[analysis][render][view]") {
  // Break test: the principal axes of a shape with a regular solid's symmetry are any directions (equal
  // variances), and the eigen-solver's pick followed the rounding: a sphere scaled by 1e-3 stood along x
  // instead of y, a cube turned by 20° changed its picture in 9 of 16 sizes and places.
  Positions sphere;
  Faces sphere_faces;
  test::icosphere(3, sphere, sphere_faces);
  Positions cube(8, 3);
  for (int i = 0; i < 8; ++i) cube.row(i) << (i & 1), (i >> 1) & 1, (i >> 2) & 1;
  const Mat3 turn = Eigen::AngleAxisd(20 * M_PI / 180, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Positions turned_cube = cube * turn.transpose();
  // A second break test: a 32-sided cylinder along z (radius 1, height 2: its bounding box a cube) has two
  // equal variances; the extents measured along the arbitrary directions between them decided, and it stood
  // up or lay down with its place and size (scale 1e5, offset (55.5, 0, 0)·scale).
  Positions cylinder(64, 3);
  for (int i = 0; i < 32; ++i) {
    const double a = 2 * M_PI * i / 32;
    cylinder.row(i) << std::cos(a), std::sin(a), -1;
    cylinder.row(32 + i) << std::cos(a), std::sin(a), 1;
  }
  CHECK(view_axes(cylinder).up == Vec3::UnitZ());  // along its own axis, where the box has no longest side
  for (const Positions* shape : std::initializer_list<const Positions*>{&sphere, &turned_cube, &cylinder}) {
    const ViewAxes home = view_axes(*shape);
    for (const double scale : {1e-3, 0.7, 3.0, 1e5})
      for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(7.624, 7.624, 7.624), Vec3(1e6, 1e6, 1e6),
                                 Vec3(55.5, 0, 0), Vec3(1023.013, -55.1, 3.3)}) {
        INFO(shape->rows() << " vertices, scale " << scale << ", offset " << offset.transpose());
        const ViewAxes there = view_axes((scale * *shape).rowwise() + scale * offset.transpose());
        CHECK(there.up == home.up);
        CHECK(there.front == home.front);
      }
  }
}

TEST_CASE("view axes: a square's view does not depend on where it sits", "[analysis][render][view]") {
  // Break test: an exactly square flat shape has equal extents across its normal; moved far along x, the
  // rounding of max - min decided which one was thinner and the picture turned by 90°.
  const Scene flat = plane(2000);  // the unit square
  const ViewAxes home = view_axes(flat.P);
  // Offsets just below a power of two: there x + 1 crosses into the next binade and max - min rounds below 1.
  for (const double offset : {7.624, 1023.013, 16383.405, 1e6})
    for (int axis = 0; axis < 3; ++axis) {
      INFO("moved by " << offset << " along axis " << axis);
      const Positions moved = flat.P.rowwise() + offset * Vec3::Unit(axis).transpose();
      const ViewAxes there = view_axes(moved);
      CHECK(there.up == home.up);
      CHECK(there.front == home.front);
    }
}

TEST_CASE("view axes: CGAL's y-up armadillo stands upright, feet at the bottom of the picture",
          "[analysis][render][view]") {
  const TriangleSoup armadillo = load_soup(test::cgal_mesh("armadillo.off"));
  const Positions& P = armadillo.P;
  const Faces& F = armadillo.F;
  // Feet: below y = -40 (y runs from -54 to 97). Coloured blue, everything else clay.
  std::vector<int> feet;
  Positions colors(P.rows(), 3);
  for (int v = 0; v < P.rows(); ++v) {
    const bool foot = P(v, 1) < -40;
    if (foot) feet.push_back(v);
    colors.row(v) = foot ? Eigen::RowVector3d(0, 0, 1) : Eigen::RowVector3d(1, 0.6, 0.3);
  }
  for (const std::vector<int>& fixed : {std::vector<int>(), feet}) {
    const ViewAxes axes = edit_view_axes(P, fixed);
    CHECK(axes.up == Vec3::UnitY());
    RenderOptions o;
    o.width = 200;
    o.height = 200;
    o.up = axes.up;
    o.view_direction = axes.default_direction();
    o.vertex_colors = &colors;
    o.shadows = false;
    const Image image = render(P, F, o);
    // Mean picture row of the blue (foot) pixels and of the clay (body) pixels: the feet lie lower.
    double foot_rows = 0, body_rows = 0, n_foot = 0, n_body = 0;
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) {
        const Eigen::Vector3i c = at(image, x, y);
        if (c[0] < 40 && c[1] < 40 && c[2] > 60) foot_rows += y, ++n_foot;  // blue, not the sky-blue background
        if (c[0] > c[2] + 60) body_rows += y, ++n_body;
      }
    REQUIRE(n_foot > 50);
    REQUIRE(n_body > 1000);
    CHECK(foot_rows / n_foot > body_rows / n_body + 40);  // rows grow downwards
  }
}

TEST_CASE("render: vertex colours and highlighted faces paint the surface, and bad ones are named",
          "[analysis][render]") {
  const Scene s = plane(2000);
  RenderOptions o;
  o.width = 120;
  o.height = 90;
  o.shadows = false;
  // Mean colour of the pixels off the background.
  auto mean_surface = [&](const Image& image) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double n = 0;
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x)
        if ((at(image, x, y) - background_at(o, y)).cwiseAbs().maxCoeff() > 2) sum += at(image, x, y).cast<double>(), ++n;
    return Eigen::Vector3d(sum / std::max(n, 1.0));
  };
  Positions green = Positions::Zero(s.P.rows(), 3);
  green.col(1).setOnes();
  o.vertex_colors = &green;
  const Eigen::Vector3d g = mean_surface(render(s.P, s.F, o));
  CHECK(g[1] > 2 * g[0]);
  CHECK(g[1] > 2 * g[2]);
  std::vector<int> all(s.F.rows());
  for (int f = 0; f < s.F.rows(); ++f) all[f] = f;
  o.highlighted_faces = &all;  // over the vertex colours
  const Eigen::Vector3d r = mean_surface(render(s.P, s.F, o));
  CHECK(r[0] > 2 * r[1]);
  std::vector<int> outside = {static_cast<int>(s.F.rows())};
  o.highlighted_faces = &outside;
  CHECK_THROWS_WITH(render(s.P, s.F, o), Contains("highlighted face"));
  o.highlighted_faces = nullptr;
  const Positions short_colors = green.topRows(3);
  o.vertex_colors = &short_colors;
  CHECK_THROWS_WITH(render(s.P, s.F, o), Contains("vertex_colors has 3 rows"));
}
