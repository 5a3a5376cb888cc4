#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

#include "msdeform/core/errors.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/scenes.h"
#include "msdeform/detail/displacement_vectors.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

namespace {

Mat3 some_rotation() { return Eigen::AngleAxisd(2.1, Vec3(0.3, 1, -0.7).normalized()).toRotationMatrix(); }

// Max over vertices of the deviation of (n, t1, t2) from a right-handed orthonormal frame.
double frame_defect(const Positions& N, const Positions& T1, const Positions& T2) {
  double worst = 0;
  for (Eigen::Index v = 0; v < N.rows(); ++v) {
    Mat3 M;
    M << N.row(v).transpose(), T1.row(v).transpose(), T2.row(v).transpose();  // columns n, t1, t2
    worst = std::max(worst, (M.transpose() * M - Mat3::Identity()).cwiseAbs().maxCoeff());
    worst = std::max(worst, std::abs(M.determinant() - 1));
  }
  return worst;
}

// A fan of six triangles around vertex 0 (normal +z), preceded by a zero-area face (0, 1, 2) whose edges
// from vertex 0 run along the normal: vertex 0's first two incident edges are parallel to n, and
// vertices 1, 2 touch only the zero-area face (no normal).
void fan_with_spike(Positions& P, Faces& F) {
  P.resize(9, 3);
  P.row(0) << 0, 0, 0;
  P.row(1) << 0, 0, 1;
  P.row(2) << 0, 0, 2;
  for (int k = 0; k < 6; ++k) P.row(3 + k) << std::cos(k * M_PI / 3), std::sin(k * M_PI / 3), 0;
  F.resize(7, 3);
  F.row(0) << 0, 1, 2;
  for (int k = 0; k < 6; ++k) F.row(1 + k) << 0, 3 + k, 3 + (k + 1) % 6;
}

Positions random_offsets(const Positions& B, double scale, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-scale, scale);
  Positions S = B;
  for (Eigen::Index i = 0; i < S.rows(); ++i) S.row(i) += Vec3(u(rng), u(rng), u(rng)).transpose();
  return S;
}

}  // namespace

TEST_CASE("displacement vectors: B' = B and rigid motions reproduce S", "[detail][vectors]") {
  SceneOptions o;
  o.resolution = 5000;
  for (SceneShape shape : {SceneShape::Plane, SceneShape::Bar}) {
    const Scene s = make_surface(shape, o);
    INFO(s.name);
    const double diag = bounding_box_diagonal(s.P);
    for (DisplacementFrame frame : {DisplacementFrame::Local, DisplacementFrame::Global}) {
      DisplacementVectors dv({frame});
      CHECK(dv.name() == "vectors");
      dv.encode(s.P, s.F, s.smooth, s.F);
      Positions out;
      dv.reconstruct(s.smooth, out);
      CHECK(test::max_row_distance(out, s.P) <= 1e-9 * diag);
      const Vec3 t(-0.4, 2.0, 0.7);
      dv.reconstruct(test::rigid_motion(s.smooth, Mat3::Identity(), t), out);
      CHECK(test::max_row_distance(out, test::rigid_motion(s.P, Mat3::Identity(), t)) <= 1e-9 * diag);
    }
    DisplacementVectors local;
    local.encode(s.P, s.F, s.smooth, s.F);
    Positions out;
    const Mat3 R = some_rotation();
    const Vec3 t(1.5, -0.2, 0.3);
    local.reconstruct(test::rigid_motion(s.smooth, R, t), out);
    CHECK(test::max_row_distance(out, test::rigid_motion(s.P, R, t)) <= 1e-9 * diag);
    // (9.8) on the flat base: the bumps are pure normal offsets, α = height, β = γ = 0.
    if (shape == SceneShape::Plane) {
      CHECK((local.coefficients().col(0) - s.heights).cwiseAbs().maxCoeff() <= 1e-15);
      CHECK(local.coefficients().rightCols(2).cwiseAbs().maxCoeff() <= 1e-15);
    }
  }
}

TEST_CASE("displacement vectors: Local details rotate with the base, Global ones do not (Fig. 9.8)",
          "[detail][vectors]") {
  SceneOptions o;
  o.resolution = 3000;
  const Scene s = make_surface(SceneShape::Plane, o);
  const Mat3 R = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();  // the plane stands up
  const Vec3 t(0, 0, 1);
  const Positions B_rotated = test::rigid_motion(s.smooth, R, t);
  DisplacementVectors local({DisplacementFrame::Local}), global({DisplacementFrame::Global});
  local.encode(s.P, s.F, s.smooth, s.F);
  global.encode(s.P, s.F, s.smooth, s.F);
  Positions out_local, out_global;
  local.reconstruct(B_rotated, out_local);
  global.reconstruct(B_rotated, out_global);
  CHECK(test::max_row_distance(out_local, test::rigid_motion(s.P, R, t)) <= 1e-12);
  // Global: every detail vector is the original world vector h = (0, 0, height), not rotated.
  CHECK(test::max_row_distance(out_global, B_rotated + (s.P - s.smooth)) <= 1e-15);
  // The two differ by |R h − h| = √2 · height at the bump tops.
  CHECK(test::max_row_distance(out_local, out_global) ==
        Approx(std::sqrt(2.0) * s.heights.maxCoeff()).epsilon(1e-12));
}

TEST_CASE("displacement vectors: frame normals are the area-weighted vertex normals", "[detail][vectors]") {
  // Thousands of faces: the face pass runs four faces at a time where the CPU has AVX2, the rest one by one.
  SceneOptions o;
  o.resolution = 3000;
  const Scene s = make_scene("bar-twist135", o);
  const Positions P = test::rigid_motion(s.P, some_rotation(), Vec3(40, -3, 7));
  Positions N, T1, T2;
  VertexFrames(s.F, static_cast<int>(P.rows())).compute(P, N, T1, T2);
  CHECK((N - vertex_normals(P, s.F)).cwiseAbs().maxCoeff() <= 1e-12);
  CHECK(frame_defect(N, T1, T2) <= 1e-13);
}

TEST_CASE("displacement vectors: frames on degenerate first edges, needles and isolated vertices",
          "[detail][vectors]") {
  SECTION("first incident edges parallel to the normal are skipped") {
    Positions P;
    Faces F;
    fan_with_spike(P, F);
    const VertexFrames frames(F, static_cast<int>(P.rows()));
    // Incident edges in face-list order: face 0 gives 1, 2; face 1 gives 3, 4; face 2 adds 5; ...
    CHECK(frames.edge_order(0) == std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8});
    CHECK(frames.edge_order(4) == std::vector<int>{0, 3, 5});
    Positions N, T1, T2;
    frames.compute(P, N, T1, T2);
    CHECK(frame_defect(N, T1, T2) <= 1e-14);
    CHECK((Vec3(N.row(0)) - Vec3::UnitZ()).norm() <= 1e-15);
    CHECK((Vec3(T1.row(0)) - Vec3::UnitX()).norm() <= 1e-15);  // the edge to vertex 3, the first usable one
    CHECK((Vec3(T2.row(0)) - Vec3::UnitY()).norm() <= 1e-15);
    // Vertices 1 and 2 only touch the zero-area face: no normal, world frame.
    for (int v : {1, 2}) {
      CHECK(Vec3(N.row(v)) == Vec3::UnitZ());
      CHECK(Vec3(T1.row(v)) == Vec3::UnitX());
      CHECK(Vec3(T2.row(v)) == Vec3::UnitY());
    }
    // The frame at vertex 0 still follows a rotation of the mesh (the same edge is chosen).
    const Mat3 R = some_rotation();
    frames.compute(test::rigid_motion(P, R, Vec3(1, 2, 3)), N, T1, T2);
    CHECK((Vec3(N.row(0)) - R * Vec3::UnitZ()).norm() <= 1e-14);
    CHECK((Vec3(T1.row(0)) - R * Vec3::UnitX()).norm() <= 1e-14);
    // Encode/reconstruct: exact for B' = B; rigid for the vertices with a geometric frame.
    const Positions S = random_offsets(P, 0.1, 5);
    DisplacementVectors dv;
    dv.encode(S, F, P, F);
    Positions out;
    dv.reconstruct(P, out);
    CHECK(test::max_row_distance(out, S) <= 1e-14);
    dv.reconstruct(test::rigid_motion(P, R, Vec3(1, 2, 3)), out);
    const Positions expected = test::rigid_motion(S, R, Vec3(1, 2, 3));
    for (int v : {0, 3, 4, 5, 6, 7, 8}) CHECK((out.row(v) - expected.row(v)).norm() <= 1e-14);
    // Vertices 1, 2 keep world-frame details: they translate with the base but do not rotate.
    for (int v : {1, 2})
      CHECK((out.row(v) - (test::rigid_motion(P, R, Vec3(1, 2, 3)).row(v) + (S.row(v) - P.row(v)))).norm() <=
            1e-14);
  }
  SECTION("a needle apex whose edges are all (nearly) parallel to the normal gets an orthogonal axis") {
    const double eps = 1e-8;  // tangential part of each edge: 1e-8 of its length, below the 1e-6 cut
    Positions P(7, 3);
    P.row(0) << 0, 0, 0;
    for (int k = 0; k < 6; ++k)
      P.row(1 + k) << eps * std::cos(k * M_PI / 3), eps * std::sin(k * M_PI / 3), -1;
    Faces F(6, 3);
    for (int k = 0; k < 6; ++k) F.row(k) << 0, 1 + k, 1 + (k + 1) % 6;
    const VertexFrames frames(F, 7);
    Positions N, T1, T2;
    frames.compute(P, N, T1, T2);
    CHECK(frame_defect(N, T1, T2) <= 1e-12);
    CHECK(N(0, 2) == Approx(1.0).margin(1e-6));  // the apex normal points up the needle
    // t1 is a world axis projected into the tangent plane: here x or y, the axes least aligned with n.
    CHECK(std::max(std::abs(T1(0, 0)), std::abs(T1(0, 1))) == Approx(1.0).margin(1e-6));
    const Positions S = random_offsets(P, 0.05, 9);
    DisplacementVectors dv;
    dv.encode(S, F, P, F);
    Positions out;
    dv.reconstruct(P, out);
    CHECK(test::max_row_distance(out, S) <= 1e-14);
  }
  SECTION("frames of a whole scene are orthonormal and right-handed") {
    SceneOptions o;
    o.resolution = 3000;
    const Scene s = make_surface(SceneShape::Bar, o);
    const VertexFrames frames(s.F, static_cast<int>(s.P.rows()));
    Positions N, T1, T2;
    frames.compute(s.P, N, T1, T2);
    CHECK(frame_defect(N, T1, T2) <= 1e-14);
    // t1 is the tangential projection of the first incident edge.
    for (int v = 0; v < s.P.rows(); v += 97) {
      const Vec3 e = Vec3(s.P.row(frames.edge_order(v).front())) - Vec3(s.P.row(v));
      const Vec3 n = N.row(v);
      CHECK((Vec3(T1.row(v)) - (e - e.dot(n) * n).normalized()).norm() <= 1e-14);
    }
  }
}

TEST_CASE("displacement vectors: bad use and mismatched connectivity", "[detail][vectors][bad-input]") {
  Positions P;
  Faces F;
  fan_with_spike(P, F);
  const Positions S = random_offsets(P, 0.1, 1);
  DisplacementVectors dv;
  Positions out;
  CHECK_THROWS_AS(dv.reconstruct(P, out), UsageError);
  CHECK_THROWS_WITH(dv.encode(Positions(S.topRows(8)), F, P, F), Contains("8 vertices") && Contains("9"));
  Faces other = F;
  other.row(3) << 0, 5, 4;
  CHECK_THROWS_WITH(dv.encode(S, other, P, F), Contains("face 3 differs"));
  CHECK_THROWS_AS(dv.encode(S, Faces(F.topRows(5)), P, F), InvalidInput);
  Faces bad = F;
  bad(2, 2) = 99;
  CHECK_THROWS_WITH(dv.encode(S, bad, P, bad), Contains("face 2") && Contains("out of range"));
  CHECK_FALSE(dv.encoded());
  dv.encode(S, F, P, F);
  CHECK(dv.encoded());
  CHECK_THROWS_AS(dv.reconstruct(Positions(P.topRows(4)), out), UsageError);
  Positions nan_b = P;
  nan_b(6, 1) = std::nan("");
  CHECK_THROWS_WITH(dv.reconstruct(nan_b, out), Contains("vertex 6"));
  DisplacementVectors global(DisplacementVectorOptions{DisplacementFrame::Global});
  global.encode(S, F, P, F);
  nan_b(6, 1) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(global.reconstruct(nan_b, out), Contains("vertex 6"));
  CHECK_THROWS_AS(VertexFrames(F, 9).compute(Positions(P.topRows(3)), out, out, out), UsageError);
}

TEST_CASE("displacement vectors: placed vertices are skipped, the others reconstructed bit for bit",
          "[detail][vectors]") {
  SceneOptions o;
  o.resolution = 2000;
  const Scene s = make_surface(SceneShape::Bar, o);
  // A bent base B': the other rows must not depend on which vertices are placed.
  Positions Bd = s.smooth;
  for (Eigen::Index i = 0; i < Bd.rows(); ++i) Bd(i, 1) += 0.2 * Bd(i, 0) * Bd(i, 0);
  std::vector<int> placed;
  std::vector<char> is_placed(s.P.rows(), 0);
  for (int v = 0; v < s.P.rows(); ++v)
    if (s.P(v, 0) > 0.5 * s.P.col(0).maxCoeff() || v % 5 == 0) placed.push_back(v), is_placed[v] = 1;
  REQUIRE(static_cast<Eigen::Index>(placed.size()) > s.P.rows() / 4);
  for (DisplacementFrame frame : {DisplacementFrame::Local, DisplacementFrame::Global}) {
    DisplacementVectors all({frame}), some({frame});
    all.encode(s.P, s.F, s.smooth, s.F);
    Positions expected;
    all.reconstruct(Bd, expected);
    some.set_placed_vertices(placed);
    some.encode(s.P, s.F, s.smooth, s.F);
    Positions out = Positions::Constant(s.P.rows(), 3, 7.0);
    some.reconstruct(Bd, out);
    int differ = 0;
    for (int v = 0; v < s.P.rows(); ++v)
      if (!is_placed[v]) differ += (out.row(v) - expected.row(v)).cwiseAbs().maxCoeff() != 0.0;
    CHECK(differ == 0);
  }
  // Local frames leave the placed rows as they are.
  DisplacementVectors local;
  local.set_placed_vertices(placed);
  local.encode(s.P, s.F, s.smooth, s.F);
  Positions out = Positions::Constant(s.P.rows(), 3, 7.0);
  local.reconstruct(Bd, out);
  int touched = 0;
  for (int v : placed) touched += (out.row(v).array() != 7.0).any();
  CHECK(touched == 0);

  DisplacementVectors bad;
  bad.set_placed_vertices({-1});
  CHECK_THROWS_WITH(bad.encode(s.P, s.F, s.smooth, s.F), Contains("placed vertex -1 is out of range"));
  CHECK_FALSE(bad.encoded());
}

TEST_CASE(
    "displacement vectors: every reconstructed vertex follows (9.8) with its frame, also where frames fall "
    "back",
    "[detail][vectors]") {
  // The frame loop runs four vertices at a time where the CPU allows; each vertex must still get exactly
  // b' + α n' + β t1' + γ t2' with VertexFrames' frame. A bent bar with a collapsed disc (vertices without
  // normal), plus the spiked fan (first edges along the normal) as a second component, and a vertex count
  // that is not a multiple of four.
  SceneOptions o;
  o.resolution = 3001;
  const Scene s = make_surface(SceneShape::Bar, o);
  Positions fan_P;
  Faces fan_F;
  fan_with_spike(fan_P, fan_F);
  const Eigen::Index n0 = s.P.rows(), nv = n0 + fan_P.rows();
  Positions B(nv, 3);
  B << s.smooth, fan_P;
  Faces F(s.F.rows() + fan_F.rows(), 3);
  F << s.F, fan_F.array() + static_cast<int>(n0);
  Positions Bd = B;
  for (Eigen::Index i = 0; i < n0; ++i) Bd(i, 1) += 0.3 * Bd(i, 0) * Bd(i, 0);
  const Vec3 centre = Bd.row(n0 / 2);
  int collapsed = 0;
  for (Eigen::Index i = 0; i < n0; ++i)
    if ((Bd.row(i).transpose() - centre).norm() < 0.05) Bd.row(i) = centre.transpose(), ++collapsed;
  REQUIRE(collapsed > 8);
  DisplacementVectors vectors;
  vectors.encode(random_offsets(B, 0.01, 3), F, B, F);
  Positions out;
  vectors.reconstruct(Bd, out);
  Positions N, T1, T2;
  vectors.frames().compute(Bd, N, T1, T2);
  const Eigen::MatrixX3d& c = vectors.coefficients();
  int differ = 0, world_frames = 0;
  for (Eigen::Index v = 0; v < nv; ++v) {
    const Vec3 n = N.row(v), t1 = T1.row(v), t2 = T2.row(v);
    const Vec3 expected = Bd.row(v).transpose() + (c(v, 0) * n + c(v, 1) * t1 + c(v, 2) * t2);
    differ += (out.row(v).transpose() - expected).cwiseAbs().maxCoeff() != 0.0;
    world_frames += n == Vec3::UnitZ() && t1 == Vec3::UnitX();
  }
  CHECK(world_frames >= collapsed / 2);
  CHECK(differ == 0);
}
