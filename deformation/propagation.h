#pragma once
//! \file Transformation propagation (seed 9.1): a scalar field s, 1 on a handle and 0 on the fixed part,
//! damps the handle's transform across the support region, p' = s·T(p) + (1 − s)·p. The field comes from
//! Euclidean or geodesic distances (9.1) or is harmonic (9.2); a transfer function can reshape it.
//! The geodesic field uses core/geodesics.h (heat method), the Euclidean one core/kd_tree.h.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "msdeform/core/geodesics.h"
#include "msdeform/deformation/deformer.h"

namespace msd {

//! How the blending field s is built (seed 9.1).
enum class PropagationField {
  Euclidean,  //!< (9.1) with straight-line distances to the nearest fixed / handle vertex (exact: core/kd_tree.h)
  Geodesic,   //!< (9.1) with surface distances from the heat method (HeatGeodesics, core/geodesics.h)
  Harmonic,   //!< (9.2): Δs = 0 on free vertices, s = 1 on the handle, 0 on the fixed part
};

//! How a vertex with weight s applies its handle's transform T(x) = A x + t.
enum class PropagationBlend {
  //! The seed's formula: p' = s·T(p) + (1 − s)·p, i.e. the matrix entries are interpolated. A rotation
  //! then moves intermediate vertices along chords, shrinking them towards the rotation axis.
  Matrix,
  //! Components damped separately (seed 9.1, after Pauly et al. 2003). With c the handle's rest centroid
  //! (mean of its vertices), write T(x) = c + τ + A (x − c), τ = T(c) − c, and A = R·S by polar
  //! decomposition (SVD A = U Σ Vᵀ, R = U D Vᵀ, S = V D Σ Vᵀ, D = diag(1, 1, ±1) so that det R = +1;
  //! for a reflection S keeps the negative eigenvalue). Then
  //!   p' = c + s·τ + slerp(I, R, s) · (I + s·(S − I)) · (p − c),
  //! slerp from the identity along the shortest arc: rotation by s·θ about R's axis (θ ∈ [0, π]).
  //! Rotations about the handle centroid turn every vertex about that point by s·θ (no chords); s = 1
  //! gives T exactly, s = 0 the identity.
  Decomposed,
};

//! The transfer function t: [0,1] → [0,1] applied to s on free vertices (seed 9.1, Pauly et al. 2003).
enum class PropagationTransfer {
  Linear,      //!< t(s) = s
  SmoothStep,  //!< t(s) = 3s² − 2s³: zero slope at both ends, so the blend meets the handle and the fixed part C¹
  Custom,      //!< PropagationOptions::custom_transfer
};

//! The raw propagation field of one handle on the vertices of (P #V×3, F #F×3) (no transfer function): #V values in
//! [0, 1], exactly 1 on handle `handle`, exactly 0 on fixed vertices and on the other handles.
//! Several handles: handle k's field treats the other handles like the fixed part (distance fields use
//! dist_F = distance to fixed ∪ other handles in (9.1); the harmonic field is 0 on them in (9.2)).
//! Distance fields: a vertex with no zero-set vertex reachable gets 1 (e.g. one handle and no fixed
//! part: the whole mesh moves rigidly), one that cannot reach the handle gets 0. The harmonic field is
//! clamped to [0, 1] (the discrete maximum principle can fail by round-off, or by more where cotan
//! weights are negative).
//! \throw InvalidInput / TopologyError from Region::validate, InvalidInput if handle is not in
//! [0, region.num_handles()); SolverError if a system is singular.
Eigen::VectorXd propagation_field(const Positions& P, const Faces& F, const Region& region, PropagationField field,
                                  int handle = 0);

struct PropagationOptions {
  PropagationField field = PropagationField::Harmonic;
  PropagationBlend blend = PropagationBlend::Matrix;
  PropagationTransfer transfer = PropagationTransfer::Linear;
  //! Used when transfer == Custom: must map [0, 1] into [0, 1] (checked at every free vertex in prepare;
  //! handle and fixed vertices stay exactly 1 and 0 whatever t(1) and t(0) are). Called sequentially.
  std::function<double(double)> custom_transfer;
  HeatGeodesicsOptions geodesic;  //!< for field == Geodesic
};

//! Transformation propagation as a Deformer ("propagate"). prepare() builds one field per handle
//! (propagation_field), applies the transfer function on free vertices, and where the weights of a
//! vertex sum above 1 (possible for distance fields with 3+ handles, or a custom transfer) divides them
//! by their sum, so every vertex stays an affine combination of p and the T_k(p) with weights in [0, 1].
//! A frame moves each vertex by the weighted sum of its handles' displacements:
//!   p' = p + Σ_k (T_k^{s_k}(p) − p),  T^s(p) = s·T(p) + (1 − s)·p for Matrix, as documented for Decomposed;
//! with one handle this is the seed's formula. Frames are O(#V·#handles), parallel and allocation-free.
class TransformationPropagation : public Deformer {
 public:
  //! \throw InvalidInput if transfer is Custom without custom_transfer, custom_transfer is set with
  //! another transfer (it would be ignored), or time_factor is not in [1e-6, 1e6].
  explicit TransformationPropagation(PropagationOptions options = {});
  const std::string& name() const override { return name_; }
  //! Surface, linear, exact constraints, reproduces rigid motions; affine handles only; the cotan Laplacian
  //! for the harmonic and geodesic fields only.
  DeformerTraits traits() const override {
    DeformerTraits t;
    t.cotan_laplacian = options_.field != PropagationField::Euclidean;
    return t;
  }
  const PropagationOptions& options() const { return options_; }

  //! #V by #handles weights used per frame: column k is handle k's field after the transfer function
  //! and the sum-to-at-most-1 normalisation (empty before prepare).
  const Eigen::MatrixXd& fields() const { return weights_; }

 protected:
  //! \throw InvalidInput for a custom transfer value outside [0, 1] (naming the vertex and value);
  //! SolverError if a field's system is singular.
  void do_prepare(const Positions& P, const Faces& F, const Region& region) override;
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) override;

 private:
  // Per-frame data of one handle, computed once per frame and read per vertex.
  struct HandleFrame {
    Mat3 linear_minus_identity;   // A − I
    Vec3 translation;             // t
    Vec3 centroid;                // c, rest centroid of the handle
    Vec3 centroid_motion;         // τ = T(c) − c
    Mat3 stretch_minus_identity;  // S − I
    Vec3 axis;                    // unit rotation axis of R
    double angle = 0;             // rotation angle of R, in [0, π]
  };

  std::string name_ = "propagate";
  PropagationOptions options_;
  Positions rest_;
  Eigen::MatrixXd weights_;            // #V by h
  std::vector<Vec3> centroids_;        // h rest centroids
  std::vector<HandleFrame> frames_;    // h, refilled per frame
};

}  // namespace msd
