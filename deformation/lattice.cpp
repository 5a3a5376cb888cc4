#include "msdeform/deformation/lattice.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"

namespace msd {

LatticeDeformer::LatticeDeformer(LatticeOptions options) : options_(options) {
  options_.least_norm.validate("lattice");  // here, not in prepare() (fifth break test)
  const auto count = [](int c) { return std::to_string(c); };
  const Eigen::Vector3i& c = options_.cells;
  // A count of 0 beside others (0, 2, 2) was refused later as "give all three cell counts or none".
  if ((c.array() < 0).any() || (c.array() > LatticeOptions::kMaxCells).any() || (c.any() && !c.all()))
    throw InvalidInput("lattice: cell counts must be in 1.." + count(LatticeOptions::kMaxCells) +
                       " (or all 0 to fit them), got (" + count(c.x()) + ", " + count(c.y()) + ", " + count(c.z()) + ")");
  if (options_.cells_longest < 1 || options_.cells_longest > LatticeOptions::kMaxCells)
    throw InvalidInput(
        "lattice: the cell count along the box's longest side (cells_longest; Python: cells=N, "
        "--lattice-cells) must be in 1.." +
        count(LatticeOptions::kMaxCells) + ", got " + count(options_.cells_longest));
  if (!(options_.margin >= 0 && options_.margin <= LatticeOptions::kMaxMargin))
    throw InvalidInput("lattice: the margin must be in 0..10 (relative to the bounding-box diagonal), got " +
                       format_number(options_.margin));
}

void LatticeDeformer::fit_basis(const Positions& P, const Region&) {
  const Vec3 lo = P.colwise().minCoeff().transpose(), hi = P.colwise().maxCoeff().transpose();
  double diag = (hi - lo).norm();
  if (!(diag > 0)) diag = 1;  // a single point (or all at one place): a unit lattice around it
  // At least a small extent along every axis, so a flat or straight input still gets a 3D lattice.
  const Vec3 size = ((hi - lo).array() + 2 * std::max(options_.margin, 1e-3) * diag).matrix();
  lo_ = lo - 0.5 * (size - (hi - lo));
  if (options_.cells.all()) {  // all positive (the constructor's check)
    cells_ = options_.cells;
  } else {
    const double cell = size.maxCoeff() / options_.cells_longest;
    for (int a = 0; a < 3; ++a) cells_[a] = std::max(1, static_cast<int>(std::lround(size[a] / cell)));
  }
  h_ = size.cwiseQuotient(cells_.cast<double>());
}

Positions LatticeDeformer::control_points() const {
  const Eigen::Vector3i n = cells_ + Eigen::Vector3i::Constant(3);
  Positions C(n.prod(), 3);
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i)
        C.row(i + n.x() * (j + n.y() * k)) = (lo_ + Vec3(i - 1, j - 1, k - 1).cwiseProduct(h_)).transpose();
  return C;
}

void LatticeDeformer::basis(const Vec3& x, BasisRow& row) const {
  // Per axis: cell s and the uniform cubic B-spline weights of control points s .. s + 3.
  int cell[3];
  double w[3][4];
  for (int a = 0; a < 3; ++a) {
    const double u = std::clamp((x[a] - lo_[a]) / h_[a], 0.0, static_cast<double>(cells_[a]));
    const int s = std::min(static_cast<int>(u), cells_[a] - 1);
    const double t = u - s, t2 = t * t, t3 = t2 * t, r = 1 - t;
    cell[a] = s;
    w[a][0] = r * r * r / 6;
    w[a][1] = (3 * t3 - 6 * t2 + 4) / 6;
    w[a][2] = (-3 * t3 + 3 * t2 + 3 * t + 1) / 6;
    w[a][3] = t3 / 6;
  }
  const int nx = cells_.x() + 3, ny = cells_.y() + 3;
  row.clear();
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i)
        row.add(cell[0] + i + nx * (cell[1] + j + ny * (cell[2] + k)), w[0][i] * w[1][j] * w[2][k]);
}

}  // namespace msd
