#include "msdeform/deformation/rbf.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "msdeform/core/errors.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"

namespace msd {

struct RbfDeformer::Factor {
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
};

RbfDeformer::RbfDeformer(RbfOptions options) : options_(options) {
  if (options_.max_centres < 1 || options_.max_centres > RbfOptions::kMaxCentres)
    throw InvalidInput("rbf: max_centres must be in 1.." + std::to_string(RbfOptions::kMaxCentres) + ", got " +
                       std::to_string(options_.max_centres));
}

void RbfDeformer::fit_basis(const Positions& P, const Region& region) {
  const std::vector<int> constrained = region.constrained_vertices();
  const long nc = static_cast<long>(constrained.size());
  Positions C(nc, 3);
  for (long c = 0; c < nc; ++c) C.row(c) = P.row(constrained[c]);
  origin_ = bounding_box_centre(C);
  scale_ = bounding_box_diagonal(C);
  if (!(scale_ > 0)) scale_ = 1;
  // Farthest-point sampling: seeds on each group (the first vertex of every handle and of the fixed
  // part), then the constrained vertex farthest from all chosen ones, until max_centres or until every
  // vertex lies within 1e-9·diag of a centre (duplicates merged).
  std::vector<double> distance(nc, std::numeric_limits<double>::infinity());
  centre_rows_.clear();
  auto choose = [&](long c) {
    centre_rows_.push_back(static_cast<int>(c));
    const Vec3 p = C.row(c);
    parallel_for_chunks(nc, [&](long i0, long i1) {
      for (long i = i0; i < i1; ++i) distance[i] = std::min(distance[i], (Vec3(C.row(i)) - p).squaredNorm());
    });
  };
  std::vector<int> seen_group;
  for (long c = 0; c < nc && static_cast<int>(centre_rows_.size()) < options_.max_centres; ++c) {
    const int group = region.handle_of(constrained[c]);
    if (std::find(seen_group.begin(), seen_group.end(), group) != seen_group.end()) continue;
    seen_group.push_back(group);
    if (distance[c] > 0) choose(c);
  }
  const double tiny = 1e-18 * scale_ * scale_;
  while (static_cast<int>(centre_rows_.size()) < options_.max_centres) {
    const long far = std::max_element(distance.begin(), distance.end()) - distance.begin();
    if (!(distance[far] > tiny)) break;
    choose(far);
  }
  std::sort(centre_rows_.begin(), centre_rows_.end());
  const long n = static_cast<long>(centre_rows_.size());
  centres_.resize(n, 3);
  centre_vertices_.resize(n);
  for (long j = 0; j < n; ++j) {
    centres_.row(j) = (C.row(centre_rows_[j]) - origin_.transpose()) / scale_;
    centre_vertices_[j] = constrained[centre_rows_[j]];
  }
  // The polynomial's directions: principal axes along which the centres extend (1e-6 of the widest).
  const Vec3 mean = centres_.colwise().mean().transpose();
  const Mat3 covariance = (centres_.rowwise() - mean.transpose()).transpose() * (centres_.rowwise() - mean.transpose()) / std::max<long>(n, 1);
  Eigen::SelfAdjointEigenSolver<Mat3> eigen(covariance);
  std::vector<int> kept;
  for (int a = 0; a < 3; ++a)
    if (eigen.eigenvalues()[a] > 1e-12 * eigen.eigenvalues().maxCoeff() && eigen.eigenvalues()[a] > 0) kept.push_back(a);
  axes_.resize(3, static_cast<Eigen::Index>(kept.size()));
  for (size_t a = 0; a < kept.size(); ++a) axes_.col(a) = eigen.eigenvectors().col(kept[a]);
}

void RbfDeformer::basis(const Vec3& x, BasisRow& row) const {
  const Vec3 q = (x - origin_) / scale_;
  const long n = centres_.rows();
  row.clear();
  for (long j = 0; j < n; ++j) {
    const double r = (Vec3(centres_.row(j)) - q).norm();
    row.add(static_cast<int>(j), r * r * r);
  }
  row.add(static_cast<int>(n), 1.0);
  for (Eigen::Index a = 0; a < axes_.cols(); ++a) row.add(static_cast<int>(n + 1 + a), axes_.col(a).dot(q));
}

void RbfDeformer::prepare_solve(const Positions&, const std::vector<int>&) {
  // (9.15) with the polynomial block: [Φ Π; Πᵀ 0] [w; a] = [d̄; 0].
  const long n = centres_.rows(), m = basis_size();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, m);
  parallel_for_chunks(n, [&](long j0, long j1) {
    BasisRow row;
    for (long j = j0; j < j1; ++j) {
      basis(Vec3(centres_.row(j).transpose()) * scale_ + origin_, row);
      for (size_t k = 0; k < row.index.size(); ++k) A(j, row.index[k]) = row.value[k];
    }
  }, 64);
  A.bottomLeftCorner(m - n, n) = A.topRightCorner(n, m - n).transpose();
  auto factor = std::make_shared<Factor>();
  factor->lu.compute(A);
  const double rcond = factor->lu.rcond();
  if (!(rcond > 1e-15)) {
    // Name the closest pair of centres: nearly coincident constraints are the usual cause.
    long a = 0, b = 0;
    double closest = std::numeric_limits<double>::infinity();
    for (long i = 0; i < n; ++i)
      for (long j = i + 1; j < n; ++j)
        if (const double d = (centres_.row(i) - centres_.row(j)).norm(); d < closest) closest = d, a = i, b = j;
    char figures[64];
    std::snprintf(figures, sizeof(figures), "%.3g", closest * scale_);
    throw SolverError("rbf: the interpolation system of " + std::to_string(n) + " centres is singular; the closest "
                      "centres are constrained vertices " + std::to_string(centre_vertices_[a]) + " and " +
                      std::to_string(centre_vertices_[b]) + ", " + figures + " apart: unconstrain one or move them apart");
  }
  factor_ = std::move(factor);
}

void RbfDeformer::solve(const Eigen::MatrixXd& values, Eigen::MatrixXd& coefficients) const {
  const long n = centres_.rows(), m = basis_size();
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, values.cols());
  for (long j = 0; j < n; ++j) rhs.row(j) = values.row(centre_rows_[j]);
  coefficients = factor_->lu.solve(rhs);
}

}  // namespace msd
