#include "msdeform/decomposition/subdivision_hierarchy.h"

#include <cstring>
#include <string>
#include <unordered_map>

#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/solver.h"

namespace msd {
namespace {

using RowMajorMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
  h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
  return h * 0xff51afd7ed558ccdull;
}

Region map_region(const Region& fine_region, const std::vector<int>& coarse_to_fine, long num_fine,
                  const char* who) {
  if (fine_region.num_vertices() != num_fine)
    throw InvalidInput(std::string(who) + ": the region has " + std::to_string(fine_region.num_vertices()) +
                       " vertex labels but the fine mesh has " + std::to_string(num_fine) + " vertices");
  std::vector<int> codes(coarse_to_fine.size());
  for (size_t i = 0; i < codes.size(); ++i) codes[i] = fine_region.code(coarse_to_fine[i]);
  Region coarse = Region::from_codes(std::move(codes));
  std::vector<int> count(fine_region.num_handles(), 0);
  for (int c : coarse.codes())
    if (c >= Region::kFirstHandle) ++count[c - Region::kFirstHandle];
  for (int h = 0; h < fine_region.num_handles(); ++h)
    if (count[h] == 0)
      throw InvalidInput(
          std::string(who) + ": handle " + std::to_string(h) +
          " has no vertex on the coarse mesh (it lies between coarse vertices); enlarge the handle "
          "or use a finer control mesh");
  return coarse;
}

}  // namespace

std::vector<int> coarse_to_fine_vertices(const LoopRefinement& refinement) {
  const RowMajorMatrix linear = refinement.linear;
  std::vector<int> map(linear.cols(), -1);
  for (Eigen::Index i = 0; i < linear.rows(); ++i) {
    if (linear.outerIndexPtr()[i + 1] - linear.outerIndexPtr()[i] != 1) continue;
    RowMajorMatrix::InnerIterator it(linear, i);
    if (it.value() == 1.0 && map[it.col()] < 0) map[it.col()] = static_cast<int>(i);
  }
  for (size_t j = 0; j < map.size(); ++j)
    if (map[j] < 0)
      throw InvalidInput("coarse_to_fine_vertices: coarse vertex " + std::to_string(j) +
                         " has no fine vertex-child (no linear stencil row equals e_" + std::to_string(j) +
                         "); is this a uniform refinement of the coarse mesh?");
  return map;
}

Region coarse_region(const Region& fine_region, const LoopRefinement& refinement) {
  return map_region(fine_region, coarse_to_fine_vertices(refinement), refinement.linear.rows(),
                    "coarse_region");
}

void SubdivisionHierarchy::build(const Positions& fine_S, const Faces& fine_F, const Positions& coarse,
                                 const Faces& coarse_F, const LoopRefinement& refinement,
                                 const SubdivisionHierarchyOptions& options) {
  static const char* who = "SubdivisionHierarchy::build";
  num_fine_ = 0;
  const Eigen::Index nf = fine_S.rows(), nc = coarse.rows();
  if (refinement.loop.rows() != nf || refinement.loop.cols() != nc || refinement.linear.rows() != nf ||
      refinement.linear.cols() != nc)
    throw InvalidInput(std::string(who) + ": the stencil matrices are " +
                       std::to_string(refinement.loop.rows()) + "x" + std::to_string(refinement.loop.cols()) +
                       " but the surface has " + std::to_string(nf) + " fine and " + std::to_string(nc) +
                       " coarse vertices");
  if (fine_F.rows() != refinement.faces.rows())
    throw InvalidInput(std::string(who) + ": the fine mesh has " + std::to_string(fine_F.rows()) +
                       " faces, the refinement " + std::to_string(refinement.faces.rows()));
  for (Eigen::Index f = 0; f < fine_F.rows(); ++f)
    if (fine_F.row(f) != refinement.faces.row(f))
      throw InvalidInput(
          std::string(who) + ": fine face " + std::to_string(f) +
          " differs from the refinement's connectivity; S must be the refined mesh, unreordered");
  if (coarse_F.rows() << (2 * refinement.levels) != fine_F.rows())
    throw InvalidInput(std::string(who) + ": " + std::to_string(coarse_F.rows()) + " coarse faces refined " +
                       std::to_string(refinement.levels) + " times cannot give " +
                       std::to_string(fine_F.rows()) +
                       " fine faces; coarse_F is not the mesh the refinement was made from");
  check_mesh_arrays(coarse, coarse_F, who);
  check_mesh_arrays(fine_S, Faces(), who);

  coarse_F_ = coarse_F;
  fine_F_ = fine_F;
  coarse_to_fine_ = coarse_to_fine_vertices(refinement);
  compress_stencils(refinement.loop);
  num_fine_ = nf;  // refine() below needs it

  if (options.control_points == ControlPointFit::Given) {
    control_ = coarse;
  } else {
    const SparseMatrix& A = refinement.loop;
    const SparseMatrix N = SparseMatrix(A.transpose()) * A;
    SparseSPDSolver solver;
    try {
      solver.factor(N);
    } catch (const SolverError& e) {
      num_fine_ = 0;
      if (e.index() < 0) throw SolverError(std::string(who) + ": " + e.what());  // not singular: e.g. out of memory
      throw SolverError(
          std::string(who) + ": the least-squares fit of the control points is singular" +
              (e.index() >= 0 ? " at coarse vertex " + std::to_string(e.index()) : std::string()) +
              "; use ControlPointFit::Given",
          e.index());
    }
    const Eigen::MatrixXd rhs = A.transpose() * fine_S;
    control_ = solver.solve(rhs);
    if (!control_.allFinite()) {
      num_fine_ = 0;
      throw SolverError(std::string(who) + ": the fitted control points are not finite");
    }
  }
  refine(control_, base_);
  details_ = fine_S - base_;
}

void SubdivisionHierarchy::compress_stencils(const SparseMatrix& loop) {
  const RowMajorMatrix R = loop;
  const long n = R.rows();
  row_pattern_.resize(n);
  row_base_.resize(n);
  pattern_start_.assign(1, 0);
  pattern_weight_.clear();
  pattern_offset_.clear();
  std::unordered_multimap<std::uint64_t, std::int32_t> seen;
  const int* outer = R.outerIndexPtr();
  const int* cols = R.innerIndexPtr();
  const double* vals = R.valuePtr();
  for (long i = 0; i < n; ++i) {
    const int b = outer[i], e = outer[i + 1];
    const int first = e > b ? cols[b] : 0;
    std::uint64_t h = static_cast<std::uint64_t>(e - b);
    for (int k = b; k < e; ++k) {
      std::uint64_t bits;
      std::memcpy(&bits, &vals[k], sizeof bits);
      h = mix(mix(h, bits), static_cast<std::uint64_t>(cols[k] - first));
    }
    std::int32_t id = -1;
    for (auto [it, end] = seen.equal_range(h); it != end && id < 0; ++it) {
      const std::int64_t s = pattern_start_[it->second], m = pattern_start_[it->second + 1] - s;
      if (m != e - b) continue;
      bool same = true;
      for (int q = 0; q < m && same; ++q)
        same = pattern_offset_[s + q] == cols[b + q] - first &&
               std::memcmp(&pattern_weight_[s + q], &vals[b + q], sizeof(double)) == 0;
      if (same) id = it->second;
    }
    if (id < 0) {
      id = static_cast<std::int32_t>(pattern_start_.size() - 1);
      for (int k = b; k < e; ++k) {
        pattern_weight_.push_back(vals[k]);
        pattern_offset_.push_back(cols[k] - first);
      }
      pattern_start_.push_back(static_cast<std::int64_t>(pattern_weight_.size()));
      seen.emplace(h, id);
    }
    row_pattern_[i] = id;
    row_base_[i] = first;
  }
}

void SubdivisionHierarchy::refine(const Positions& coarse_deformed, Positions& fine_out) const {
  if (!built()) throw UsageError("SubdivisionHierarchy::refine: call build() first");
  const long nc = static_cast<long>(coarse_to_fine_.size());
  if (coarse_deformed.rows() != nc)
    throw UsageError("SubdivisionHierarchy::refine: " + std::to_string(coarse_deformed.rows()) +
                     " coarse positions for " + std::to_string(nc) + " control points");
  if (!coarse_deformed.allFinite())
    for (long j = 0; j < nc; ++j)
      if (!coarse_deformed.row(j).allFinite())
        throw InvalidInput("SubdivisionHierarchy::refine: control point " + std::to_string(j) +
                           " is not finite");
  if (fine_out.rows() != num_fine_) fine_out.resize(num_fine_, 3);
  const long n = num_fine_;
  const double* c = coarse_deformed.data();  // column-major: x, y, z columns of nc each
  double* out = fine_out.data();
  const std::int32_t* pattern = row_pattern_.data();
  const std::int32_t* base = row_base_.data();
  const std::int64_t* start = pattern_start_.data();
  const double* weight = pattern_weight_.data();
  const std::int32_t* offset = pattern_offset_.data();
  parallel_for_chunks(
      n,
      [&](long b, long e) {
        for (long i = b; i < e; ++i) {
          const std::int64_t s = start[pattern[i]], m = start[pattern[i] + 1] - s;
          const double* w = weight + s;
          const std::int32_t* o = offset + s;
          const double* ci = c + base[i];
          double x = 0, y = 0, z = 0;
          for (std::int64_t q = 0; q < m; ++q) {
            const double* cq = ci + o[q];
            x += w[q] * cq[0];
            y += w[q] * cq[nc];
            z += w[q] * cq[2 * nc];
          }
          out[i] = x;
          out[n + i] = y;
          out[2 * n + i] = z;
        }
      },
      1 << 14);
}

Positions SubdivisionHierarchy::refine(const Positions& coarse_deformed) const {
  Positions out;
  refine(coarse_deformed, out);
  return out;
}

void SubdivisionHierarchy::reconstruct_global(const Positions& coarse_deformed, Positions& fine_out) const {
  refine(coarse_deformed, fine_out);
  fine_out += details_;
}

Region SubdivisionHierarchy::coarse_region(const Region& fine_region) const {
  if (!built()) throw UsageError("SubdivisionHierarchy::coarse_region: call build() first");
  return map_region(fine_region, coarse_to_fine_, num_fine_, "SubdivisionHierarchy::coarse_region");
}

}  // namespace msd
