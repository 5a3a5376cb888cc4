// Deformation transfer (detail/deformation_transfer.h): needle and degenerate triangles treated by
// cotan_laplacian()'s rule, results independent of where the mesh sits and of its scale, and results
// checked before they are returned.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/scenes.h"
#include "msdeform/detail/deformation_transfer.h"
#include "test_util.h"

using namespace msd;

namespace {

constexpr double kPi = 3.14159265358979323846;

// The input: a flat 4 × 2 strip of quads near (1000, 2000, 500), 0.7 long, where one quad is
// split at vertex 8, which sits on the diagonal 1–6 up to the rounding of the coordinates. Triangle
// (1, 6, 8) has twice its area 1.3e-14 for edges of 0.47, cotangents ~1e13: within the rounding of
// coordinates near 2000 (4 ε · 2000 · 0.47 = 8e-13), so degenerate, as the same triangle at the origin.
// Labels (.sel): 0 fixed, 1 free, 2 handle.
struct Needle {
  Positions P;
  Faces F;
  std::vector<int> labels = {0, 1, 1, 2, 0, 1, 1, 2, 1};
  Needle() {
    P.resize(9, 3);
    P << 1000, 2000, 500,                                            //
        1000.232395318116, 2000.0412710658554, 499.76462747324285,   //
        1000.464790636232, 2000.0825421317109, 499.52925494648576,   //
        1000.697185954348, 2000.1238131975663, 499.2938824197286,    //
        999.9863312423164, 2000.3267939041712, 500.04380535652194,   //
        1000.2187265604324, 2000.3680649700266, 499.80843282976485,  //
        1000.4511218785484, 2000.409336035882, 499.5730603030077,    //
        1000.6835171966644, 2000.4506071017372, 499.33768777625056,  //
        1000.3417585983323, 2000.2253035508688, 499.66884388812525;
    F.resize(8, 3);
    F << 0, 1, 5, 0, 5, 4, 1, 2, 6, 2, 3, 7, 2, 7, 6, 1, 8, 5, 8, 6, 5, 1, 6, 8;
  }
  std::vector<int> anchors() const {
    std::vector<int> out;
    for (int v = 0; v < static_cast<int>(labels.size()); ++v)
      if (labels[v] != 1) out.push_back(v);
    return out;
  }
  // Position along the strip: 0 at the fixed end (vertex 0), 1 at the handle end (vertex 3).
  double along(const Positions& X, int v) const {
    const Vec3 axis = X.row(3) - X.row(0);
    return (X.row(v) - X.row(0)).dot(axis.transpose()) / axis.squaredNorm();
  }
};

// A base deformation like the shell's for the edit: the handle end raised by `lift` along z,
// the fixed end kept, smoothstep in between (`affine` = false) or linear in the position along the strip
// (`affine` = true: an affine map, which deformation transfer reproduces exactly).
Positions lift_strip(const Needle& n, const Positions& X, double lift, bool affine) {
  Positions out = X;
  for (int v = 0; v < X.rows(); ++v) {
    const double u = n.along(X, v), t = std::clamp(u, 0.0, 1.0);
    out(v, 2) += lift * (affine ? u : t * t * (3 - 2 * t));
  }
  return out;
}

// x → a R x + t.
struct Similarity {
  double scale;
  Mat3 R;
  Vec3 offset;
  Positions operator()(const Positions& P) const {
    return ((scale * P) * R.transpose()).rowwise() + offset.transpose();
  }
};

std::vector<Similarity> similarities() {
  const Mat3 I = Mat3::Identity();
  const Mat3 R = Eigen::AngleAxisd(0.9, Vec3(0.3, -1, 0.5).normalized()).toRotationMatrix();
  return {{1, I, Vec3(-1000, -2000, -500)},  // the needle strip moved next to the origin
          {1, I, Vec3(3e4, -2e4, 1e4)},     {1e-3, I, Vec3::Zero()},        {1e4, I, Vec3::Zero()},
          {1e-3, R, Vec3(0.2, 5, -3)},      {1e4, R, Vec3(-4e7, 1e7, 2e7)}, {1, R, Vec3(1e4, 1e4, -1e4)}};
}

// S' of transfer(S, B, anchors) for the deformed base B_deformed.
Positions transfer(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb,
                   const std::vector<int>& anchors, const Positions& B_deformed,
                   DeformationTransfer::Report* report = nullptr) {
  DeformationTransfer dt;
  dt.set_anchor_vertices(anchors);
  dt.encode(S, Fs, B, Fb);
  Positions out;
  dt.reconstruct(B_deformed, out);
  if (report) *report = dt.report();
  return out;
}

}  // namespace

TEST_CASE("transfer: the issue's needle strip far from the origin follows a 0.3 lift",
          "[detail][transfer][needle]") {
  const Needle n;
  const double diagonal = bounding_box_diagonal(n.P);
  const std::vector<int> anchors = n.anchors();

  // B' = B gives back S (G = identity): the needle's own frame would turn the rounding of B' at ~2000
  // into gradients of order one.
  Positions out = transfer(n.P, n.F, n.P, n.F, anchors, n.P);
  CHECK(test::max_row_distance(out, n.P) <= 1e-9 * diagonal);

  // An affine lift of the base: S' is S under the same map, the free vertices rise by 0.3 u (0 < u < 1).
  const Positions affine = lift_strip(n, n.P, 0.3, true);
  out = transfer(n.P, n.F, n.P, n.F, anchors, affine);
  for (int v = 0; v < 9; ++v) {
    if (n.labels[v] != 1) continue;
    INFO("free vertex " << v << " moved by " << (out.row(v) - n.P.row(v)) << ", expected a rise of "
                        << 0.3 * n.along(n.P, v));
    CHECK((out.row(v) - n.P.row(v)).norm() <= 0.3);
  }
  CHECK(test::max_row_distance(out, affine) <= 1e-9 * diagonal);

  // The shell-like (smoothstep) lift: every vertex moves by at most the handle's 0.3, and mostly up.
  const Positions smooth = lift_strip(n, n.P, 0.3, false);
  out = transfer(n.P, n.F, n.P, n.F, anchors, smooth);
  for (int v = 0; v < 9; ++v) {
    INFO("vertex " << v << " moved by " << (out.row(v) - n.P.row(v)));
    CHECK((out.row(v) - n.P.row(v)).norm() <= 0.3 + 1e-9);
    CHECK(out(v, 2) - n.P(v, 2) >= -0.01);
  }
}

TEST_CASE("transfer: needle and degenerate triangles follow cotan_laplacian's rule, counted",
          "[detail][transfer][needle]") {
  const Needle n;
  DeformationTransfer dt;
  dt.set_anchor_vertices(n.anchors());
  dt.encode(n.P, n.F, n.P, n.F);
  const LaplaceOperator L = cotan_laplacian(n.P, n.F);
  const auto& r = dt.report();
  // (1, 6, 8) within the coordinates' rounding: left out (it was clamped as a needle, all three angles
  // beyond the clamp, before the rounding counted).
  CHECK(L.degenerate_faces == 1);
  CHECK(L.clamped_cotangents == 0);
  CHECK(r.degenerate_faces == L.degenerate_faces);
  CHECK(r.clamped_cotangents == L.clamped_cotangents);
  CHECK(r.needle_base_faces == 0);
  CHECK(r.degenerate_base_faces == 1);  // B = S: the same triangle has no frame and borrows a neighbour's
  CHECK(triangle_cotangents(n.P.row(1), n.P.row(6), n.P.row(8)).degenerate);

  // Vertex 8 put exactly on the diagonal (next to the origin, where the midpoint is exact): the triangle is
  // degenerate for both, left out of S's system and without a frame in B.
  Positions exact = n.P.rowwise() - n.P.row(0);
  exact.row(1) << 1, 0, 0;
  exact.row(6) << 3, 2, 0;
  exact.row(8) << 2, 1, 0;
  const LaplaceOperator Le = cotan_laplacian(exact, n.F);
  REQUIRE(Le.degenerate_faces == 1);
  DeformationTransfer de;
  de.encode(exact, n.F, exact, n.F);
  CHECK(de.report().degenerate_faces == 1);
  CHECK(de.report().clamped_cotangents == Le.clamped_cotangents);
  CHECK(de.report().degenerate_base_faces == 1);
  CHECK(de.report().needle_base_faces == 0);
  Positions out;
  de.reconstruct(exact, out);
  CHECK(test::max_row_distance(out, exact) <= 1e-12 * bounding_box_diagonal(exact));
}

TEST_CASE("transfer: translating, rotating and scaling the input moves the result the same way",
          "[detail][transfer][invariance]") {
  SECTION("the needle strip") {
    const Needle n;
    const Positions B_deformed = lift_strip(n, n.P, 0.3, false);
    DeformationTransfer::Report reference_report;
    const Positions reference = transfer(n.P, n.F, n.P, n.F, n.anchors(), B_deformed, &reference_report);
    for (const Similarity& T : similarities()) {
      const Positions S = T(n.P);
      DeformationTransfer::Report report;
      const Positions out = transfer(S, n.F, S, n.F, n.anchors(), T(B_deformed), &report);
      const double error = test::max_row_distance(out, T(reference)) / bounding_box_diagonal(S);
      INFO("scale " << T.scale << ", offset " << T.offset.transpose() << ": relative error " << error
                    << "; needle base faces " << report.needle_base_faces << ", degenerate base faces "
                    << report.degenerate_base_faces << ", S: degenerate " << report.degenerate_faces
                    << ", clamped cotangents " << report.clamped_cotangents);
      CHECK(error <= 1e-9);
    }
  }
  SECTION("the bumpy patch under a 120 degree bend") {
    SceneOptions o;
    o.resolution = 2000;
    const Scene s = make_surface(SceneShape::Plane, o);
    const test::ArcBend bend{0.2, 0.6 / (120 * kPi / 180), 120 * kPi / 180};
    const Positions B_deformed = bend(s.smooth);
    const std::vector<int> anchors = s.region.constrained_vertices();
    const Positions reference = transfer(s.P, s.F, s.smooth, s.F, anchors, B_deformed);
    REQUIRE(test::max_row_distance(reference, bend(s.P)) <= 0.25 * s.bump_height);  // a sensible result
    for (const Similarity& T : similarities()) {
      const Positions out = transfer(T(s.P), s.F, T(s.smooth), s.F, anchors, T(B_deformed));
      const double error = test::max_row_distance(out, T(reference)) / bounding_box_diagonal(T(s.P));
      INFO("scale " << T.scale << ", offset " << T.offset.transpose() << ": relative error " << error);
      CHECK(error <= 1e-9);
    }
  }
}

TEST_CASE("transfer: a result that blew up is reported, not returned", "[detail][transfer][bad-input]") {
  // S: a regular 6 × 6 grid in the plane z = 0. B: the same grid with vertex c moved to within 2e-5 of a
  // grid spacing of the diagonal a–d of its cell, so the base triangle (a, d, c) is thin but its largest
  // cotangent (~5e4) is still inside cotan_laplacian's bound: it keeps its own frame.
  const int n = 6;
  Positions S, B;
  Faces F;
  std::vector<bool> interior;
  test::jittered_grid(n, 0, S, F, interior);
  // The grid has faces (a, b, d) and (a, d, c) per cell; take cell (2, 2).
  const int a = 2 * (n + 1) + 2, c = a + n + 1, d = c + 1;
  B = S;
  const Vec3 mid = (S.row(a) + S.row(d)).transpose() / 2, across(-1, 1, 0);
  B.row(c) = (mid + 2e-5 / n * across.normalized()).transpose();
  const TriangleCotangents shape = triangle_cotangents(B.row(a), B.row(d), B.row(c));
  REQUIRE_FALSE(shape.degenerate);
  REQUIRE(shape.needle_corners == 0);
  REQUIRE(std::max({shape.cot[0], shape.cot[1]}) > 1e4);

  std::vector<int> anchors;
  for (int v = 0; v < S.rows(); ++v)
    if (!interior[v]) anchors.push_back(v);
  DeformationTransfer dt;
  dt.set_anchor_vertices(anchors);
  dt.encode(S, F, B, F);
  CHECK(dt.report().needle_base_faces == 0);
  Positions out;
  dt.reconstruct(B, out);
  CHECK(test::max_row_distance(out, S) <= 1e-9);

  // B' lifts the thin base triangle's apex by a tenth of a grid spacing: its gradient maps the
  // direction across the diagonal to a vector ~5e3 long, and S's well-shaped triangle there with it.
  Positions lifted = B;
  lifted(c, 2) += 0.1 / n;
  try {
    dt.reconstruct(lifted, out);
    FAIL("reconstruct returned a result " << test::max_row_distance(out, lifted) << " away from B'");
  } catch (const SolverError& e) {
    INFO(e.what());
    CHECK_THAT(e.what(), Catch::Matchers::Contains("vertex " + std::to_string(e.index())) &&
                             Catch::Matchers::Contains("outside the bounding box"));
    CHECK(e.index() >= 0);
  }

  // A base vertex so far out (finite, but near DBL_MAX) that S' overflows: reported with its vertex.
  Positions far = B;
  far(c, 2) = 1e306;
  try {
    dt.reconstruct(far, out);
    FAIL("reconstruct returned a result");
  } catch (const SolverError& e) {
    INFO(e.what());
    CHECK_THAT(e.what(), Catch::Matchers::Contains("vertex " + std::to_string(e.index())) &&
                             Catch::Matchers::Contains("not finite"));
  }

  // A good frame afterwards still works (the check leaves the object usable).
  dt.reconstruct(test::rigid_motion(B, Mat3::Identity(), Vec3(0, 0, 1)), out);
  CHECK(test::max_row_distance(out, test::rigid_motion(S, Mat3::Identity(), Vec3(0, 0, 1))) <= 1e-9);
}
