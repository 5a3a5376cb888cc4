#pragma once
//! \file The split of a supernodal elimination tree between two threads, shared by the supernodal
//! factorisation and substitution (internal).

#include <vector>

struct cholmod_factor_struct;

namespace msd {

//! The supernodal elimination tree of L, a supernodal CHOLMOD factor with 64-bit indices: super_of[j] is
//! the supernode holding column j (n entries), parent[s] the supernode holding s's first row below its
//! diagonal block, or -1 (nsuper entries). Returns false when the tree is not postordered (a parent
//! numbered before its child), as every postordered analysis numbers each subtree contiguously, parents
//! last.
bool supernodal_elimination_tree(const cholmod_factor_struct* L, std::vector<long>& super_of,
                                 std::vector<long>& parent);

//! Splits a postordered elimination forest (parent[s] > s, or -1 at a root) whose node s costs work[s]
//! into two groups of disjoint subtrees of about equal work, which can be processed in parallel, and the
//! rest above them. Roots are moved above the split, the largest subtree's first, while that shortens the
//! split's time: the work above (done on one thread) plus the larger of the two groups' work. Returns the
//! group of every node: 0 or 1 for the two groups, 2 above the split. Stores the share of the work in
//! groups 0 and 1 in *parallel_share when given.
std::vector<int> split_elimination_tree(const std::vector<long>& parent, const std::vector<double>& work,
                                        double* parallel_share = nullptr);

}  // namespace msd
