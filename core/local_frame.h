#pragma once
//! \file A centred, normalised frame x̂ = (x − centre) / scale, for code whose tolerances, damping or
//! single-precision copies depend on where a shape sits or the units it is modelled in (issue 14: a shape
//! 1e6 from the origin, or modelled in 1e-30 units, is the same shape).

#include <vector>

#include "msdeform/core/types.h"

namespace msd {

struct LocalFrame {
  Vec3 centre = Vec3::Zero();
  double scale = 1;
  //! The frame of P (#V by 3): its bounding box's centre and diagonal (scale 1 when all points coincide).
  static LocalFrame of(const Positions& P);
  Positions to_local(const Positions& X) const { return (X.rowwise() - centre.transpose()) / scale; }
  //! Into out (no allocation once it has X's size).
  void to_local(const Positions& X, Positions& out) const {
    out = (X.rowwise() - centre.transpose()) / scale;
  }
  Vec3 to_local(const Vec3& x) const { return (x - centre) / scale; }
  //! In place, allocation-free.
  void to_world(Positions& X) const {
    X *= scale;
    X.rowwise() += centre.transpose();
  }
  //! T̂ = N T N⁻¹ with N(x) = (x − centre) / scale: the same motion in the local frame.
  Mat4 to_local(const Mat4& T) const;
  //! Every transform, into out (resized; no allocation once it has the size).
  void to_local(const std::vector<Mat4>& T, std::vector<Mat4>& out) const {
    out.resize(T.size());
    for (size_t k = 0; k < T.size(); ++k) out[k] = to_local(T[k]);
  }
};

}  // namespace msd
