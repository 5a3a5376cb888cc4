#include "msdeform/deformation/gradient_editing.h"

#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/parallel.h"

namespace msd {

DeformerTraits GradientEditing::traits() const {
  DeformerTraits t;  // Surface, Linear, exact constraints, no vertex targets
  t.reproduces_rigid_motions = true;
  return t;
}

void GradientEditing::do_prepare(const Positions& P, const Faces& F, const Region& region) {
  rest_ = P;
  origin_ = bounding_box_centre(P);
  faces_ = F;
  const int nv = static_cast<int>(P.rows()), nf = static_cast<int>(F.rows()), nh = region.num_handles();
  const LaplaceOperator lap = cotan_laplacian(P, F);
  const std::vector<int> constrained = region.constrained_vertices();
  try {
    system_.prepare(-lap.W, constrained);  // Gᵀ A G = −W: the Poisson matrix of (9.10)
  } catch (const SolverError& e) {
    if (e.index() < 0) throw SolverError(std::string("gradient: ") + e.what());  // not singular: e.g. out of memory
    throw SolverError("gradient: the Poisson system is singular near vertex " + std::to_string(e.index()) +
                          " (a free vertex whose faces all have zero area?)",
                      e.index());
  }
  // (9.2) harmonic propagation weights from the same factored Dirichlet system.
  weights_ = harmonic_weights(system_, region);
  face_weights_.resize(nf, nh);
  for (int f = 0; f < nf; ++f)
    face_weights_.row(f) = (weights_.row(F(f, 0)) + weights_.row(F(f, 1)) + weights_.row(F(f, 2))) / 3.0;
  face_transforms_.resize(nf, 9);

  // Corner vectors: on face T with corners c, c' and opposite corner o, A_T ∇φ_c·∇φ_c' = −½ cot θ_o, so
  // the divergence term of vertex c is (Gᵀ A J')_c = M_T Σ_{c'≠c} ½ cot θ_o (p_c − p_c') =: M_T e_{T,c}
  // (the same clamped cotangents as W, so M_T = I gives back −W p exactly).
  const std::vector<int>& unknown = system_.unknown();
  std::vector<int> row_of(nv, -1);
  for (size_t u = 0; u < unknown.size(); ++u) row_of[unknown[u]] = static_cast<int>(u);
  corner_offsets_.assign(unknown.size() + 1, 0);
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c)
      if (row_of[F(f, c)] >= 0) ++corner_offsets_[row_of[F(f, c)] + 1];
  for (size_t u = 0; u < unknown.size(); ++u) corner_offsets_[u + 1] += corner_offsets_[u];
  corner_face_.resize(corner_offsets_.back());
  corner_vectors_.resize(corner_offsets_.back(), 3);
  std::vector<int> fill(corner_offsets_.begin(), corner_offsets_.end() - 1);
  for (int f = 0; f < nf; ++f) {
    const Vec3 p[3] = {P.row(F(f, 0)), P.row(F(f, 1)), P.row(F(f, 2))};
    const TriangleCotangents t = triangle_cotangents(p[0], p[1], p[2]);
    for (int c = 0; c < 3; ++c) {
      const int u = row_of[F(f, c)];
      if (u < 0) continue;
      Vec3 e = Vec3::Zero();
      if (!t.degenerate) {
        const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
        e = 0.5 * t.weight[c2] * (p[c] - p[c1]) + 0.5 * t.weight[c1] * (p[c] - p[c2]);
      }
      corner_face_[fill[u]] = f;
      corner_vectors_.row(fill[u]++) = e;
    }
  }
  handle_of_known_.resize(constrained.size());
  for (size_t c = 0; c < constrained.size(); ++c) handle_of_known_[c] = region.handle_of(constrained[c]);
  frame_.prepare(system_, 3);
  gradients_.assign(nh, HandleGradient{});
}

void GradientEditing::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  handle_gradients(transforms, gradients_);
  const long nf = faces_.rows();
  // Per face M_T (9.4.3).
  parallel_for_chunks(nf, [&](long b, long e) {
    for (long f = b; f < e; ++f) {
      const Mat3 M = blended_gradient(face_weights_.row(f).data(), gradients_);
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(face_transforms_.row(f).data()) = M;
    }
  });
  // Right-hand side Gᵀ A J' on the unknown rows, gathered per vertex.
  Eigen::MatrixXd& rhs = frame_.rhs();
  const long nu = rhs.rows();
  parallel_for_chunks(nu, [&](long b, long e) {
    for (long u = b; u < e; ++u) {
      Vec3 sum = Vec3::Zero();
      for (int q = corner_offsets_[u]; q < corner_offsets_[u + 1]; ++q) {
        const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> M(face_transforms_.row(corner_face_[q]).data());
        sum.noalias() += M * corner_vectors_.row(q).transpose();
      }
      rhs.row(u) = sum.transpose();
    }
  });
  // Known rows: p on fixed vertices, T_k p on handle vertices, relative to the rest shape's centre (the
  // Poisson matrix annihilates constants, so the solution moves with them; absolute positions far from the
  // origin lost digits in the solve: 25 times the input's rounding at an offset of 1e8 sizes).
  Eigen::MatrixXd& known = frame_.known();
  const std::vector<int>& kv = system_.known();
  for (size_t c = 0; c < kv.size(); ++c) {
    const int k = handle_of_known_[c];
    const Vec3 p = rest_.row(kv[c]);
    const Vec3 target = k < 0 ? p : transform_point(transforms[k], p);
    out.row(kv[c]) = target.transpose();
    known.row(c) = (target - origin_).transpose();
  }
  frame_.solve();
  const Eigen::MatrixXd& x = frame_.solution();
  const std::vector<int>& uv = system_.unknown();
  parallel_for_chunks(static_cast<long>(uv.size()), [&](long b, long e) {
    for (long u = b; u < e; ++u) out.row(uv[u]) = x.row(u) + origin_.transpose();
  });
}

Mat3 GradientEditing::rest_jacobian(int f) const {
  if (f < 0 || f >= faces_.rows()) throw UsageError("GradientEditing::rest_jacobian: face out of range (or not prepared)");
  const Vec3 p[3] = {rest_.row(faces_(f, 0)), rest_.row(faces_(f, 1)), rest_.row(faces_(f, 2))};
  const Vec3 n = (p[1] - p[0]).cross(p[2] - p[0]);
  const double area2 = n.norm();
  Mat3 J = Mat3::Zero();
  if (!(area2 > 0)) return J;
  const Vec3 unit = n / area2;
  for (int c = 0; c < 3; ++c) {
    // ∇φ_c = n̂ × (p_{c+2} − p_{c+1}) / (2A): perpendicular to the opposite edge, pointing to c.
    const Vec3 grad = unit.cross(p[(c + 2) % 3] - p[(c + 1) % 3]) / area2;
    J += p[c] * grad.transpose();
  }
  return J;
}

Mat3 GradientEditing::target_jacobian(int f) const {
  if (f < 0 || f >= face_transforms_.rows()) throw UsageError("GradientEditing::target_jacobian: face out of range (or not prepared)");
  const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> M(face_transforms_.row(f).data());
  return M * rest_jacobian(f);
}

}  // namespace msd
