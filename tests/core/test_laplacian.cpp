#include <catch2/catch.hpp>

#include <Eigen/Eigenvalues>
#include <random>

#include "msdeform/core/laplacian.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/scenes.h"
#include "test_util.h"

using namespace msd;

namespace {
double max_abs(const SparseMatrix& A) {
  double m = 0;
  for (int k = 0; k < A.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(A, k); it; ++it) m = std::max(m, std::abs(it.value()));
  return m;
}
}  // namespace

TEST_CASE("cotan Laplacian: constants in the kernel, symmetric, mass sums to the area", "[core][laplacian]") {
  Positions P;
  Faces F;
  SECTION("bumpy plane") {
    SceneOptions o;
    o.resolution = 2000;
    const Scene s = make_surface(SceneShape::Plane, o);
    P = s.P;
    F = s.F;
  }
  SECTION("real mesh: bumpy.off") {
    const Mesh m = load_mesh(test::shared_data("bumpy.off"));
    P = positions(m);
    F = faces(m);
  }
  REQUIRE(F.rows() > 0);  // Catch runs the case once more without a section when one throws
  const LaplaceOperator lap = cotan_laplacian(P, F);
  CHECK(lap.degenerate_faces == 0);
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(P.rows());
  CHECK((lap.W * ones).cwiseAbs().maxCoeff() <= 1e-12 * max_abs(lap.W));
  CHECK(max_abs(SparseMatrix(lap.W - SparseMatrix(lap.W.transpose()))) <= 1e-15 * max_abs(lap.W));
  CHECK(lap.mass.sum() == Approx(face_areas(P, F).sum()).epsilon(1e-12));
  CHECK(lap.mass.minCoeff() > 0);
}

TEST_CASE("cotan Laplacian: linear precision at interior vertices of a planar mesh", "[core][laplacian]") {
  Positions P;
  Faces F;
  std::vector<bool> interior;
  test::jittered_grid(12, 0.3, P, F, interior);
  const LaplaceOperator lap = cotan_laplacian(P, F);
  const Eigen::VectorXd f = 2.0 * P.col(0) - 3.0 * P.col(1) + Eigen::VectorXd::Constant(P.rows(), 0.5);
  const Eigen::VectorXd Wf = lap.W * f;
  for (int i = 0; i < P.rows(); ++i)
    if (interior[i]) REQUIRE(std::abs(Wf[i]) <= 1e-12);
}

TEST_CASE("cotan Laplacian of a sphere approximates -2H n, better with refinement", "[core][laplacian]") {
  double previous = 1e9;
  for (int level = 2; level <= 5; ++level) {
    Positions P;
    Faces F;
    test::icosphere(level, P, F);
    const LaplaceOperator lap = cotan_laplacian(P, F);
    const Positions HN = lap.mass.cwiseInverse().asDiagonal() * (lap.W * P);
    // Unit sphere: Δp = -2 H n = -2 p.
    const double err = (HN + 2.0 * P).rowwise().norm().maxCoeff() / 2.0;
    INFO("level " << level << " max relative error " << err);
    CHECK(err < previous);
    previous = err;
  }
  CHECK(previous < 0.01);
}

TEST_CASE("gradient of a linear function is exact, divergence of gradient is W", "[core][laplacian]") {
  Positions P;
  Faces F;
  test::icosphere(2, P, F);
  P.col(0) *= 1.7;  // an ellipsoid, so faces are not all alike
  const Vec3 a(0.3, -1.2, 2.0);
  const Eigen::VectorXd f = P * a + Eigen::VectorXd::Constant(P.rows(), 4.0);
  const SparseMatrix G = gradient_operator(P, F);
  const Eigen::VectorXd g = G * f;
  for (int t = 0; t < F.rows(); ++t) {
    const Vec3 n = (Vec3(P.row(F(t, 1)) - P.row(F(t, 0)))).cross(Vec3(P.row(F(t, 2)) - P.row(F(t, 0)))).normalized();
    const Vec3 expected = a - a.dot(n) * n;  // the tangential part of a
    REQUIRE((g.segment<3>(3 * t) - expected).norm() <= 1e-12 * a.norm());
  }
  const SparseMatrix DG = divergence_operator(P, F) * G;
  const LaplaceOperator lap = cotan_laplacian(P, F);
  CHECK(max_abs(SparseMatrix(DG - lap.W)) <= 1e-12 * max_abs(lap.W));
}

TEST_CASE("degenerate and needle triangles give finite operators and are reported", "[core][laplacian]") {
  Positions P(6, 3);
  P << 0, 0, 0,  //
      1, 0, 0,   //
      0, 1, 0,   //
      2, 0, 0,   // collinear with 0 and 1: zero-area face (0, 1, 3)
      1, 1e-9, 0,  // needle
      0.5, -1, 0;
  Faces F(4, 3);
  F << 0, 1, 2,  //
      0, 3, 1,   //
      1, 3, 4,   //
      0, 5, 1;
  const LaplaceOperator lap = cotan_laplacian(P, F);
  CHECK(lap.degenerate_faces == 1);
  CHECK(lap.clamped_cotangents >= 1);
  for (int k = 0; k < lap.W.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(lap.W, k); it; ++it) REQUIRE(std::isfinite(it.value()));
  CHECK(lap.mass.allFinite());
  CHECK(gradient_operator(P, F).coeffs().allFinite());
}

TEST_CASE("a zero-area triangle stays degenerate far from the origin, a needle stays a needle",
          "[core][laplacian]") {
  // The second break test: zero-area triangles of the lift moved by (1e6, 5e5, -1e6) came back from the
  // rounding as needles of area 1e-9 of their edges', clamped instead of left out (results 7e-5 of the
  // diagonal off the edit at the origin), and the fold check counted them as folds.
  const Vec3 a(0, 0, 0), b(0.01, 0, 0), c(0.02, 0, 0), far(1e6, 5e5, -1e6);
  CHECK(triangle_cotangents(a, b, c).degenerate);
  CHECK(triangle_cotangents(a + far, b + far, c + far).degenerate);
  // Collinear as read: rounded to the coordinates' precision, not exactly on a line.
  const Vec3 d(0.0123456789, 0.00987654321, 0), e = 2 * d;
  const TriangleCotangents rounded = triangle_cotangents(a + far, d + far, e + far);
  CHECK(rounded.degenerate);
  // A needle well above the rounding stays one, at the origin and far from it.
  const Vec3 tip(0.02, 1e-7, 0);  // cotangent 2e5 at a
  for (const Vec3& shift : {Vec3(0, 0, 0), Vec3(1e3, 1e3, 1e3)}) {
    const TriangleCotangents needle = triangle_cotangents(a + shift, c + shift, tip + shift);
    CHECK_FALSE(needle.degenerate);
    CHECK(needle.needle_corners > 0);
  }
}

TEST_CASE("uniform Laplacian: rows sum to zero, diagonal is minus the degree", "[core][laplacian]") {
  Positions P;
  Faces F;
  test::icosphere(1, P, F);
  const SparseMatrix W = uniform_laplacian(F, static_cast<int>(P.rows()));
  CHECK((W * Eigen::VectorXd::Ones(P.rows())).cwiseAbs().maxCoeff() == 0.0);
  // Icosahedron vertices have degree 5, edge midpoints degree 6.
  for (int i = 0; i < P.rows(); ++i) REQUIRE(-W.coeff(i, i) == (i < 12 ? 5.0 : 6.0));
}

TEST_CASE("cotan Laplacian: negative semi-definite for any triangle, needles included", "[core][laplacian]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  Faces F(1, 3);
  F << 0, 1, 2;
  for (int trial = 0; trial < 2000; ++trial) {
    Positions P(3, 3);
    for (int i = 0; i < 3; ++i) P.row(i) = Vec3(u(rng), u(rng), u(rng)).transpose();
    if (trial % 2 == 1) {  // a needle: the third corner almost on the first edge, or two corners almost together
      const double t = trial % 4 == 1 ? 0.5 : 1e-9;
      P.row(2) = (1 - t) * P.row(0) + t * P.row(1) + 1e-8 * Eigen::RowVector3d(u(rng), u(rng), u(rng));
    }
    const LaplaceOperator L = cotan_laplacian(P, F);
    const Eigen::Matrix3d W = Eigen::MatrixXd(L.W);
    const double largest = W.cwiseAbs().maxCoeff();
    const Eigen::Vector3d eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(W).eigenvalues();
    INFO("trial " << trial << ", eigenvalues " << eig.transpose());
    CHECK(eig.maxCoeff() <= 1e-9 * std::max(largest, 1.0));
  }
}

TEST_CASE("weighted_square refuses a product beyond a sparse matrix's int index, naming the vertex",
          "[core][laplacian]") {
  // A disk triangulated as one fan: W M⁻¹ W couples every two of the centre's 47000 neighbours, more than
  // 2^31 − 1 entries (the column starts' int sums overflowed before: the shell crashed on such a cone).
  Positions P;
  Faces F;
  test::fan_disk(47000, P, F);
  const LaplaceOperator lap = cotan_laplacian(P, F);
  CHECK_THROWS_WITH(weighted_square(lap.W, lap.mass.cwiseInverse()),
                    Catch::Contains("more than 2^31 - 1 nonzeros") && Catch::Contains("vertex 0 has 47000"));
}

TEST_CASE("weighted_square refuses a product that would not fit in memory, naming the vertex", "[core][laplacian]") {
  // Below 2^31 entries, a fan's W M^-1 W and its factorisation took 35 bytes per entry: a 25000-neighbour
  // centre ran a 24 GB machine out of memory after minutes, with a bare "out of memory". The smallest fan
  // over this machine's memory at the 48 bytes per entry assumed is refused at once.
  const std::uint64_t memory = physical_memory();
  REQUIRE(memory > 0);
  const int k = static_cast<int>(std::sqrt(memory / 48.0)) + 1;
  Positions P;
  Faces F;
  test::fan_disk(k, P, F);
  const LaplaceOperator lap = cotan_laplacian(P, F);
  const bool indexable = static_cast<double>(k + 1) * (k + 1) <= 2147483647.0;
  CHECK_THROWS_WITH(weighted_square(lap.W, lap.mass.cwiseInverse()),
                    Catch::Contains(indexable ? "more than this machine's" : "more than 2^31 - 1 nonzeros") &&
                        Catch::Contains("vertex 0 has " + std::to_string(k)));
}

TEST_CASE("weighted_square is Eigen's W diag(w) W bit for bit, submatrix is the dense extraction", "[core][laplacian]") {
  SceneOptions options;
  options.resolution = 20000;  // over the parallel grain: both cores take part
  const Scene scene = make_scene("lift", options);
  const LaplaceOperator lap = cotan_laplacian(scene.P, scene.F);
  Eigen::VectorXd w = lap.mass.cwiseInverse();
  for (Eigen::Index v = 0; v < w.size(); v += 97) w[v] = 0;  // zero weights keep the pattern, as Eigen does
  const SparseMatrix eigen_product = lap.W * SparseMatrix(w.asDiagonal() * lap.W);
  const SparseMatrix Q = weighted_square(lap.W, w);
  REQUIRE(Q.nonZeros() == eigen_product.nonZeros());
  bool same = true;
  for (Eigen::Index j = 0; j < Q.outerSize(); ++j) {
    SparseMatrix::InnerIterator a(Q, j), b(eigen_product, j);
    for (; a && b; ++a, ++b) same = same && a.row() == b.row() && a.value() == b.value();
    same = same && !a && !b;
  }
  CHECK(same);

  // Rows in shuffled order, columns a subset: entries keep their list order, rows ascend in each column.
  std::vector<int> rows, cols;
  for (int v = 0; v < static_cast<int>(scene.P.rows()); ++v) (v % 3 ? rows : cols).push_back(v);
  std::shuffle(rows.begin(), rows.end(), std::mt19937(5));
  const SparseMatrix S = submatrix(Q, rows, cols);
  REQUIRE(S.rows() == static_cast<Eigen::Index>(rows.size()));
  REQUIRE(S.cols() == static_cast<Eigen::Index>(cols.size()));
  double difference = 0;
  bool ascending = true;
  long entries = 0;
  for (Eigen::Index c = 0; c < S.outerSize(); ++c) {
    Eigen::Index previous = -1;
    for (SparseMatrix::InnerIterator it(S, c); it; ++it) {
      ascending = ascending && it.row() > previous;
      previous = it.row();
      difference = std::max(difference, std::abs(it.value() - Q.coeff(rows[it.row()], cols[c])));
    }
  }
  std::vector<char> is_row(Q.rows(), 0);
  for (int r : rows) is_row[r] = 1;
  for (int c : cols)
    for (SparseMatrix::InnerIterator it(Q, c); it; ++it) entries += is_row[it.row()];
  CHECK(S.nonZeros() == entries);
  CHECK(difference == 0.0);
  CHECK(ascending);
}
