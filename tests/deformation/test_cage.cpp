// Cage-based free-form deformation (seed 9.5.2): mean value coordinates (partition of unity, linear
// precision, continuity, positivity in a convex cage, agreement with Ju et al.'s formula) on, near and away
// from the cage; harmonic coordinates on a grid; the generated 26-DOP cage; the deformer on the space seam.

#include <random>

#include "msdeform/core/errors.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/cage.h"
#include "test_util.h"

namespace msd {
namespace {

// The paper's pseudo-code (Ju, Schaefer & Warren 2005, Fig. 4) for generic points (no special cases): the
// reference the robust evaluation must agree with away from the cage and its face planes.
std::vector<double> paper_mvc(const Positions& C, const Faces& F, const Vec3& x) {
  const int m = static_cast<int>(C.rows());
  std::vector<double> d(m), w(m, 0.0);
  std::vector<Vec3> u(m);
  for (int l = 0; l < m; ++l) {
    d[l] = (Vec3(C.row(l)) - x).norm();
    u[l] = (Vec3(C.row(l)) - x) / d[l];
  }
  double total = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const int v[3] = {F(f, 0), F(f, 1), F(f, 2)};
    double theta[3], c[3], s[3];
    for (int i = 0; i < 3; ++i) theta[i] = 2 * std::asin((u[v[(i + 1) % 3]] - u[v[(i + 2) % 3]]).norm() / 2);
    const double h = (theta[0] + theta[1] + theta[2]) / 2;
    Mat3 U;
    U << u[v[0]], u[v[1]], u[v[2]];
    const double sign = U.determinant() > 0 ? 1.0 : -1.0;
    for (int i = 0; i < 3; ++i) {
      c[i] = 2 * std::sin(h) * std::sin(h - theta[i]) /
                 (std::sin(theta[(i + 1) % 3]) * std::sin(theta[(i + 2) % 3])) -
             1;
      s[i] = sign * std::sqrt(std::max(0.0, 1 - c[i] * c[i]));
    }
    for (int i = 0; i < 3; ++i) {
      const int ip = (i + 1) % 3, im = (i + 2) % 3;
      const double wi =
          (theta[i] - c[ip] * theta[im] - c[im] * theta[ip]) / (d[v[i]] * std::sin(theta[ip]) * s[im]);
      w[v[i]] += wi;
      total += wi;
    }
  }
  for (double& wi : w) wi /= total;
  return w;
}

struct Cage {
  std::string name;
  Positions P;
  Faces F;
  bool convex = true;
};

// A level-1 icosphere (convex), the 26-DOP around a bumpy bar (convex, large coplanar regions), and a
// non-convex "L": two boxes fused, 12 vertices.
std::vector<Cage> test_cages() {
  std::vector<Cage> cages(3);
  cages[0].name = "icosphere";
  test::icosphere(1, cages[0].P, cages[0].F);
  cages[1].name = "26-DOP";
  SceneOptions o;
  o.resolution = 2500;
  offset_kdop_cage(make_scene("bar-bend120", o).P, 0.05, 1, cages[1].P, cages[1].F);
  // The L: the profile (0,0) (2,0) (2,1) (1,1) (1,2) (0,2) in the xy-plane, extruded over z in [0, 1].
  Cage& L = cages[2];
  L.name = "L";
  L.convex = false;
  const double profile[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  L.P.resize(12, 3);
  for (int i = 0; i < 6; ++i) {
    L.P.row(i) << profile[i][0], profile[i][1], 0;
    L.P.row(6 + i) << profile[i][0], profile[i][1], 1;
  }
  std::vector<Eigen::Vector3i> f;
  // bottom (normal −z) and top (+z): the L split into convex pieces (0,1,2,3), (0,3,4,5)
  for (const auto& t : std::vector<Eigen::Vector3i>{{0, 2, 1}, {0, 3, 2}, {0, 4, 3}, {0, 5, 4}}) {
    f.push_back(t);
    f.push_back(Eigen::Vector3i(t[0] + 6, t[2] + 6, t[1] + 6));
  }
  for (int i = 0; i < 6; ++i) {  // sides: the profile is counter-clockwise, so (i, i+1, top) faces outward
    const int j = (i + 1) % 6;
    f.push_back({i, j, j + 6});
    f.push_back({i, j + 6, i + 6});
  }
  L.F.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t i = 0; i < f.size(); ++i) L.F.row(i) = f[i].transpose();
  return cages;
}

double diagonal(const Positions& P) { return bounding_box_diagonal(P); }

// |Σ w − 1| and |Σ w c − x| / diag.
std::pair<double, double> precision(const Positions& C, const std::vector<double>& w, const Vec3& x) {
  double sum = 0;
  Vec3 y = Vec3::Zero();
  for (Eigen::Index l = 0; l < C.rows(); ++l) {
    sum += w[l];
    y += w[l] * Vec3(C.row(l));
  }
  return {std::abs(sum - 1), (y - x).norm() / diagonal(C)};
}

// Random points of the cage's bounding box grown by `grow` (relative), split by the winding number.
void random_points(const MeanValueCage& cage, double grow, int count, std::vector<Vec3>& inside,
                   std::vector<Vec3>& outside, unsigned seed = 3) {
  std::mt19937 rng(seed);
  const Positions& C = cage.positions();
  const Vec3 lo = C.colwise().minCoeff(), hi = C.colwise().maxCoeff(), pad = grow * (hi - lo);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < count; ++i) {
    const Vec3 t(u(rng), u(rng), u(rng));
    const Vec3 x = (lo - pad).array() + t.array() * (hi - lo + 2 * pad).array();
    (cage.winding_number(x) > 0.5 ? inside : outside).push_back(x);
  }
}

TEST_CASE("mvc: partition of unity and linear precision inside, outside, near and on the cage", "[cage]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  for (const Cage& c : test_cages()) {
    INFO(c.name);
    const MeanValueCage cage(c.P, c.F);
    MeanValueWorkspace ws;
    std::vector<double> w(cage.num_vertices());
    double worst_sum = 0, worst_lin = 0;
    std::string worst_where;
    auto check = [&](const Vec3& x, const char* where = "random") {
      cage.coordinates(x, ws, w.data());
      for (double wl : w) REQUIRE(std::isfinite(wl));
      const auto [sum, lin] = precision(c.P, w, x);
      worst_sum = std::max(worst_sum, sum);
      if (lin > worst_lin) worst_where = where;
      worst_lin = std::max(worst_lin, lin);
    };
    std::vector<Vec3> inside, outside;
    random_points(cage, 0.5, 400, inside, outside);
    REQUIRE(inside.size() > 20);
    REQUIRE(outside.size() > 20);
    for (const Vec3& x : inside) check(x);
    for (const Vec3& x : outside) check(x);
    for (const double scale : {3.0, 30.0})
      check(scale * diagonal(c.P) * Vec3(0.3, -0.5, 0.81), "far outside");
    const double diag = diagonal(c.P);
    for (Eigen::Index f = 0; f < c.F.rows(); ++f) {
      const Vec3 a = c.P.row(c.F(f, 0)), b = c.P.row(c.F(f, 1)), cc = c.P.row(c.F(f, 2));
      const Vec3 n = (b - a).cross(cc - a).normalized();
      double l0 = u(rng) + 0.05, l1 = u(rng) + 0.05, l2 = u(rng) + 0.05;
      const double s = l0 + l1 + l2;
      const Vec3 on_face = (l0 / s) * a + (l1 / s) * b + (l2 / s) * cc;
      check(on_face, "on a face");
      check(on_face + 1e-10 * diag * n, "1e-10 outside a face");
      check(on_face - 1e-10 * diag * n, "1e-10 inside a face");
      check(on_face + 1e-6 * diag * n, "1e-6 outside a face");
      check(0.3 * a + 0.7 * b, "on an edge");
      check(0.3 * a + 0.7 * b + 1e-11 * diag * (n + (cc - a).normalized()), "beside an edge");
      check(a, "on a vertex");
      check(a + 1e-12 * diag * Vec3(0.6, 0.0, 0.8), "beside a vertex");
    }
    INFO("worst linear precision: " << worst_where);
    CHECK(worst_sum <= 1e-12);
    CHECK(worst_lin <= 1e-12);
  }
}

TEST_CASE(
    "mvc: equal to Ju et al.'s formula at generic points, the vertex on a vertex, barycentric on a face",
    "[cage]") {
  for (const Cage& c : test_cages()) {
    INFO(c.name);
    const MeanValueCage cage(c.P, c.F);
    MeanValueWorkspace ws;
    std::vector<double> w(cage.num_vertices());
    std::vector<Vec3> inside, outside;
    random_points(cage, 0.3, 100, inside, outside, 5);
    double worst = 0;
    for (const auto* set : {&inside, &outside})
      for (const Vec3& x : *set) {
        cage.coordinates(x, ws, w.data());
        const std::vector<double> ref = paper_mvc(c.P, c.F, x);
        for (size_t l = 0; l < w.size(); ++l) worst = std::max(worst, std::abs(w[l] - ref[l]));
      }
    CHECK(worst <= 1e-9);
    // On a vertex: that vertex alone; on a face: its barycentric coordinates; on an edge: linear.
    cage.coordinates(c.P.row(3), ws, w.data());
    for (size_t l = 0; l < w.size(); ++l) CHECK(w[l] == (l == 3 ? 1.0 : 0.0));
    const Vec3 a = c.P.row(c.F(0, 0)), b = c.P.row(c.F(0, 1)), cc = c.P.row(c.F(0, 2));
    cage.coordinates(0.2 * a + 0.3 * b + 0.5 * cc, ws, w.data());
    CHECK(w[c.F(0, 0)] == Approx(0.2).margin(1e-12));
    CHECK(w[c.F(0, 1)] == Approx(0.3).margin(1e-12));
    CHECK(w[c.F(0, 2)] == Approx(0.5).margin(1e-12));
    cage.coordinates(0.25 * a + 0.75 * b, ws, w.data());
    CHECK(w[c.F(0, 0)] == Approx(0.25).margin(1e-12));
    CHECK(w[c.F(0, 1)] == Approx(0.75).margin(1e-12));
  }
}

TEST_CASE("mvc: continuous across a face and through the plane of a face outside it", "[cage]") {
  for (const Cage& c : test_cages()) {
    INFO(c.name);
    const MeanValueCage cage(c.P, c.F);
    MeanValueWorkspace ws;
    const int m = cage.num_vertices();
    std::vector<double> w0(m), w1(m);
    const double diag = diagonal(c.P);
    auto jump = [&](const Vec3& x, const Vec3& y) {
      cage.coordinates(x, ws, w0.data());
      cage.coordinates(y, ws, w1.data());
      double worst = 0;
      for (int l = 0; l < m; ++l) worst = std::max(worst, std::abs(w0[l] - w1[l]));
      return worst;
    };
    double across = 0, through_plane = 0;
    for (Eigen::Index f = 0; f < c.F.rows(); ++f) {
      const Vec3 a = c.P.row(c.F(f, 0)), b = c.P.row(c.F(f, 1)), cc = c.P.row(c.F(f, 2));
      const Vec3 n = (b - a).cross(cc - a).normalized();
      const Vec3 p = (a + b + cc) / 3;
      across = std::max(across, jump(p + 1e-9 * diag * n, p - 1e-9 * diag * n));
      // In the face's plane, beyond its edge (a, b): the face is seen edge-on there.
      const Vec3 beyond = 0.5 * (a + b) + 0.7 * (0.5 * (a + b) - cc);
      for (const double eta : {1e-12, 1e-10}) {
        through_plane = std::max(through_plane, jump(beyond + eta * diag * n, beyond - eta * diag * n));
        through_plane = std::max(through_plane, jump(beyond + eta * diag * n, beyond));
      }
    }
    CHECK(across <= 1e-6);
    CHECK(through_plane <= 1e-7);
  }
}

TEST_CASE("mvc: linear in the distance to a face plane outside the face, down to 1e-12 (the thin case)",
          "[cage]") {
  // A unit cube; points in the plane z = 0 beyond the bottom face, then lifted by η. Every face in that plane
  // is seen edge-on; the coordinates are smooth there, so w(η) − w(0) ≈ η w'(0) for every η. Ju et al.'s
  // formula loses it below η ≈ 1e-6 (its terms cancel to O(η²)).
  Positions C(8, 3);
  for (int i = 0; i < 8; ++i) C.row(i) << (i & 1), ((i >> 1) & 1), ((i >> 2) & 1);
  Faces F(12, 3);
  F << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3,
      7, 5;
  REQUIRE_NOTHROW(check_cage(C, F, "test"));
  const MeanValueCage cage(C, F);
  MeanValueWorkspace ws;
  std::vector<double> w0(8), w(8);
  for (const Vec3& base : {Vec3(1.7, 0.4, 0), Vec3(-0.5, 1.3, 0), Vec3(0.3, -0.2, 0)}) {
    INFO(base.transpose());
    cage.coordinates(base, ws, w0.data());
    std::vector<double> slope;
    for (const double eta : {1e-4, 1e-6, 1e-8, 1e-10, 1e-12}) {
      cage.coordinates(base - eta * Vec3::UnitZ(), ws, w.data());
      double change = 0;
      for (int l = 0; l < 8; ++l) change = std::max(change, std::abs(w[l] - w0[l]));
      slope.push_back(change / eta);
    }
    REQUIRE(slope.front() > 1e-3);
    for (const double s : slope) CHECK(s == Approx(slope.front()).epsilon(1e-2));  // at 1e-12: round-off of w
  }
}

TEST_CASE("mvc: non-negative inside a convex cage", "[cage]") {
  for (const Cage& c : test_cages()) {
    if (!c.convex) continue;
    INFO(c.name);
    const MeanValueCage cage(c.P, c.F);
    MeanValueWorkspace ws;
    std::vector<double> w(cage.num_vertices());
    std::vector<Vec3> inside, outside;
    random_points(cage, 0.0, 300, inside, outside, 7);
    double lowest = 1;
    for (const Vec3& x : inside) {
      cage.coordinates(x, ws, w.data());
      lowest = std::min(lowest, *std::min_element(w.begin(), w.end()));
    }
    CHECK(lowest >= -1e-14);
  }
}

TEST_CASE("harmonic coordinates: partition of unity, linear precision, non-negative and smooth inside",
          "[cage]") {
  for (const Cage& c : test_cages()) {
    INFO(c.name);
    const HarmonicCoordinates hc(c.P, c.F, 32);
    const MeanValueCage cage(c.P, c.F);
    const int m = hc.num_vertices();
    CHECK(hc.num_inside_nodes() > 100);
    std::vector<double> w(m), w2(m);
    std::vector<Vec3> inside, outside;  // outside: within the cage's box, so within the grid
    random_points(cage, 0.0, 400, inside, outside, 9);
    double worst_sum = 0, worst_lin = 0, lowest = 1;
    for (const auto* set : {&inside, &outside})
      for (const Vec3& x : *set) {
        hc.coordinates(x, w.data());
        const auto [sum, lin] = precision(c.P, w, x);
        worst_sum = std::max(worst_sum, sum);
        worst_lin = std::max(worst_lin, lin);
        if (set == &inside) lowest = std::min(lowest, *std::min_element(w.begin(), w.end()));
      }
    CHECK(worst_sum <= 1e-9);
    CHECK(worst_lin <= 1e-9);
    CHECK(lowest >= -1e-3);
    // Smooth: along a segment through the cage, steps of a tenth of a cell change no coordinate by more
    // than a few times what the largest gradient across the segment allows.
    const Vec3 lo = c.P.colwise().minCoeff(), hi = c.P.colwise().maxCoeff();
    const Vec3 from = lo + 0.2 * (hi - lo), to = lo + 0.8 * (hi - lo);
    const int steps = static_cast<int>(10 * (to - from).norm() / hc.cell_size());
    double largest_step = 0, total_variation = 0;
    hc.coordinates(from, w.data());
    for (int s = 1; s <= steps; ++s) {
      hc.coordinates(from + (to - from) * s / steps, w2.data());
      double step = 0;
      for (int l = 0; l < m; ++l) {
        step = std::max(step, std::abs(w2[l] - w[l]));
        total_variation += std::abs(w2[l] - w[l]);
      }
      largest_step = std::max(largest_step, step);
      w.swap(w2);
    }
    CHECK(largest_step <= 0.02);
  }
}

TEST_CASE("offset k-DOP cage: closed, manifold, outward and enclosing on every built-in scene", "[cage]") {
  SceneOptions o;
  o.resolution = 2500;
  std::vector<std::pair<std::string, Positions>> inputs;
  for (const std::string& name : scene_names()) inputs.push_back({name, make_scene(name, o).P});
  // A box: its 8 corners and points on its faces, so that many planes touch the input along whole faces
  // and edges; a flat square (zero thickness); a segment (zero extent in two directions).
  Positions box(8 + 6 * 25, 3);
  for (int i = 0; i < 8; ++i) box.row(i) << (i & 1) * 2.0, ((i >> 1) & 1) * 1.0, ((i >> 2) & 1) * 0.5;
  for (int f = 0, r = 8; f < 6; ++f)
    for (int j = 0; j < 25; ++j, ++r) {
      Vec3 p(0.25 * (j % 5), 0.25 * (j / 5), f % 2);
      std::swap(p[2], p[f / 2]);
      box.row(r) = p.cwiseProduct(Vec3(2.0, 1.0, 0.5)).transpose();
    }
  inputs.push_back({"box", box});
  Positions square(100, 3);
  for (int i = 0; i < 100; ++i) square.row(i) << (i % 10) / 9.0, (i / 10) / 9.0, 0.0;
  inputs.push_back({"flat square", square});
  Positions segment(10, 3);
  for (int i = 0; i < 10; ++i) segment.row(i) << i, 2.0 * i, 0.0;
  inputs.push_back({"segment", segment});
  for (const auto& [name, P] : inputs) {
    for (int sub = 0; sub <= 2; ++sub) {
      INFO(name << ", subdivisions " << sub);
      Positions C;
      Faces F;
      offset_kdop_cage(P, 0.05, sub, C, F);
      bool flipped = true;
      CHECK_NOTHROW(check_cage(C, F, "test", &flipped));
      CHECK_FALSE(flipped);
      const MeanValueCage cage(C, F);
      double lowest = 2, highest = 0;
      for (Eigen::Index i = 0; i < P.rows(); ++i) {
        const double wn = cage.winding_number(P.row(i));
        lowest = std::min(lowest, wn);
        highest = std::max(highest, wn);
      }
      CHECK(lowest == Approx(1).margin(1e-9));
      CHECK(highest == Approx(1).margin(1e-9));
      // The cage keeps its distance: no point is closer than the margin to a face plane (up to the 1e-9
      // snap).
      const double diag = diagonal(P);
      double nearest = 1e300;
      for (Eigen::Index f = 0; f < F.rows(); ++f) {
        const Vec3 a = C.row(F(f, 0)), b = C.row(F(f, 1)), c = C.row(F(f, 2));
        const Vec3 n = (b - a).cross(c - a).normalized();
        for (Eigen::Index i = 0; i < P.rows(); ++i) nearest = std::min(nearest, n.dot(a - Vec3(P.row(i))));
      }
      CHECK(nearest >= 0.05 * diag * (1 - 1e-6));
      if (sub == 0) CHECK(F.rows() <= 2 * 26 * 6);
    }
  }
  Positions C;
  Faces F;
  CHECK_THROWS_AS(offset_kdop_cage(Positions(0, 3), 0.05, 1, C, F), InvalidInput);
  CHECK_THROWS_AS(offset_kdop_cage(Positions::Ones(4, 3), 0.05, 1, C, F), InvalidInput);
  CHECK_THROWS_AS(offset_kdop_cage(box, 0.0, 1, C, F), InvalidInput);
}

// ---------------------------------------------------------------------------------------------------
// The deformer

std::vector<CageOptions> both_kinds() {
  CageOptions mvc, harmonic;
  harmonic.coordinates = CageCoordinates::Harmonic;
  harmonic.harmonic_resolution = 32;
  return {mvc, harmonic};
}

TEST_CASE("cage deformer: an affine motion of every constraint moves every point by it", "[cage]") {
  const Scene& s = test::bent_bar();
  const double diag = diagonal(s.P);
  std::vector<int> codes = s.region.codes();
  for (int& c : codes)
    if (c != Region::kFree) c = Region::kFirstHandle;
  const Region one = Region::from_codes(codes);
  for (const CageOptions& options : both_kinds()) {
    CageDeformer d(options);
    INFO(d.name());
    d.prepare(s.P, s.F, one);
    CHECK(d.prepare_warnings().empty());
    CHECK(test::max_row_distance(d.deform({test::general_affine()}), test::transformed(test::general_affine(), s.P)) <= 1e-8 * diag);
    CHECK(d.frame_report().constraint_error <= 1e-8 * diag);
  }
}

TEST_CASE("cage deformer: the frame report states the constraint residual it leaves", "[cage]") {
  const Scene& s = test::bent_bar();
  for (const CageOptions& options : both_kinds()) {
    CageDeformer d(options);
    INFO(d.name());
    CHECK_FALSE(d.traits().exact_constraints);
    d.prepare(s.P, s.F, s.region);
    const Positions out = d.deform(s.transforms);
    const double measured = test::constraint_error(s.P, out, s.region, s.transforms);
    CHECK(measured > 0);
    CHECK(d.frame_report().constraint_error == Approx(measured).epsilon(1e-9));
  }
}

TEST_CASE("cage deformer: editing the cage vertices, translating the whole cage translates everything",
          "[cage]") {
  const Scene& s = test::bent_bar();
  const double diag = diagonal(s.P);
  for (const CageOptions& options : both_kinds()) {
    CageDeformer d(options);
    INFO(d.name());
    d.prepare(s.P, s.F, s.region);
    const Positions C = d.control_points();
    CHECK(C.rows() == d.cage_positions().rows());
    CHECK(C.rows() == d.num_coefficients());
    const Vec3 t(0.1, -0.25, 0.4);
    Eigen::MatrixX3d moves = t.transpose().replicate(C.rows(), 1);
    Positions out;
    d.deform_controls(moves, out);
    CHECK(test::max_row_distance(out, s.P.rowwise() + t.transpose()) <= 1e-10 * diag);
    // Moving one cage vertex moves the points near it most, and the map is that of evaluate().
    moves.setZero();
    moves(0, 2) = 0.2;
    d.deform_controls(moves, out);
    Positions again;
    d.evaluate(s.P, again);
    CHECK(test::max_row_distance(out, again) <= 1e-12 * diag);
  }
}

TEST_CASE("cage deformer: a user cage is checked, flipped when inward and warns about points outside it",
          "[cage]") {
  const Scene& s = test::bent_bar();
  const double diag = diagonal(s.P);
  Positions sphere;
  Faces F;
  test::icosphere(2, sphere, F);
  const Vec3 centre = 0.5 * (s.P.colwise().minCoeff() + s.P.colwise().maxCoeff()).transpose();
  CageOptions options;
  options.cage_P = (sphere * 0.8 * diag).rowwise() + centre.transpose();  // radius 0.8 diag: encloses the bar
  options.cage_F = F;
  options.cage_F.col(1).swap(options.cage_F.col(2));  // inward: flipped by prepare
  {
    CageDeformer d(options);
    d.prepare(s.P, s.F, s.region);
    CHECK(d.prepare_warnings().empty());
    CHECK(d.cage_positions().rows() == sphere.rows());
    Positions out;
    d.deform_controls(Eigen::MatrixX3d::Constant(sphere.rows(), 3, 0.3), out);
    CHECK(test::max_row_distance(out, s.P.array() + 0.3) <= 1e-10 * diag);
  }
  {
    CageOptions small = options;
    small.cage_P = (sphere * 0.3 * diag).rowwise() + centre.transpose();  // the bar's ends stick out
    CageDeformer d(small);
    d.prepare(s.P, s.F, s.region);
    REQUIRE(d.prepare_warnings().size() == 1);
    CHECK(d.prepare_warnings()[0].find("points lie outside the cage") != std::string::npos);
  }
  // An open cage (a face removed) and a non-manifold one (a face repeated) are refused.
  CageOptions open = options;
  open.cage_F = options.cage_F.topRows(options.cage_F.rows() - 1);
  CHECK_THROWS_AS(CageDeformer(open).prepare(s.P, s.F, s.region), InvalidInput);
  try {
    CageDeformer(open).prepare(s.P, s.F, s.region);
  } catch (const InvalidInput& e) {
    CHECK(std::string(e.what()).find("not closed") != std::string::npos);
  }
  CageOptions doubled = options;
  doubled.cage_F.conservativeResize(options.cage_F.rows() + 1, 3);
  doubled.cage_F.row(options.cage_F.rows()) = options.cage_F.row(0);
  CHECK_THROWS_AS(CageDeformer(doubled).prepare(s.P, s.F, s.region), InvalidInput);
  CageOptions half = options;
  half.cage_F.resize(0, 3);
  CHECK_THROWS_AS(CageDeformer(half), InvalidInput);
}

}  // namespace
}  // namespace msd
