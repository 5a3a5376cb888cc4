// Assembly and factorisation of the bi-Laplacian system on the free vertices of the lift scene, then the
// 3-column substitution of a frame-time solve against its memory floor.
// Usage: bench_factorisation [resolution ...]   (default: 10k 100k 1M)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/solver.h"

using namespace msd::bench;


int main(int argc, char** argv) {
  msd::retain_freed_memory();
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"10k", "100k", "1M"});
  for (const auto& size : sizes) {  // every size refused before any work (exit 2, bench_common.h)
    if (size == "-h" || size == "--help") {
      std::printf("usage: bench_factorisation [resolution ...]   (e.g. 10k 100k 1M; default: 10k 100k 1M)\n");
      return 0;
    }
    msd::parse_resolution(size);
  }
  // The frame-time substitution (SparseSPDSolver::solve_ordered, 3 right-hand sides) with the factor of
  // deformation transfer's system, the cotan Laplacian on the free vertices, reading the factor in double
  // and from its single-precision copy (the low-pass preconditioner's solves). The floor: one read of the
  // double factor per pass (forward, back) at the streamed bandwidth, for a factor larger than the caches
  // (a small one is read from them, faster). Its rows are printed after the factorisation's table.
  const double bandwidth = triad_gigabytes_per_second();
  std::vector<std::string> substitution_rows;
  std::printf("backend: %s\n", msd::SparseSPDSolver::backend().c_str());
  std::printf("%10s %10s %10s %10s %11s %10s %10s %10s %12s\n", "vertices", "free", "cotan[s]", "bilap[s]",
              "restrict[s]", "factor[s]", "order[s]", "numeric[s]", "factor nnz");
  for (const auto& size : sizes) {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(size);
    const msd::Scene scene = msd::make_scene("lift", options);
    auto t0 = std::chrono::steady_clock::now();
    const msd::LaplaceOperator lap = msd::cotan_laplacian(scene.P, scene.F);
    const double t_cotan = seconds_since(t0);
    const auto free = scene.region.free_vertices();
    {  // the bi-Laplacian, released before the Laplacian's factor below
      t0 = std::chrono::steady_clock::now();
      const Eigen::VectorXd inv_mass = lap.mass.cwiseInverse();
      const msd::SparseMatrix A = (lap.W * inv_mass.asDiagonal() * lap.W).pruned();
      const double t_bilap = seconds_since(t0);
      t0 = std::chrono::steady_clock::now();
      const msd::SparseMatrix Aff = msd::submatrix(A, free, free);
      const double t_restrict = seconds_since(t0);
      t0 = std::chrono::steady_clock::now();
      msd::SparseSPDSolver solver;
      solver.factor(Aff);
      const double t_factor = seconds_since(t0);
      std::printf("%10ld %10zu %10.3f %10.3f %11.3f %10.3f %10.3f %10.3f %12.3g\n", long(scene.P.rows()),
                  free.size(), t_cotan, t_bilap, t_restrict, t_factor, solver.analyse_seconds(),
                  solver.numeric_seconds(), solver.factor_nonzeros());
      std::fflush(stdout);
    }
    msd::SparseSPDSolver solver;
    solver.factor(msd::SparseMatrix(-msd::submatrix(lap.W, free, free)));
    // Median of 21 solves, each from the same right-hand side (refilled untimed: repeated solves in place
    // would grow the values towards overflow).
    std::vector<double> Y(4 * free.size());
    const auto median_ms = [&] {
      std::vector<double> ms;
      for (int i = 0; i < 21; ++i) {
        std::fill(Y.begin(), Y.end(), 1.0);
        const auto t1 = Clock::now();
        solver.solve_ordered(Y.data(), 3);
        ms.push_back(ms_since(t1));
      }
      std::sort(ms.begin(), ms.end());
      return ms[ms.size() / 2];
    };
    const double in_double = median_ms();
    solver.set_single_precision_solves(true);
    const double in_single = median_ms();
    char row[160];
    std::snprintf(row, sizeof row, "%10ld %10zu %12.3g %11.2f %11.2f %10.2f", long(scene.P.rows()),
                  free.size(), solver.factor_nonzeros(), in_double, in_single,
                  2 * 8 * solver.factor_nonzeros() / (bandwidth * 1e6));
    substitution_rows.push_back(row);
  }
  std::printf("\nsubstitution, 3 columns, cotan Laplacian on the free vertices (streamed %.1f GB/s)\n",
              bandwidth);
  std::printf("%10s %10s %12s %11s %11s %10s\n", "vertices", "unknowns", "factor nnz", "double[ms]",
              "single[ms]", "floor[ms]");
  for (const std::string& row : substitution_rows) std::printf("%s\n", row.c_str());
  return 0;
}
