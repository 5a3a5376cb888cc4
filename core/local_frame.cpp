#include "msdeform/core/local_frame.h"

#include <cmath>

namespace msd {

LocalFrame LocalFrame::of(const Positions& P) {
  LocalFrame f;
  if (P.rows() == 0) return f;
  const Vec3 lo = P.colwise().minCoeff().transpose(), hi = P.colwise().maxCoeff().transpose();
  f.centre = 0.5 * (lo + hi);
  const double diagonal = (hi - lo).norm();
  f.scale = diagonal > 0 && std::isfinite(diagonal) ? diagonal : 1;
  return f;
}

Mat4 LocalFrame::to_local(const Mat4& T) const {
  Mat4 out = T;
  // N T N⁻¹ x̂ = (A (scale x̂ + centre) + t − centre) / scale = A x̂ + (A centre + t − centre) / scale
  out.topRightCorner<3, 1>() = (T.topLeftCorner<3, 3>() * centre + T.topRightCorner<3, 1>() - centre) / scale;
  return out;
}

}  // namespace msd
