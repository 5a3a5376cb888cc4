#pragma once
//! \file How much the edges around a region's free vertices changed length: the measure of the Laplacian
//! editing frame check (seed 9.4.2, the linearised rotations' scaling) and of the Fig. 9.16 tests.

#include <cmath>
#include <utility>
#include <vector>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/region.h"
#include "msdeform/core/types.h"

namespace msd {

//! The edges with at least one free end and non-zero rest length, with those rest lengths.
struct FreeEdgeLengths {
  std::vector<std::pair<int, int>> edges;
  std::vector<double> rest;

  FreeEdgeLengths() = default;
  //! P #V×3 rest positions, F #F×3 triangles, region #V codes.
  FreeEdgeLengths(const Positions& P, const Faces& F, const Region& region) {
    const VertexAdjacency adjacency = vertex_adjacency(F, static_cast<int>(P.rows()));
    for (int i = 0; i < adjacency.num_vertices(); ++i)
      for (const int* j = adjacency.begin(i); j != adjacency.end(i); ++j) {
        const double length = (P.row(i) - P.row(*j)).norm();
        if (i < *j && (region.is_free(i) || region.is_free(*j)) && length > 0) {
          edges.emplace_back(i, *j);
          rest.push_back(length);
        }
      }
  }

  //! exp(mean |log(ℓ'/ℓ)|) over the edges for deformed positions X (#V×3): 1 when no edge changed
  //! length (and when there are no edges); a collapsed edge counts as infinitely scaled.
  double mean_scale(const Positions& X) const {
    if (edges.empty()) return 1;
    double sum = 0;
    for (size_t e = 0; e < edges.size(); ++e)
      sum += std::abs(std::log((X.row(edges[e].first) - X.row(edges[e].second)).norm() / rest[e]));
    return std::exp(sum / static_cast<double>(edges.size()));
  }
};

}  // namespace msd
