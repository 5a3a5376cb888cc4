#pragma once
//! \file Self-intersecting face pairs of a triangle mesh (CGAL Polygon Mesh Processing). This header is
//! CGAL-free; self_intersections.cpp is the only translation unit of msdeform that includes CGAL.

#include <utility>
#include <vector>

#include "msdeform/core/types.h"

namespace msd {

//! Number of pairs of distinct faces of (P #V×3, F #F×3) that intersect other than along what they
//! share: faces with a common edge intersect only if they overlap beyond it, faces with a common vertex
//! only if they meet elsewhere. Exact predicates (CGAL Epick), so touching counts as intersecting.
//! Runs CGAL::Polygon_mesh_processing::self_intersections, in parallel with TBB.
//!
//! Degenerate faces are not tested against others (CGAL creates no bounding box for them, so an
//! intersection that involves one goes unreported): a face with collinear corners, or one that repeats
//! a vertex index, is counted in *degenerate_faces instead and never appears in pairs.
//!
//! pairs, if given, receives the intersecting faces as (f, g) rows of F with f < g, sorted.
//! \throw InvalidInput for a face index out of range, a non-finite coordinate, or a face that cannot be
//! added to a manifold, consistently oriented surface (named by its row; the msd::Mesh loaders already
//! guarantee this for their meshes).
int count_self_intersections(const Positions& P, const Faces& F,
                             std::vector<std::pair<int, int>>* pairs = nullptr,
                             int* degenerate_faces = nullptr);

//! The self-intersecting pairs an edit adds to a rest shape that may intersect itself already (a scan's
//! arm along its torso): a result's pair counts unless both its faces are in a pair at rest or within two
//! rings of one (such contacts slide). A face of a contact at rest pushed through another part counts
//! (third break test: any pair with a face of a rest contact was left out). The constructor counts the
//! rest's pairs once; each count() is one CGAL run.
class AddedSelfIntersections {
 public:
  //! rest: #V×3, F: #F×3. \throw InvalidInput as count_self_intersections, and for a vertex on more than
  //! 10000 faces: CGAL tests the faces around a vertex pairwise (a flat fan of 16000 faces took 45 s per
  //! count, one of 47000 an hour).
  AddedSelfIntersections(const Positions& rest, const Faces& F);
  int rest_pairs() const { return rest_pairs_; }
  //! The pairs of result (#V×3, on F) the edit added; their faces (rows of F, a face once per pair) into
  //! *faces if given. \throw InvalidInput as count_self_intersections.
  int count(const Positions& result, std::vector<int>* faces = nullptr) const;

 private:
  Faces F_;
  int rest_pairs_ = 0;
  std::vector<char> near_contact_;  // per face: in a pair at rest, or within two rings of one
};

}  // namespace msd
