#include "msdeform/deformation/propagation.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/kd_tree.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/rotation.h"
#include "msdeform/core/solver.h"

namespace msd {
namespace {

//! #V distances from every vertex of P to the nearest vertex of `set` (+∞ when set is empty).
Eigen::VectorXd euclidean_distance(const Positions& P, const std::vector<int>& set) {
  Eigen::VectorXd d(P.rows());
  const KdTree tree(P, set);
  parallel_for_chunks(P.rows(), [&](long b, long e) {
    for (long i = b; i < e; ++i) d[i] = tree.nearest_distance(P.row(i).transpose());
  });
  return d;
}

// ---------------------------------------------------------------------------------------------------
// Fields


//! #V by h raw fields: exactly 1 on handle k in column k, exactly 0 on fixed vertices and other handles.
Eigen::MatrixXd raw_fields(const Positions& P, const Faces& F, const Region& region, PropagationField field,
                           const HeatGeodesicsOptions& heat) {
  const int n = static_cast<int>(P.rows()), nh = region.num_handles();
  Eigen::MatrixXd S(n, nh);
  switch (field) {
    case PropagationField::Harmonic: {
      // (9.2): minimise the Dirichlet energy ½ sᵀ(−W)s with s fixed on the constrained vertices; its
      // minimiser satisfies (W s)_i = 0, i.e. Δs = 0, at every free vertex.
      if (nh == 1 && region.fixed_vertices().empty()) {
        S.setOnes();  // nothing to blend towards: the exact solution, without round-off
        break;
      }
      const std::vector<int> constrained = region.constrained_vertices();
      Eigen::MatrixXd values = Eigen::MatrixXd::Zero(constrained.size(), nh);
      for (size_t c = 0; c < constrained.size(); ++c) {
        const int k = region.handle_of(constrained[c]);
        if (k >= 0) values(c, k) = 1.0;
      }
      ConstrainedQuadratic laplace;
      try {
        laplace.prepare(-cotan_laplacian(P, F).W, constrained);
      } catch (const SolverError& e) {
        if (e.index() < 0) throw SolverError(std::string("propagate (harmonic field): ") + e.what());  // not singular: e.g. out of memory
        throw SolverError("propagate (harmonic field): the Laplace system is singular at vertex " +
                              std::to_string(e.index()) + " (a free vertex whose faces all have zero area?)",
                          e.index());
      }
      laplace.solve(values, S);
      break;
    }
    case PropagationField::Euclidean:
    case PropagationField::Geodesic: {
      // Distances to the fixed part (column 0) and to every handle (column 1 + j).
      Eigen::MatrixXd dist(n, nh + 1);
      std::vector<std::vector<int>> sets = {region.fixed_vertices()};
      for (int j = 0; j < nh; ++j) sets.push_back(region.handle_vertices(j));
      if (field == PropagationField::Euclidean) {
        for (size_t c = 0; c < sets.size(); ++c) dist.col(c) = euclidean_distance(P, sets[c]);
      } else {
        HeatGeodesics geodesics(P, F, heat);
        for (size_t c = 0; c < sets.size(); ++c) dist.col(c) = geodesics.distance(sets[c]);
      }
      // (9.1) per handle k, with dist_F = distance to fixed ∪ other handles = min of their distances.
      parallel_for_chunks(n, [&](long b, long e) {
        for (long i = b; i < e; ++i)
          for (int k = 0; k < nh; ++k) {
            double to_zero = dist(i, 0);
            for (int j = 0; j < nh; ++j)
              if (j != k) to_zero = std::min(to_zero, dist(i, 1 + j));
            const double to_handle = dist(i, 1 + k);
            double s;
            if (std::isinf(to_zero))
              s = 1.0;  // nothing holds this part back (or nothing at all is reachable)
            else if (std::isinf(to_handle))
              s = 0.0;
            else if (to_zero + to_handle > 0)
              s = to_zero / (to_zero + to_handle);
            else
              s = 0.5;  // a vertex on top of both a handle and a zero-set vertex
            S(i, k) = s;
          }
      });
      break;
    }
    default:
      throw InvalidInput("propagate: unknown PropagationField value " + std::to_string(static_cast<int>(field)));
  }
  if (!S.allFinite()) throw SolverError("propagate: the propagation field is not finite (ill-conditioned system)");
  // Clamp (round-off and, for the harmonic field, the maximum principle's failure where cotan weights are
  // negative), then impose the constraints exactly.
  S = S.cwiseMax(0.0).cwiseMin(1.0);
  for (int i = 0; i < n; ++i)
    if (!region.is_free(i)) {
      S.row(i).setZero();
      const int k = region.handle_of(i);
      if (k >= 0) S(i, k) = 1.0;
    }
  return S;
}

}  // namespace

Eigen::VectorXd propagation_field(const Positions& P, const Faces& F, const Region& region, PropagationField field,
                                  int handle) {
  check_mesh_arrays(P, F, "propagation_field");
  region.validate(static_cast<int>(P.rows()), &F);
  if (handle < 0 || handle >= region.num_handles())
    throw InvalidInput("propagation_field: handle " + std::to_string(handle) + " requested, the region has " +
                       std::to_string(region.num_handles()) + " handle(s)");
  return raw_fields(P, F, region, field, HeatGeodesicsOptions{}).col(handle);
}

// ---------------------------------------------------------------------------------------------------
// Deformer

TransformationPropagation::TransformationPropagation(PropagationOptions options) : options_(std::move(options)) {
  if (options_.transfer == PropagationTransfer::Custom && !options_.custom_transfer)
    throw InvalidInput("propagate: transfer is PropagationTransfer::Custom but custom_transfer is empty");
  if (options_.transfer != PropagationTransfer::Custom && options_.custom_transfer)
    throw InvalidInput("propagate: custom_transfer is set but transfer is not PropagationTransfer::Custom; set "
                       "transfer = Custom to use it");
  if (options_.transfer != PropagationTransfer::Linear && options_.transfer != PropagationTransfer::SmoothStep &&
      options_.transfer != PropagationTransfer::Custom)
    throw InvalidInput("propagate: unknown PropagationTransfer value");
  if (options_.blend != PropagationBlend::Matrix && options_.blend != PropagationBlend::Decomposed)
    throw InvalidInput("propagate: unknown PropagationBlend value");
  if (std::string why = check_time_factor(options_.geodesic.time_factor); !why.empty())
    throw InvalidInput("propagate: geodesic.time_factor: " + why);
}

void TransformationPropagation::do_prepare(const Positions& P, const Faces& F, const Region& region) {
  const int n = static_cast<int>(P.rows()), nh = region.num_handles();
  Eigen::MatrixXd S = raw_fields(P, F, region, options_.field, options_.geodesic);

  // Transfer function on free vertices only: constrained vertices keep exactly 1 / 0.
  if (options_.transfer != PropagationTransfer::Linear) {
    for (int i = 0; i < n; ++i) {
      if (!region.is_free(i)) continue;
      for (int k = 0; k < nh; ++k) {
        const double s = S(i, k);
        double v;
        if (options_.transfer == PropagationTransfer::SmoothStep) {
          v = s * s * (3.0 - 2.0 * s);
        } else {
          v = options_.custom_transfer(s);
          if (!(v >= 0.0 && v <= 1.0))
            throw InvalidInput("propagate: custom_transfer(" + format_number(s) + ") = " + format_number(v) +
                               " at vertex " + std::to_string(i) + " (handle " + std::to_string(k) +
                               "); a transfer function must map [0, 1] into [0, 1]");
        }
        S(i, k) = v;
      }
    }
  }
  // Keep every vertex a combination of p and the T_k(p) with weights summing to at most 1.
  for (int i = 0; i < n; ++i) {
    const double sum = S.row(i).sum();
    if (sum > 1.0) S.row(i) /= sum;
  }

  std::vector<Vec3> centroids(nh, Vec3::Zero());
  std::vector<int> counts(nh, 0);
  for (int i = 0; i < n; ++i) {
    const int k = region.handle_of(i);
    if (k < 0) continue;
    centroids[k] += P.row(i).transpose();
    ++counts[k];
  }
  for (int k = 0; k < nh; ++k) centroids[k] /= counts[k];  // validate() guarantees non-empty handles

  rest_ = P;
  weights_ = std::move(S);
  centroids_ = std::move(centroids);
  frames_.assign(nh, HandleFrame{});
}

void TransformationPropagation::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  const int nh = static_cast<int>(transforms.size());
  const bool decomposed = options_.blend == PropagationBlend::Decomposed;
  for (int k = 0; k < nh; ++k) {
    HandleFrame& f = frames_[k];
    const Mat3 A = transforms[k].topLeftCorner<3, 3>();
    f.linear_minus_identity = A - Mat3::Identity();
    f.translation = transforms[k].topRightCorner<3, 1>();
    if (!decomposed) continue;
    f.centroid = centroids_[k];
    f.centroid_motion = A * f.centroid + f.translation - f.centroid;
    if (A == Mat3::Identity()) {
      f.stretch_minus_identity.setZero();
      f.axis = Vec3::UnitX();
      f.angle = 0;
      continue;
    }
    // A = R S with det R = +1; a reflection stays in S (core/rotation.h).
    const PolarDecomposition polar = polar_decomposition(A);
    const Mat3& R = polar.rotation;
    f.stretch_minus_identity = polar.stretch - Mat3::Identity();
    const Eigen::AngleAxisd rotation(R);  // angle in [0, π]: the shortest arc, as slerp takes it
    f.axis = rotation.axis();
    f.angle = rotation.angle();
  }

  const Eigen::Index n = rest_.rows();
  parallel_for_chunks(n, [&](long b, long e) {
    for (long i = b; i < e; ++i) {
      const Vec3 p = rest_.row(i).transpose();
      Vec3 d = Vec3::Zero();
      for (int k = 0; k < nh; ++k) {
        const double s = weights_(i, k);
        if (s == 0.0) continue;
        const HandleFrame& f = frames_[k];
        if (s == 1.0) {
          d += f.linear_minus_identity * p + f.translation;  // T(p) − p, exactly T on the handle
        } else if (!decomposed) {
          d += s * (f.linear_minus_identity * p + f.translation);  // s·T(p) + (1 − s)·p − p
        } else {
          const Vec3 r = p - f.centroid;
          const Vec3 w = r + s * (f.stretch_minus_identity * r);
          // slerp(I, R, s) applied to w: rotation by s·θ about the axis (Rodrigues).
          const double phi = s * f.angle, c = std::cos(phi), sn = std::sin(phi);
          const Vec3 rotated = c * w + sn * f.axis.cross(w) + ((1.0 - c) * f.axis.dot(w)) * f.axis;
          d += s * f.centroid_motion + (rotated - r);
        }
      }
      out.row(i) = (p + d).transpose();
    }
  });
}

}  // namespace msd
