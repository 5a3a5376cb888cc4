#pragma once
//! \file Union-find over ids 0..n−1, for grouping (mesh pieces, vertex fans, welded vertices).

#include <algorithm>
#include <numeric>
#include <vector>

namespace msd {

//! Union-find with path halving; a root is its set's smallest member (unions link the larger root below
//! the smaller), so "the first" of a set is its root.
class DisjointSets {
 public:
  explicit DisjointSets(int n) : parent_(static_cast<size_t>(n)) { std::iota(parent_.begin(), parent_.end(), 0); }
  int find(int x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<int> parent_;
};

}  // namespace msd
