#include "msdeform/core/supernodal_tree.h"

#include <cholmod.h>

#include <algorithm>

namespace msd {

bool supernodal_elimination_tree(const cholmod_factor_struct* factor, std::vector<long>& super_of,
                                 std::vector<long>& parent) {
  using Int = SuiteSparse_long;
  const cholmod_factor* L = factor;
  const auto* super = static_cast<const Int*>(L->super);
  const auto* pi = static_cast<const Int*>(L->pi);
  const auto* rows = static_cast<const Int*>(L->s);
  const long ns = static_cast<long>(L->nsuper);
  super_of.resize(L->n);
  for (long s = 0; s < ns; ++s) std::fill(super_of.begin() + super[s], super_of.begin() + super[s + 1], s);
  parent.assign(ns, -1);
  for (long s = 0; s < ns; ++s) {
    const Int ncol = super[s + 1] - super[s];
    if (pi[s + 1] - pi[s] > ncol) {
      parent[s] = super_of[rows[pi[s] + ncol]];
      if (parent[s] <= s) return false;
    }
  }
  return true;
}

std::vector<int> split_elimination_tree(const std::vector<long>& parent, const std::vector<double>& work,
                                        double* parallel_share) {
  const long ns = static_cast<long>(parent.size());
  std::vector<double> subtree(work);  // work in each node's subtree
  std::vector<std::vector<long>> children(ns);
  for (long s = 0; s < ns; ++s)
    if (parent[s] >= 0) subtree[parent[s]] += subtree[s], children[parent[s]].push_back(s);
  double total = 0;
  std::vector<long> frontier;  // roots of disjoint subtrees, split between the two groups
  for (long s = 0; s < ns; ++s)
    if (parent[s] < 0) frontier.push_back(s), total += subtree[s];
  // The larger group's work when the frontier's subtrees are shared out largest first; their groups in
  // *half when given.
  auto halves = [&](const std::vector<long>& roots, std::vector<int>* half) {
    std::vector<long> order(roots.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<long>(i);
    std::sort(order.begin(), order.end(), [&](long a, long b) { return subtree[roots[a]] > subtree[roots[b]]; });
    double load[2] = {0, 0};
    if (half) half->assign(roots.size(), 0);
    for (long i : order) {
      const int h = load[1] < load[0];
      load[h] += subtree[roots[i]];
      if (half) (*half)[i] = h;
    }
    return std::max(load[0], load[1]);
  };
  double above = 0, best = total;
  std::vector<long> best_frontier;
  for (int step = 0; step < 1024 && !frontier.empty(); ++step) {
    const double time = above + halves(frontier, nullptr);
    if (time < best) best = time, best_frontier = frontier;
    const auto largest = std::max_element(frontier.begin(), frontier.end(),
                                          [&](long a, long b) { return subtree[a] < subtree[b]; });
    const long s = *largest;
    frontier.erase(largest);
    above += work[s];
    frontier.insert(frontier.end(), children[s].begin(), children[s].end());
  }
  std::vector<int> group(ns, 2), half;
  halves(best_frontier, &half);
  for (size_t i = 0; i < best_frontier.size(); ++i) group[best_frontier[i]] = half[i];
  for (long s = ns - 1; s >= 0; --s)  // parents before children
    if (group[s] == 2 && parent[s] >= 0) group[s] = group[parent[s]];
  if (parallel_share) {
    double parallel = 0;
    for (long s = 0; s < ns; ++s) parallel += group[s] < 2 ? work[s] : 0;
    *parallel_share = total > 0 ? parallel / total : 0;
  }
  return group;
}

}  // namespace msd
