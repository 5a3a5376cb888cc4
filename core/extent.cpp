#include "msdeform/core/extent.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

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
    throw InvalidInput(who + ": coordinates too " + (large ? "large" : "small") +
                       ": the bounding-box diagonal is " +
                       (std::isfinite(diagonal) ? format_number(diagonal) : std::string("beyond the largest double")) +
                       " and the largest |coordinate| " + format_number(largest) +
                       "; msdeform works with sizes from 1e-70 to 1e70 (squared areas must fit a double): rescale "
                       "the input");
}

}  // namespace msd
