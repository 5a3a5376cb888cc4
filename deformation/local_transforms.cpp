#include "msdeform/deformation/local_transforms.h"

#include <cmath>

#include "msdeform/core/errors.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/rotation.h"

namespace msd {

void handle_gradients(const std::vector<Mat4>& transforms, std::vector<HandleGradient>& out) {
  if (out.size() != transforms.size()) out.resize(transforms.size());
  for (size_t k = 0; k < transforms.size(); ++k) {
    const PolarDecomposition pd = polar_decomposition(transforms[k].topLeftCorner<3, 3>());
    const Eigen::AngleAxisd aa(pd.rotation);
    out[k].rotation_vector = aa.angle() * aa.axis();
    out[k].stretch_minus_identity = pd.stretch - Mat3::Identity();
  }
}

Mat3 blended_gradient(const double* s, const std::vector<HandleGradient>& handles) {
  Vec3 omega = Vec3::Zero();
  Mat3 stretch = Mat3::Identity();
  for (size_t k = 0; k < handles.size(); ++k) {
    omega += s[k] * handles[k].rotation_vector;
    stretch += s[k] * handles[k].stretch_minus_identity;
  }
  const double angle = omega.norm();
  if (angle < 1e-300) return stretch;
  return Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix() * stretch;
}

Eigen::MatrixXd harmonic_weights(const ConstrainedQuadratic& system, const Region& region) {
  const int n = region.num_vertices(), nh = region.num_handles();
  const std::vector<int>& known = system.known();
  Eigen::MatrixXd S(n, nh);
  if (nh == 1 && region.fixed_vertices().empty()) {
    S.setOnes();  // nothing to blend towards (as propagation_field)
    return S;
  }
  Eigen::MatrixXd values = Eigen::MatrixXd::Zero(known.size(), nh);
  for (size_t c = 0; c < known.size(); ++c) {
    const int k = region.handle_of(known[c]);
    if (k >= 0) values(c, k) = 1.0;
  }
  system.solve(values, S);
  if (!S.allFinite()) throw SolverError("harmonic weights are not finite (ill-conditioned Laplace system)");
  S = S.cwiseMax(0.0).cwiseMin(1.0);
  for (int i = 0; i < n; ++i) {
    if (!region.is_free(i)) {
      S.row(i).setZero();
      const int k = region.handle_of(i);
      if (k >= 0) S(i, k) = 1.0;
    } else {
      const double sum = S.row(i).sum();
      if (sum > 1) S.row(i) /= sum;
    }
  }
  return S;
}

void KnownRowSolve::prepare(const ConstrainedQuadratic& system, int columns) {
  system_ = &system;
  coupling_ = system.coupling();
  known_.setZero(system.known().size(), columns);
  rhs_.setZero(system.unknown().size(), columns);
  xu_.setZero(system.unknown().size(), columns);
}

void KnownRowSolve::solve() {
  if (!system_) throw UsageError("KnownRowSolve::solve: call prepare() first");
  const long nu = rhs_.rows(), cols = rhs_.cols();
  if (nu == 0) return;
  const int* outer = coupling_.outerIndexPtr();
  const int* inner = coupling_.innerIndexPtr();
  const double* value = coupling_.valuePtr();
  parallel_for_chunks(nu, [&](long b, long e) {
    for (long i = b; i < e; ++i)
      for (int p = outer[i]; p < outer[i + 1]; ++p) {
        const double w = value[p];
        const long c = inner[p];
        for (long d = 0; d < cols; ++d) rhs_(i, d) -= w * known_(c, d);
      }
  }, 1 << 14);
  system_->solver().solve(rhs_, xu_);  // CHOLMOD reuses its workspace: no allocation once sized
}

}  // namespace msd
