#include "msdeform/core/extent.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "msdeform/core/errors.h"
#include "msdeform/core/mesh.h"

namespace msd {

std::string format_number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", x);
  return text;
}

void check_extent(const Positions& P, const std::string& who) {
  if (P.rows() == 0) return;
  const double diagonal = bounding_box_diagonal(P);
  const double largest = P.cwiseAbs().maxCoeff();
  if (diagonal == 0)
    throw InvalidInput(who + ": the input has no extent (all its " + std::to_string(P.rows()) +
                       " vertices are at one point)");
  const bool large = !(std::max(diagonal, largest) < kMaxExtent);
  if (large || !(diagonal >= kMinExtent))
    throw InvalidInput(
        who + ": coordinates too " + (large ? "large" : "small") + ": the bounding-box diagonal is " +
        (std::isfinite(diagonal) ? format_number(diagonal) : std::string("beyond the largest double")) +
        " and the largest |coordinate| " + format_number(largest) +
        "; msdeform works with sizes from 1e-70 to 1e70 (squared areas must fit a double): " +
        // A shape of a fine size far from the origin needs moving, not scaling.
        (large && diagonal < kMaxExtent && diagonal >= kMinExtent
             ? std::string("move the input nearer the origin (centre it)")
             : std::string("rescale the input")));
}

std::string extent_outlier_warning(const Positions& P, const Faces& F, const std::string& who) {
  const long n = static_cast<long>(P.rows());
  if (n < 8) return {};
  const long k = std::max({n / 1000, std::min(5L, n / 100), 1L});  // coordinates left out at each end of an axis
  Vec3 lo, hi;
  std::vector<double> c(n);
  for (int d = 0; d < 3; ++d) {
    std::copy(P.col(d).data(), P.col(d).data() + n, c.begin());
    std::nth_element(c.begin(), c.begin() + k, c.end());
    lo[d] = c[k];
    std::nth_element(c.begin(), c.begin() + (n - 1 - k), c.end());
    hi[d] = c[n - 1 - k];
  }
  const double diagonal = bounding_box_diagonal(P), core = (hi - lo).norm();
  if (!(diagonal > 10 * core)) return {};
  long farthest = 0;
  double distance = -1;
  for (long v = 0; v < n; ++v) {
    const Vec3 p = P.row(v);
    const double outside = (p - p.cwiseMax(lo).cwiseMin(hi)).norm();
    if (outside > distance) distance = outside, farthest = v;
  }
  if (F.rows() > 0) {  // a stray lies far from the rest in edge lengths, not only in the box
    std::vector<double> edges(3 * static_cast<size_t>(F.rows()));
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int j = 0; j < 3; ++j)
        edges[3 * f + j] = (P.row(F(f, j)) - P.row(F(f, (j + 1) % 3))).norm();
    const auto middle = edges.begin() + static_cast<long>(edges.size() / 2);
    std::nth_element(edges.begin(), middle, edges.end());
    if (!(distance > 100 * *middle)) return {};
  }
  // A vertex no face uses is usually a leftover of the file, not part of the surface: say so.
  const bool used = F.rows() == 0 || (F.array() == static_cast<int>(farthest)).any();
  const std::string stray = "vertex " + std::to_string(farthest) + (used ? "" : ", which no face uses,");
  return who + ": " + kOutlierWarning + ": its diagonal is " + format_number(diagonal) + ", but without the " +
         std::to_string(k) + " most extreme coordinate(s) at each end of each axis it is " + format_number(core) +
         " (" + stray + " lies " + format_number(distance) +
         " outside that box). Tolerances given in bounding-box diagonals (ARAP's and PriMo's stopping tests, "
         "constraint errors) are " + format_number(diagonal / core) + " times looser than meant; remove the "
         "outliers first";
}

}  // namespace msd
