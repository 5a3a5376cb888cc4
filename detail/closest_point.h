#pragma once
//! \file Exact closest points on a triangle mesh. An Embree 3 BVH prunes the search; the distance to
//! each candidate triangle is computed in double precision from our own arrays, so results do not
//! carry Embree's single-precision rounding. All Embree use is hidden in closest_point.cpp.

#include <limits>
#include <memory>
#include <vector>

#include "msdeform/core/types.h"

namespace msd {

//! The closest point of a triangle mesh to a query point.
struct ClosestPoint {
  int face = -1;                    //!< row of F holding the closest triangle; -1 if nothing was found
  Vec3 barycentric = Vec3::Zero();  //!< (α, β, γ) for F(face, 0..2): α + β + γ = 1, each in [0, 1]
  Vec3 point = Vec3::Zero();        //!< α a + β b + γ c
  double squared_distance = std::numeric_limits<double>::infinity();  //!< |query − point|²
};

//! Closest point to p on triangle (a, b, c), by Voronoi regions of vertices, edges and interior
//! (Ericson, Real-Time Collision Detection, 5.1.5). Writes (α, β, γ) with point = α a + β b + γ c.
//! Degenerate (zero-area) triangles are handled as the union of their three edges.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& barycentric);

//! Closest-point queries against one triangle mesh: build once, query many times. query() is
//! const and thread-safe, so several threads may query one object at the same time.
class ClosestPointQuery {
 public:
  ClosestPointQuery();
  //! Same as build(P, F).
  ClosestPointQuery(const Positions& P, const Faces& F);
  ~ClosestPointQuery();
  ClosestPointQuery(ClosestPointQuery&&) noexcept;
  ClosestPointQuery& operator=(ClosestPointQuery&&) noexcept;
  ClosestPointQuery(const ClosestPointQuery&) = delete;
  ClosestPointQuery& operator=(const ClosestPointQuery&) = delete;

  //! Builds the search structure over P (#V by 3) and F (#F by 3); copies both.
  //! \throw InvalidInput if F is empty, has an index out of range, or P has a non-finite coordinate;
  //! Error if Embree cannot create its device or scene.
  void build(const Positions& P, const Faces& F);

  //! True until build() succeeded.
  bool empty() const;
  int num_faces() const;

  //! The exact closest point on the mesh to p (ties between triangles go to either).
  //! max_distance: a distance from p to some point of the mesh (a vertex a face uses, say), so at least the
  //! closest distance. The search starts with that sphere instead of an unbounded one, which prunes it; the
  //! result is the same (a bound that is too small only makes it search again without one).
  //! face_group (#F entries, or null: every face) and group: only faces f with face_group[f] == group are
  //! candidates (e.g. the connected component of the point's own vertex); face = −1 when none is.
  //! \throw UsageError before build().
  ClosestPoint query(const Vec3& p, double max_distance = std::numeric_limits<double>::infinity(),
                     const int* face_group = nullptr, int group = -1) const;

  //! query() for every row of points (#Q by 3), in parallel. \throw UsageError before build().
  std::vector<ClosestPoint> query_all(const Positions& points) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace msd
