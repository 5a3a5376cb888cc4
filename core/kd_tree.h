#pragma once
//! \file Exact nearest-neighbour queries among 3D points: a balanced k-d tree (median split on the widest
//! axis, leaves of up to 8 points, bounding boxes per node). Used for Euclidean distance fields
//! (deformation/propagation.h); any module may use it for closest-vertex look-ups.

#include <vector>

#include "msdeform/core/types.h"

namespace msd {

//! The answer of KdTree::nearest().
struct KdNearest {
  int index = -1;        //!< the nearest point's id (a row of P), -1 for an empty tree
  double distance = 0;   //!< its Euclidean distance to the query (+∞ for an empty tree)
};

//! A k-d tree over a subset of the rows of P. Build O(n log n); a query is exact (no approximation
//! factor), O(log n) for well-spread points, and allocates nothing. Queries are const and may run in
//! parallel.
class KdTree {
 public:
  //! All rows of P (#V by 3).
  explicit KdTree(const Positions& P);
  //! The rows `ids` of P (#V by 3). Ids are not checked against P (the caller's region is validated).
  KdTree(const Positions& P, const std::vector<int>& ids);

  //! Distance from q to the nearest stored point (+∞ for an empty tree).
  double nearest_distance(const Vec3& q) const { return nearest(q).distance; }
  //! The nearest stored point to q and its distance; on ties, one of the nearest.
  KdNearest nearest(const Vec3& q) const;

  int size() const { return static_cast<int>(points_.size()); }

 private:
  static constexpr int kLeafSize = 8;
  struct Point {
    Vec3 position;
    int id;
  };
  struct Node {
    int begin, end;
    int left = -1, right = -1;  // children; left < 0 for a leaf
    Vec3 lo, hi;                // bounding box of the node's points
  };

  static double box_distance2(const Node& n, const Vec3& q) {
    return (n.lo - q).cwiseMax(q - n.hi).cwiseMax(0.0).squaredNorm();
  }
  void build_tree();
  int build(int begin, int end);

  std::vector<Point> points_;
  std::vector<Node> nodes_;
};

}  // namespace msd
