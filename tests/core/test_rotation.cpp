#include <catch2/catch.hpp>

#include <random>

#include "msdeform/core/rotation.h"

using namespace msd;

namespace {

Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  return q.normalized().toRotationMatrix();
}

Mat3 random_matrix(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Mat3 A;
  for (int i = 0; i < 9; ++i) A(i) = u(rng);
  return A;
}

// Cross-covariance Σ e e'ᵀ of random edges e and their images e' = R e.
Mat3 covariance_of(const Mat3& R, std::mt19937& rng, int edges = 6) {
  std::uniform_real_distribution<double> u(-1, 1);
  Mat3 C = Mat3::Zero();
  for (int j = 0; j < edges; ++j) {
    const Vec3 e(u(rng), u(rng), u(rng));
    C += e * (R * e).transpose();
  }
  return C;
}

}  // namespace

TEST_CASE("best_rotation recovers the rotation of rotated edges", "[core][rotation]") {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 100; ++trial) {
    const Mat3 R = random_rotation(rng);
    const Mat3 fitted = best_rotation(covariance_of(R, rng));
    CHECK((fitted - R).cwiseAbs().maxCoeff() <= 1e-12);
    CHECK(std::abs(fitted.determinant() - 1) <= 1e-12);
  }
}

TEST_CASE("best_rotation of a mirror image is a rotation, never the reflection", "[core][rotation]") {
  std::mt19937 rng(11);
  const Mat3 mirror = Vec3(1, 1, -1).asDiagonal();
  for (int trial = 0; trial < 50; ++trial) {
    const Mat3 R = best_rotation(covariance_of(random_rotation(rng) * mirror, rng));
    CHECK(std::abs(R.determinant() - 1) <= 1e-12);
    CHECK((R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff() <= 1e-12);
  }
  // Rank-deficient covariance (edges in one plane): still a rotation.
  const Mat3 planar = Vec3(1, 2, 0).asDiagonal();
  const Mat3 R = best_rotation(planar);
  CHECK(std::abs(R.determinant() - 1) <= 1e-12);
}

TEST_CASE("polar_decomposition: R S reproduces A, R a rotation, S symmetric", "[core][rotation]") {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 100; ++trial) {
    Mat3 A = random_matrix(rng);
    if (trial % 2) A.col(0) = -A.col(0);  // both signs of det A, so reflections too
    const PolarDecomposition d = polar_decomposition(A);
    INFO("det A = " << A.determinant());
    CHECK((d.rotation * d.stretch - A).cwiseAbs().maxCoeff() <= 1e-12);
    CHECK(std::abs(d.rotation.determinant() - 1) <= 1e-12);
    CHECK((d.rotation.transpose() * d.rotation - Mat3::Identity()).cwiseAbs().maxCoeff() <= 1e-12);
    CHECK((d.stretch - d.stretch.transpose()).cwiseAbs().maxCoeff() <= 1e-12);
    CHECK(d.stretch.determinant() * A.determinant() >= 0);  // the reflection stays in S
  }
  SECTION("a rotation times a symmetric positive stretch splits back into its factors") {
    const Mat3 R = random_rotation(rng);
    Mat3 S;
    S << 2, 0.3, 0, 0.3, 1.5, 0.1, 0, 0.1, 0.7;
    const PolarDecomposition d = polar_decomposition(R * S);
    CHECK((d.rotation - R).cwiseAbs().maxCoeff() <= 1e-12);
    CHECK((d.stretch - S).cwiseAbs().maxCoeff() <= 1e-12);
  }
  SECTION("a reflection: det R = +1 and S has one negative eigenvalue") {
    const Mat3 mirror = Vec3(1, -1, 1).asDiagonal();
    const PolarDecomposition d = polar_decomposition(mirror);
    CHECK(std::abs(d.rotation.determinant() - 1) <= 1e-12);
    CHECK((d.rotation * d.stretch - mirror).cwiseAbs().maxCoeff() <= 1e-12);
    CHECK(d.stretch.determinant() == Approx(-1).margin(1e-12));
  }
}
