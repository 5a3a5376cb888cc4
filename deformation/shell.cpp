#include "msdeform/deformation/shell.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "msdeform/core/checks.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/parallel.h"

namespace msd {

ShellDeformer::ShellDeformer(ShellOptions options) : options_(options) {
  if (!(options_.ks >= 0) || !(options_.kb >= 0) || !std::isfinite(options_.ks) ||
      !std::isfinite(options_.kb) || options_.ks + options_.kb <= 0) {
    char got[100];
    std::snprintf(got, sizeof got, "(got ks = %.6g, kb = %.6g)", options_.ks, options_.kb);
    throw InvalidInput(std::string("shell: stiffnesses must be finite and non-negative with ks + kb > 0 ") +
                       got);
  }
}

DeformerTraits ShellDeformer::traits() const {
  DeformerTraits t;
  t.vertex_targets = true;
  t.reproduces_rigid_motions = false;
  return t;
}

void ShellDeformer::do_prepare(const Positions& P, const Faces& F, const Region& region) {
  rest_ = P;
  const int nv = static_cast<int>(rest_.rows()), nh = region.num_handles();
  // Only the ratio ks : kb shapes the displacements, so stiffnesses such as 1e-320 or 1e308 must neither
  // underflow nor overflow Q: one of them zero, the other is taken as 1; otherwise both are scaled by the
  // power of four that brings the larger near 1, which scales Q, its Cholesky factor and the right-hand
  // sides exactly (the same bits as unscaled).
  const int exponent = std::ilogb(std::max(options_.ks, options_.kb)) & ~1;  // even, rounded down
  const double ks = options_.kb == 0 ? 1.0 : std::ldexp(options_.ks, -exponent);
  const double kb = options_.ks == 0 ? 1.0 : std::ldexp(options_.kb, -exponent);
  // (9.7) in symmetric form: −ks·L + kb·L² (L = M⁻¹W) multiplied by M is ks·Q₁ + kb·Q₂. The Laplacian and
  // Q are released before the factorisation, the peak of memory.
  SparseMatrix Q(nv, nv);
  {
    const LaplaceOperator lap = cotan_laplacian(rest_, F);
    if (ks > 0) Q = ks * polyharmonic_matrix(lap, 1);
    if (kb > 0) Q += kb * polyharmonic_matrix(lap, 2);
  }
  constrained_ = region.constrained_vertices();
  try {
    system_.prepare(std::move(Q), constrained_);
  } catch (const SolverError& e) {
    if (e.index() < 0) throw SolverError(std::string("shell: ") + e.what());  // not singular: e.g. out of memory
    throw SolverError("shell: the system is singular near vertex " + std::to_string(e.index()) +
                          " (a degenerate neighbourhood, or a free vertex whose faces all have zero area)",
                      e.index());
  }
  // Basis: handle k's vertices carry (p, 1) in its 4 columns, everything else constrained is 0; the free
  // rows follow from one solve per handle with 4 right-hand sides (the two-core substitution), written
  // into its columns. Solving all 4h columns at once held them about five times over (right-hand sides,
  // solution, the solver's copies): 3.1 GB for 1,940 handles on 9,409 vertices.
  handle_of_.assign(nv, -1);
  std::vector<std::vector<int>> rows_of(nh);  // rows of `known` (constrained vertices) in each handle
  for (size_t c = 0; c < constrained_.size(); ++c) {
    const int v = constrained_[c], k = region.handle_of(v);
    handle_of_[v] = k;
    if (k >= 0) rows_of[k].push_back(static_cast<int>(c));
  }
  fields_.resize(nv, 3 + 4 * nh);
  fields_.leftCols(3) = rest_;
  Eigen::MatrixXd known = Eigen::MatrixXd::Zero(constrained_.size(), 4), basis;
  for (int k = 0; k < nh; ++k) {
    for (int c : rows_of[k]) known.row(c) << rest_.row(constrained_[c]), 1.0;
    system_.solve(known, basis);
    fields_.middleCols(3 + 4 * k, 4) = basis;
    for (int c : rows_of[k]) known.row(c).setZero();
  }
  if (!fields_.allFinite()) throw SolverError("shell: basis fields are not finite (ill-conditioned system)");
  frame_matrix_.resize(4 * nh, 3);
}

void ShellDeformer::do_deform(const std::vector<Mat4>& transforms, Positions& out) {
  const int nh = static_cast<int>(transforms.size());
  for (int k = 0; k < nh; ++k) {
    Eigen::Matrix<double, 3, 4> M = transforms[k].topRows<3>();
    M.leftCols<3>() -= Mat3::Identity();
    frame_matrix_.middleRows<4>(4 * k) = M.transpose();
  }
  const double* f = fields_.data();
  const long n = fields_.rows();
  double* o = out.data();
  const double* m = frame_matrix_.data();  // column-major (4h) x 3
  const long mrows = frame_matrix_.rows();
  // One pass per coordinate and chunk: handle 0's columns are fused with the rest position (one write per
  // output), further handles add theirs. A chunk's columns stay in L2 across the coordinates. A column
  // whose weight is zero is not read: a translation reads one column of four, and a coordinate no handle
  // moves is the rest position (the terms left out are ±0, so every sum is the same value).
  // Each computed coordinate of a chunk is checked finite while it is in L2 (a copied one is the rest
  // position, checked by prepare()), so end_frame() does not read B' again.
  std::atomic<bool> finite{true};
  parallel_for_chunks(n, [&](long begin, long end) {
    for (int d = 0; d < 3; ++d) {
      double* od = o + d * n;
      const double* rest = f + d * n;
      bool computed = false;
      for (int k = 0; k < nh; ++k) {
        const double* w = m + d * mrows + 4 * k;
        const double* c[4];
        double cw[4];
        int nc = 0;
        for (int j = 0; j < 4; ++j)
          if (w[j] != 0) {
            c[nc] = f + (3 + 4 * k + j) * n;
            cw[nc++] = w[j];
          }
        computed = computed || nc > 0;
        const double* base = k == 0 ? rest : od;
        switch (nc) {
          case 0:
            if (k == 0) std::copy(rest + begin, rest + end, od + begin);
            break;
          case 1:
            for (long i = begin; i < end; ++i) od[i] = base[i] + c[0][i] * cw[0];
            break;
          case 2:
            for (long i = begin; i < end; ++i) od[i] = base[i] + c[0][i] * cw[0] + c[1][i] * cw[1];
            break;
          case 3:
            for (long i = begin; i < end; ++i)
              od[i] = base[i] + c[0][i] * cw[0] + c[1][i] * cw[1] + c[2][i] * cw[2];
            break;
          default:
            for (long i = begin; i < end; ++i)
              od[i] = base[i] + c[0][i] * cw[0] + c[1][i] * cw[1] + c[2][i] * cw[2] + c[3][i] * cw[3];
        }
      }
      if (computed && !all_finite(od + begin, end - begin)) finite = false;
    }
  }, 1 << 14);
  if (finite) set_output_checked_finite();  // else end_frame() names the first non-finite vertex
}

void ShellDeformer::do_deform_to(const Positions& targets, Positions& out) {
  Positions d = targets;
  for (size_t c = 0; c < constrained_.size(); ++c) d.row(c) -= rest_.row(constrained_[c]);
  Eigen::MatrixXd x;
  system_.solve(d, x);
  out = rest_ + x;
}

void ShellDeformer::deform_by_solve(const std::vector<Mat4>& transforms, Positions& out) {
  Positions check;
  deform(transforms, check);  // validates the frame exactly like deform()
  std::vector<int> handle_of(constrained_.size());
  for (size_t c = 0; c < constrained_.size(); ++c) handle_of[c] = handle_of_[constrained_[c]];
  Positions targets;
  affine_targets(rest_, constrained_, handle_of, transforms, targets);
  deform_to(targets, out);
}

}  // namespace msd
