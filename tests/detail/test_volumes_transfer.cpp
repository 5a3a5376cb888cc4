#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "msdeform/core/errors.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/subdivision.h"
#include "msdeform/detail/deformation_transfer.h"
#include "msdeform/detail/displacement_volumes.h"
#include "msdeform/detail/encodings.h"
#include "msdeform/detail/normal_displacements.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

constexpr double kPi = 3.14159265358979323846;

Mat3 some_rotation() { return Eigen::AngleAxisd(1.3, Vec3(-0.4, 1, 0.6).normalized()).toRotationMatrix(); }

using test::ArcBend;

ArcBend bend120() { return {0.2, 0.6 / (120 * kPi / 180), 120 * kPi / 180}; }

// Triangles of X whose normal points against the bent base's normal below the triangle's original
// centroid (x of the undeformed S): inverted faces, a cheap proxy of local self-intersections.
int inverted_faces(const Positions& X, const Faces& F, const Positions& S, const ArcBend& bend) {
  int count = 0;
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    const Vec3 a = X.row(F(t, 0)), b = X.row(F(t, 1)), c = X.row(F(t, 2));
    const double x = (S(F(t, 0), 0) + S(F(t, 1), 0) + S(F(t, 2), 0)) / 3;
    if (!((b - a).cross(c - a).dot(bend.normal(x)) > 0)) ++count;
  }
  return count;
}

// The flat base one Loop level coarser than S (same plane, other connectivity and vertex count).
void coarser_flat_base(const Scene& s, Positions& B, Faces& Fb) {
  const LoopRefinement r =
      loop_refine(s.coarse_F, static_cast<int>(s.coarse_P.rows()), s.refinement.levels - 1);
  B = r.linear * s.coarse_P;
  Fb = r.faces;
}

// The named encoding (encoding_names()) of S over its smooth base for scene s, anchored at the region's
// constrained vertices, and told that the caller places them when `placed`.
std::unique_ptr<DetailEncoding> encoded(const std::string& name, const Scene& s, bool placed = false) {
  EncodingOptions options;
  options.kind = encoding_kind(name);
  std::unique_ptr<DetailEncoding> e = make_encoding(options);
  e->set_anchor_vertices(s.region.constrained_vertices());
  if (placed) e->set_placed_vertices(s.region.constrained_vertices());
  e->encode(s.P, s.F, s.smooth, s.F);
  return e;
}

}  // namespace

TEST_CASE("prism_volume: closed form of the blended prism", "[detail][volumes]") {
  const Vec3 a0(0.1, 0.2, 0.3), a1(1.2, 0.1, 0.2), a2(0.3, 0.9, 0.1);
  const Vec3 n = (a1 - a0).cross(a2 - a0);
  const double area = n.norm() / 2;
  const Vec3 u = n.normalized();
  // Right prism, sheared prism: A h.
  CHECK(prism_volume(a0, a1, a2, a0 + 0.7 * u, a1 + 0.7 * u, a2 + 0.7 * u) ==
        Approx(area * 0.7).epsilon(1e-14));
  const Vec3 shift = 0.7 * u + Vec3(0.3, -0.2, 0.1) - Vec3(0.3, -0.2, 0.1).dot(u) * u;
  CHECK(prism_volume(a0, a1, a2, a0 + shift, a1 + shift, a2 + shift) == Approx(area * 0.7).epsilon(1e-14));
  // Tetrahedron: A h / 3; flipped side: negative.
  const Vec3 apex = (a0 + a1 + a2) / 3 + 0.6 * u;
  CHECK(prism_volume(a0, a1, a2, apex, apex, apex) == Approx(area * 0.6 / 3).epsilon(1e-14));
  CHECK(prism_volume(a0, a1, a2, a0 - 0.5 * u, a1 - 0.5 * u, a2 - 0.5 * u) ==
        Approx(-area * 0.5).epsilon(1e-14));
  // Invariant under cyclic relabelling and rigid motions, for a general (twisted) top.
  const Vec3 c0 = a0 + Vec3(0.1, 0.3, 0.5), c1 = a1 + Vec3(-0.2, 0.1, 0.8), c2 = a2 + Vec3(0.05, -0.1, 0.4);
  const double v = prism_volume(a0, a1, a2, c0, c1, c2);
  CHECK(prism_volume(a1, a2, a0, c1, c2, c0) == Approx(v).epsilon(1e-13));
  const Mat3 R = some_rotation();
  const Vec3 t(3, -1, 2);
  auto T = [&](const Vec3& p) -> Vec3 { return R * p + t; };
  CHECK(prism_volume(T(a0), T(a1), T(a2), T(c0), T(c1), T(c2)) == Approx(v).epsilon(1e-13));
  // Prisms over two triangles sharing an edge add up to the prism over their union (the shared side wall
  // is the same bilinear patch): split (a0, a1, a2) at the midpoint m of a1a2 with the top split likewise.
  const Vec3 m = (a1 + a2) / 2, cm = (c1 + c2) / 2;
  CHECK(prism_volume(a0, a1, m, c0, c1, cm) + prism_volume(a0, m, a2, c0, cm, c2) ==
        Approx(v).epsilon(1e-13));
}

TEST_CASE("volumes: B' = B and rigid motions of the base return S", "[detail][volumes]") {
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Plane, o);
  const double diagonal = bounding_box_diagonal(s.P);
  SECTION("same connectivity") {
    DisplacementVolumes dv;
    CHECK(dv.name() == "volumes");
    dv.encode(s.P, s.F, s.smooth, s.F);
    CHECK(dv.report().skipped_prisms == 0);
    Positions out;
    dv.reconstruct(s.smooth, out);
    CHECK(test::max_row_distance(out, s.P) <= 1e-9 * diagonal);
    CHECK(dv.report().iterations == 0);
    CHECK(dv.report().converged);
    dv.reconstruct(test::rigid_motion(s.smooth, some_rotation(), Vec3(0.4, -2, 1)), out);
    INFO("rigid: max relative volume error " << dv.report().max_relative_error);
    CHECK(test::max_row_distance(out, test::rigid_motion(s.P, some_rotation(), Vec3(0.4, -2, 1))) <= 1e-9 * diagonal);
  }
  SECTION("base with other connectivity (one Loop level coarser)") {
    Positions B;
    Faces Fb;
    coarser_flat_base(s, B, Fb);
    DisplacementVolumes dv;
    dv.encode(s.P, s.F, B, Fb);
    Positions out;
    dv.reconstruct(B, out);
    CHECK(test::max_row_distance(out, s.P) <= 1e-9 * diagonal);
    dv.reconstruct(test::rigid_motion(B, some_rotation(), Vec3(1, 2, 3)), out);
    CHECK(test::max_row_distance(out, test::rigid_motion(s.P, some_rotation(), Vec3(1, 2, 3))) <= 1e-9 * diagonal);
  }
}

TEST_CASE("volumes: an affine stretch of a flat base keeps every prism volume", "[detail][volumes]") {
  // Over a flat base with parallel normals a prism's volume is its base area times its mean height, so
  // stretching the base by det (in its plane) is matched exactly by h' = h / det for every prism (and
  // every dual cell) at once.
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Plane, o);
  Mat3 A = Mat3::Identity();
  A(0, 0) = 1.5;
  A(0, 1) = 0.3;
  A(1, 1) = 0.9;
  const double det = A.determinant();
  const Positions B_stretched = s.smooth * A.transpose();
  SECTION("default options: within the volume window (det 1.35 < 1.5), every volume to 1e-6") {
    DisplacementVolumes dv;
    dv.encode(s.P, s.F, s.smooth, s.F);
    Positions out;
    dv.reconstruct(B_stretched, out);
    const auto& r = dv.report();
    INFO("iterations " << r.iterations << ", max relative error " << r.max_relative_error << " (start "
                       << r.initial_max_relative_error << ")");
    CHECK(r.converged);
    CHECK(r.limited_volumes == 0);
    CHECK(r.regularised_heights == 0);
    CHECK(r.max_relative_error <= 1e-6);
    CHECK((dv.heights() - dv.normal_displacements().heights() / det).cwiseAbs().maxCoeff() <=
          1e-6 * s.bump_height);
  }
  SECTION("tight tolerance: every volume within 1e-10, prisms too") {
    DisplacementVolumeOptions options;
    options.volume_tolerance = 1e-10;
    DisplacementVolumes dv(options);
    dv.encode(s.P, s.F, s.smooth, s.F);
    Positions out;
    dv.reconstruct(B_stretched, out);
    const auto& r = dv.report();
    INFO("iterations " << r.iterations << ", max relative error " << r.max_relative_error);
    CHECK(r.converged);
    CHECK(r.volumes_within_tolerance);
    CHECK(r.max_relative_error <= 1e-10);
    CHECK(r.iterations <= 30);  // l1-Jacobi contracts by about 0.41 per sweep on a flat base
    double prism_error = 0;
    for (Eigen::Index t = 0; t < s.F.rows(); ++t) {
      const int a = s.F(t, 0), b = s.F(t, 1), c = s.F(t, 2);
      const Positions& X = B_stretched;
      const double v = prism_volume(X.row(a), X.row(b), X.row(c), out.row(a), out.row(b), out.row(c));
      prism_error = std::max(prism_error, std::abs(v - dv.volumes()[t]));
    }
    CHECK(prism_error <= 1e-9 * dv.volumes().cwiseAbs().maxCoeff());
  }
}

TEST_CASE("volumes: a 120 degree bend keeps the volumes around each vertex", "[detail][volumes]") {
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Plane, o);
  const Positions B_bent = bend120()(s.smooth);
  DisplacementVolumes dv;
  dv.encode(s.P, s.F, s.smooth, s.F);
  Positions out, out_normal, feet;
  dv.reconstruct(B_bent, out);
  NormalDisplacements nd;
  nd.encode(s.P, s.F, s.smooth, s.F);
  nd.reconstruct(B_bent, out_normal);
  nd.base_points(B_bent, feet);

  // Volume around each vertex: the sum of the prisms of its triangles, before and after.
  auto ring_volumes = [&](const Positions& bottom, const Positions& top) {
    Eigen::VectorXd ring = Eigen::VectorXd::Zero(s.P.rows());
    for (Eigen::Index t = 0; t < s.F.rows(); ++t) {
      const int a = s.F(t, 0), b = s.F(t, 1), c = s.F(t, 2);
      const double v =
          prism_volume(bottom.row(a), bottom.row(b), bottom.row(c), top.row(a), top.row(b), top.row(c));
      for (int k : {a, b, c}) ring[k] += v;
    }
    return ring;
  };
  const Eigen::VectorXd before = ring_volumes(s.smooth, s.P);
  const double scale = before.cwiseAbs().maxCoeff();
  const double ring_error = (ring_volumes(feet, out) - before).cwiseAbs().maxCoeff() / scale;
  const double ring_error_normal = (ring_volumes(feet, out_normal) - before).cwiseAbs().maxCoeff() / scale;

  const auto& r = dv.report();
  INFO("iterations " << r.iterations << ", converged " << r.converged << ", bounded heights "
                     << r.bounded_heights << ", regularised " << r.regularised_heights << "; per dual cell: max "
                     << r.max_relative_error << " rms " << r.rms_relative_error << " (start: max "
                     << r.initial_max_relative_error << " rms " << r.initial_rms_relative_error
                     << "); per vertex ring of prisms: " << ring_error << " (normal displacements: "
                     << ring_error_normal << "), " << r.seconds << " s");
  CHECK(out.allFinite());
  // One volume per vertex (its dual cell) and one height: a square system, solved to the tolerance.
  CHECK(r.converged);
  CHECK(r.max_relative_error <= 1e-6);
  CHECK(r.limited_volumes == 0);
  CHECK(r.regularised_heights == 0);
  // The whole prisms around each vertex (which reach into the neighbours' cells, so they are not what is
  // solved for) are kept about 9 times more closely than by plain normal displacements.
  CHECK(ring_error <= ring_error_normal / 5);
  CHECK(ring_error <= 0.01);
}

TEST_CASE("transfer: B' = B and rigid motions return S, same and other connectivity", "[detail][transfer]") {
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Plane, o);
  const double diagonal = bounding_box_diagonal(s.P);
  const Mat3 R = some_rotation();
  const Vec3 t(0.4, -2, 1);
  const Positions moved = test::rigid_motion(s.P, R, t);
  const std::vector<int> anchors = s.region.constrained_vertices();

  auto check_base = [&](const Positions& B, const Faces& Fb, const char* label) {
    INFO(label);
    DeformationTransfer dt;
    dt.set_anchor_vertices(anchors);
    dt.encode(s.P, s.F, B, Fb);
    CHECK(dt.report().identical_connectivity == (B.rows() == s.P.rows()));
    CHECK(dt.report().pinned_vertices.empty());
    CHECK(dt.report().degenerate_base_faces == 0);
    CHECK(dt.report().unreachable_faces == 0);
    // G_t = V V⁻¹ is the identity up to rounding whatever the correspondence, and the anchors sit at
    // their normal-displacement reconstruction (S itself: every base-point search converges here), so a
    // base with other connectivity is held to the same 1e-9.
    CHECK(dt.normal_displacements().report().fallback == 0);
    Positions out;
    dt.reconstruct(B, out);
    CHECK(test::max_row_distance(out, s.P) <= 1e-9 * diagonal);
    dt.reconstruct(test::rigid_motion(B, R, t), out);
    CHECK(test::max_row_distance(out, moved) <= 1e-9 * diagonal);
    double anchor_error = 0;
    for (int a : anchors) anchor_error = std::max(anchor_error, (out.row(a) - moved.row(a)).norm());
    CHECK(anchor_error <= 1e-9 * diagonal);

    // No anchors: vertex 0 is pinned to its normal-displacement reconstruction.
    DeformationTransfer free_dt;
    free_dt.encode(s.P, s.F, B, Fb);
    REQUIRE(free_dt.report().pinned_vertices == std::vector<int>{0});
    free_dt.reconstruct(test::rigid_motion(B, R, t), out);
    CHECK(test::max_row_distance(out, moved) <= 1e-9 * diagonal);
  };
  check_base(s.smooth, s.F, "same connectivity");
  Positions B;
  Faces Fb;
  coarser_flat_base(s, B, Fb);
  check_base(B, Fb, "one Loop level coarser base");
  std::vector<bool> interior;
  test::jittered_grid(41, 0.3, B, Fb, interior);
  check_base(B, Fb, "jittered 41 x 41 grid base with other diagonals");
}

TEST_CASE("transfer: 120 degree bend, same and other base connectivity", "[detail][transfer]") {
  SceneOptions o;
  o.resolution = 10000;
  const Scene s = make_surface(SceneShape::Plane, o);
  const ArcBend bend = bend120();
  const std::vector<int> anchors = s.region.constrained_vertices();
  const Positions exact = bend(s.P);  // the bumps bent with the plate: a reference, not the answer

  Positions B_coarse;
  Faces F_coarse;
  coarser_flat_base(s, B_coarse, F_coarse);
  std::vector<Positions> results;
  for (const auto& [B, Fb] :
       {std::pair<const Positions&, const Faces&>(s.smooth, s.F), {B_coarse, F_coarse}}) {
    const bool same = B.rows() == s.P.rows();
    DeformationTransfer dt;
    dt.set_anchor_vertices(anchors);
    dt.encode(s.P, s.F, B, Fb);
    const Positions B_bent = bend(B);
    Positions out, targets;
    dt.reconstruct(B_bent, out);
    NormalDisplacements nd;
    nd.encode(s.P, s.F, B, Fb);
    nd.reconstruct(B_bent, targets);
    double anchor_error = 0, anchor_vs_exact = 0;
    for (int a : anchors) {
      anchor_error = std::max(anchor_error, (out.row(a) - targets.row(a)).norm());
      anchor_vs_exact = std::max(anchor_vs_exact, (out.row(a) - exact.row(a)).norm());
    }
    const double deviation = test::max_row_distance(out, exact);
    INFO((same ? "same" : "other") << " connectivity: anchor error " << anchor_error
                                   << " (vs the analytic bend " << anchor_vs_exact
                                   << "), max distance to the bent plate " << deviation << ", "
                                   << dt.report().seconds << " s");
    REQUIRE(out.allFinite());
    CHECK(anchor_error <= 1e-9);
    // The coarser base is a polygon inscribed in the arc: its sagitta (R (1 − cos(Δφ/2)), Δφ = 0.02 / R
    // for 0.02-long coarse edges) is ~2e-4; the anchors follow it.
    CHECK(anchor_vs_exact <= (same ? 1e-9 : 1e-3));
    CHECK(inverted_faces(out, s.F, s.P, bend) == 0);
    CHECK(deviation <= 0.25 * s.bump_height);
    results.push_back(out);
  }
  // The two bases differ only in how finely they sample the same bend.
  const double between = test::max_row_distance(results[0], results[1]);
  INFO("same vs other connectivity: " << between);
  CHECK(between <= 0.1 * s.bump_height);
}

TEST_CASE("Fig. 9.10: a bend tighter than the bumps inverts normal displacements, not volumes or transfer",
          "[detail][volumes][transfer]") {
  SceneOptions o;
  o.resolution = 40000;
  const Scene s = make_surface(SceneShape::Plane, o);
  // Radius of curvature half the bump height, bumps on the concave side; the arc is centred on a row of
  // bumps (centres at x = 0.45).
  const double R = 0.5 * s.bump_height, theta = 120 * kPi / 180;
  const ArcBend bend{0.45 - R * theta / 2, R, theta};
  const Positions B_bent = bend(s.smooth);
  CHECK(inverted_faces(s.P, s.F, s.P, ArcBend{0, 1, 0}) == 0);

  NormalDisplacements nd;
  nd.encode(s.P, s.F, s.smooth, s.F);
  Positions out_normal;
  nd.reconstruct(B_bent, out_normal);

  DisplacementVolumes dv;
  dv.encode(s.P, s.F, s.smooth, s.F);
  Positions out_volumes;
  dv.reconstruct(B_bent, out_volumes);

  std::vector<int> anchors;
  for (int v = 0; v < s.P.rows(); ++v)
    if (s.smooth(v, 0) < bend.x0 - 0.05 || s.smooth(v, 0) > bend.x0 + R * theta + 0.05) anchors.push_back(v);
  DeformationTransfer dt;
  dt.set_anchor_vertices(anchors);
  dt.encode(s.P, s.F, s.smooth, s.F);
  Positions out_transfer;
  dt.reconstruct(B_bent, out_transfer);

  const int normal = inverted_faces(out_normal, s.F, s.P, bend);
  const int volumes = inverted_faces(out_volumes, s.F, s.P, bend);
  const int transfer = inverted_faces(out_transfer, s.F, s.P, bend);
  const auto& r = dv.report();
  INFO("inverted faces of " << s.F.rows() << ": normal " << normal << ", volumes " << volumes << ", transfer "
                            << transfer << "; volumes: iterations " << r.iterations << ", converged "
                            << r.converged << ", heights at the fold guard " << r.bounded_heights
                            << ", relative volume error max " << r.max_relative_error << " rms "
                            << r.rms_relative_error << " (normal: " << r.initial_max_relative_error << ", "
                            << r.initial_rms_relative_error << ")");
  CHECK(out_volumes.allFinite());
  CHECK(out_transfer.allFinite());
  CHECK(normal > 0);
  CHECK(volumes == 0);
  CHECK(transfer == 0);
  // Why the volumes are not kept here: on the concave side of a bend of radius R the shell between B'
  // and the focal line holds at most R/2 per unit area, less than the bumps' volume; the fold guard
  // holds those heights below the focal line instead of letting the surface fold over.
  CHECK(r.converged);
  CHECK(r.bounded_heights > 0);
  CHECK_FALSE(r.volumes_within_tolerance);

  // Without the guard the least-squares solve chases the unreachable volumes past the focal line.
  DisplacementVolumeOptions unguarded_options;
  unguarded_options.focal_fraction = std::numeric_limits<double>::infinity();
  unguarded_options.max_iterations = 10;
  DisplacementVolumes unguarded(unguarded_options);
  unguarded.encode(s.P, s.F, s.smooth, s.F);
  Positions out_unguarded;
  unguarded.reconstruct(B_bent, out_unguarded);
  const int unguarded_inverted = inverted_faces(out_unguarded, s.F, s.P, bend);
  INFO("without the fold guard: " << unguarded_inverted << " inverted faces");
  CHECK(out_unguarded.allFinite());
  CHECK(unguarded_inverted > 0);
}

TEST_CASE("volumes and transfer: degenerate prisms and base triangles stay finite",
          "[detail][volumes][transfer]") {
  SceneOptions o;
  o.resolution = 2000;
  const Scene s = make_surface(SceneShape::Plane, o);
  // Move one vertex of an interior triangle onto the midpoint of the opposite edge (in the plane): the
  // triangle's prism has a zero-area base, and for S = B a zero-area base triangle.
  int face = -1;
  for (int t = 0; t < s.F.rows() && face < 0; ++t) {
    const Vec3 c = (s.smooth.row(s.F(t, 0)) + s.smooth.row(s.F(t, 1)) + s.smooth.row(s.F(t, 2))) / 3;
    if (std::abs(c.x() - 0.5) < 0.02 && std::abs(c.y() - 0.5) < 0.02) face = t;
  }
  REQUIRE(face >= 0);
  Positions S = s.P, flat = s.smooth;
  const int moved = s.F(face, 2);
  const Vec3 mid = (flat.row(s.F(face, 0)) + flat.row(s.F(face, 1))) / 2;
  flat.row(moved) = mid.transpose();
  S.row(moved) << mid.x(), mid.y(), S(moved, 2);
  const Positions bent = bend120()(s.smooth);

  DisplacementVolumes dv;
  dv.encode(S, s.F, s.smooth, s.F);
  CHECK(dv.report().skipped_prisms >= 1);
  CHECK_FALSE(dv.active_prisms()[face]);
  Positions out;
  dv.reconstruct(bent, out);
  CHECK(out.allFinite());
  CHECK(std::isfinite(dv.report().max_relative_error));

  DeformationTransfer dt;
  dt.encode(flat, s.F, flat, s.F);  // S = B with a degenerate triangle
  CHECK(dt.report().degenerate_base_faces >= 1);
  dt.reconstruct(flat, out);
  CHECK(test::max_row_distance(out, flat) <= 1e-9);
  dt.reconstruct(bent, out);
  CHECK(out.allFinite());
}

TEST_CASE("volumes and transfer: bad use and bad input", "[detail][volumes][transfer][bad-input]") {
  Positions S, B;
  Faces Fs, Fb;
  test::icosphere(3, S, Fs);
  S *= 1.05;
  test::icosphere(2, B, Fb);
  Positions out;

  DisplacementVolumes dv;
  CHECK_THROWS_AS(dv.reconstruct(B, out), UsageError);
  Faces bad = Fs;
  bad(4, 2) = static_cast<int>(S.rows());
  CHECK_THROWS_WITH(dv.encode(S, bad, B, Fb), Contains("face 4") && Contains("out of range"));
  CHECK_FALSE(dv.encoded());
  dv.encode(S, Fs, B, Fb);
  CHECK(dv.encoded());
  CHECK_THROWS_AS(dv.reconstruct(S, out), UsageError);  // S is not the base: wrong size
  CHECK_THROWS_WITH(dv.reconstruct(Positions(B.topRows(7)), out), Contains("7 vertices"));
  Positions nan_b = B;
  nan_b(2, 1) = std::nan("");
  CHECK_THROWS_WITH(dv.reconstruct(nan_b, out), Contains("vertex 2"));
  DisplacementVolumeOptions negative;
  negative.regularization = -1;
  // Refused when made, before any mesh (fourth break test: only encode() refused it).
  CHECK_THROWS_WITH(DisplacementVolumes(negative),
                    Contains("DisplacementVolumeOptions::regularization must be finite and >= 0, got -1"));

  DeformationTransfer dt;
  CHECK_THROWS_AS(dt.reconstruct(B, out), UsageError);
  dt.set_anchor_vertices({0, static_cast<int>(S.rows())});
  CHECK_THROWS_WITH(dt.encode(S, Fs, B, Fb), Contains("anchor vertex " + std::to_string(S.rows())));
  CHECK_FALSE(dt.encoded());
  dt.set_anchor_vertices({0, 5, 5});  // repeats are harmless
  dt.encode(S, Fs, B, Fb);
  CHECK_THROWS_AS(dt.reconstruct(S, out), UsageError);
  CHECK_THROWS_WITH(dt.reconstruct(nan_b, out), Contains("vertex 2"));
  dt.reconstruct(B, out);
  CHECK(test::max_row_distance(out, S) <= 1e-9);
}

TEST_CASE("every encoding refuses to write S' over the B' it reads", "[detail][bad-input]") {
  SceneOptions o;
  o.resolution = 2000;
  const Scene s = make_surface(SceneShape::Plane, o);
  for (const std::string& name : encoding_names()) {
    const std::unique_ptr<DetailEncoding> e = encoded(name, s);
    Positions B = bend120()(s.smooth);
    const Positions before = B;
    INFO(name);
    CHECK_THROWS_WITH(e->reconstruct(B, B), Contains("out is the deformed base itself"));
    CHECK((B.array() == before.array()).all());  // untouched
    Positions out;
    e->reconstruct(B, out);
    CHECK(out.rows() == s.P.rows());
  }
}

TEST_CASE("every encoding throws rather than return a non-finite row of S' from a finite B'",
          "[detail][bad-input]") {
  // The multi-scale deformer relies on it (DetailEncoding::reconstruct) and does not scan S' again. Two
  // neighbouring base vertices near ±DBL_MAX: their edge overflows, and so would normals, frames and
  // gradients. Whatever an encoding does with them, it returns finite rows or throws.
  SceneOptions o;
  o.resolution = 2000;
  const Scene s = make_surface(SceneShape::Plane, o);
  Positions far = s.smooth;
  const int a = s.F(7, 0), b = s.F(7, 1);
  far(a, 0) = 1.7e308;
  far(b, 0) = -1.7e308;
  for (const std::string& name : encoding_names()) {
    for (const bool with_placed : {false, true}) {
      INFO(name << (with_placed ? ", fixed and handle vertices placed by the caller" : ""));
      const std::unique_ptr<DetailEncoding> e = encoded(name, s, with_placed);
      Positions out = Positions::Zero(s.P.rows(), 3);  // placed rows stay 0 (finite)
      bool threw = false;
      try {
        e->reconstruct(far, out);
      } catch (const Error& error) {
        threw = true;
        INFO(error.what());
        CHECK_THAT(error.what(), Contains("finite"));
      }
      if (!threw) CHECK(out.allFinite());
    }
  }
}

TEST_CASE("volumes and transfer: reconstruct reuses out", "[detail][volumes][transfer]") {
  SceneOptions o;
  o.resolution = 2000;
  const Scene s = make_surface(SceneShape::Plane, o);
  const Positions bent = bend120()(s.smooth);
  DisplacementVolumes dv;
  DeformationTransfer dt;
  dt.set_anchor_vertices(s.region.constrained_vertices());
  for (DetailEncoding* e : std::vector<DetailEncoding*>{&dv, &dt}) {
    e->encode(s.P, s.F, s.smooth, s.F);
    Positions out(s.P.rows(), 3);
    const double* data = out.data();
    e->reconstruct(bent, out);
    e->reconstruct(s.smooth, out);
    CHECK(out.data() == data);
    CHECK(test::max_row_distance(out, s.P) <= 1e-9 * bounding_box_diagonal(s.P));
  }
}

TEST_CASE("every encoding leaves the placed rows as the caller wrote them, and transfer solves from them",
          "[detail][volumes][transfer]") {
  // Displacement volumes and deformation transfer wrote every row, and transfer took its Dirichlet values
  // from its own normal displacements: the multi-scale deformer's placed handle vertices (T p) were not
  // where the solve had ended, a step at the region's border.
  SceneOptions o;
  o.resolution = 2000;
  const Scene s = make_surface(SceneShape::Plane, o);
  const Positions bent = bend120()(s.smooth);
  const std::vector<int>& placed = s.region.constrained_vertices();
  REQUIRE(!placed.empty());
  const double diagonal = bounding_box_diagonal(s.P);
  for (const std::string& name : encoding_names()) {
    INFO(name);
    const std::unique_ptr<DetailEncoding> e = encoded(name, s, true);
    Positions out = Positions::Zero(s.P.rows(), 3);
    for (int v : placed) out.row(v) = bent.row(v) + Eigen::RowVector3d(0.5, -0.25, 0.125);
    const Positions written = out;
    e->reconstruct(bent, out);
    double moved = 0;
    for (int v : placed) moved = std::max(moved, (out.row(v) - written.row(v)).norm());
    CHECK(moved == 0);
    if (name != "transfer") continue;
    // Every Dirichlet value moved by c: Q's rows sum to zero, so every solved vertex moves by c too.
    const Eigen::RowVector3d c(0.01, 0.02, -0.03);
    Positions shifted = out;
    for (int v : placed) shifted.row(v) += c;
    e->reconstruct(bent, shifted);
    CHECK(test::max_row_distance(shifted.rowwise() - c, out) <= 1e-9 * diagonal);
  }
  // A placed vertex that is not an anchor is held where the caller wrote it too.
  DeformationTransfer dt;
  dt.set_anchor_vertices(placed);
  std::vector<int> more = placed;
  REQUIRE(!s.region.free_vertices().empty());
  const int free_vertex = s.region.free_vertices()[s.region.free_vertices().size() / 2];
  more.push_back(free_vertex);
  dt.set_placed_vertices(more);
  dt.encode(s.P, s.F, s.smooth, s.F);
  Positions out = bent;
  out.row(free_vertex) += Eigen::RowVector3d(0, 0, 0.25);
  const Eigen::RowVector3d held = out.row(free_vertex);
  dt.reconstruct(bent, out);
  CHECK(out.row(free_vertex) == held);
  // With placed vertices, out must already have S's rows (the placed ones written).
  const std::unique_ptr<DetailEncoding> e = encoded("normal", s, true);
  Positions wrong(3, 3);
  CHECK_THROWS_AS(e->reconstruct(bent, wrong), UsageError);
}
