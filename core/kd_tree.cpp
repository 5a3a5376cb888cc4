#include "msdeform/core/kd_tree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace msd {

KdTree::KdTree(const Positions& P) {
  points_.reserve(P.rows());
  for (Eigen::Index v = 0; v < P.rows(); ++v) points_.push_back({P.row(v).transpose(), static_cast<int>(v)});
  build_tree();
}

KdTree::KdTree(const Positions& P, const std::vector<int>& ids) {
  points_.reserve(ids.size());
  for (int v : ids) points_.push_back({P.row(v).transpose(), v});
  build_tree();
}

void KdTree::build_tree() {
  nodes_.reserve(2 * points_.size() / kLeafSize + 2);
  if (!points_.empty()) build(0, static_cast<int>(points_.size()));
}

KdNearest KdTree::nearest(const Vec3& q) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  KdNearest out;
  out.distance = kInf;
  if (nodes_.empty()) return out;
  double best2 = kInf;
  struct Entry {
    int node;
    double bound2;  // squared distance from q to the node's bounding box
  };
  std::array<Entry, 128> stack;  // one pending sibling per level: depth <= log2(2^31 / kLeafSize) + 1
  int top = 0;
  stack[top++] = {0, box_distance2(nodes_[0], q)};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.bound2 >= best2) continue;
    const Node& n = nodes_[e.node];
    if (n.left < 0) {
      for (int i = n.begin; i < n.end; ++i) {
        const double d2 = (points_[i].position - q).squaredNorm();
        if (d2 < best2) {
          best2 = d2;
          out.index = points_[i].id;
        }
      }
      continue;
    }
    const double dl = box_distance2(nodes_[n.left], q), dr = box_distance2(nodes_[n.right], q);
    // Push the farther child first so the nearer one is searched first and tightens best2.
    if (dl < dr) {
      stack[top++] = {n.right, dr};
      stack[top++] = {n.left, dl};
    } else {
      stack[top++] = {n.left, dl};
      stack[top++] = {n.right, dr};
    }
  }
  out.distance = std::sqrt(best2);
  return out;
}

int KdTree::build(int begin, int end) {
  Vec3 lo = points_[begin].position, hi = lo;
  for (int i = begin + 1; i < end; ++i) {
    lo = lo.cwiseMin(points_[i].position);
    hi = hi.cwiseMax(points_[i].position);
  }
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back({begin, end, -1, -1, lo, hi});
  if (end - begin <= kLeafSize) return id;
  int axis;
  (hi - lo).maxCoeff(&axis);
  const int mid = begin + (end - begin) / 2;
  std::nth_element(points_.begin() + begin, points_.begin() + mid, points_.begin() + end,
                   [axis](const Point& a, const Point& b) { return a.position[axis] < b.position[axis]; });
  const int left = build(begin, mid);
  const int right = build(mid, end);
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

}  // namespace msd
