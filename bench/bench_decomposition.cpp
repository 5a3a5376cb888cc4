// Decomposition S → B on the bumpy plane: the low-pass base (automatic and given detail scale), region fairing (prepare = assembly + factorisation, and one
// re-fair of moved constraints with the stored factor) for each order, and the subdivision hierarchy
// (build with least-squares control points, and the per-frame refine() of coarse positions to full
// resolution).
// Usage: bench_decomposition [--orders=1,2,3] [resolution ...]   (default: 100k 1M)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/solver.h"
#include "msdeform/decomposition/fairing.h"
#include "msdeform/decomposition/low_pass.h"
#include "msdeform/decomposition/subdivision_hierarchy.h"

using namespace msd::bench;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> sizes;
  std::vector<int> orders = {1, 2, 3};
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--orders=", 0) == 0) {
      orders.clear();
      for (char c : arg.substr(9))
        if (c >= '1' && c <= '3') orders.push_back(c - '0');
    } else {
      sizes.push_back(arg);
    }
  }
  if (sizes.empty()) sizes = {"100k", "1M"};
  std::printf("sparse solver: %s\n", msd::SparseSPDSolver::backend().c_str());
  for (const auto& size : sizes) {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(size);
    const msd::Scene scene = msd::make_scene("lift", options);
    std::printf("\nbumpy plane, %ld vertices, %zu free\n", long(scene.P.rows()),
                scene.region.free_vertices().size());
    std::printf("  %-18s %10s %12s %14s\n", "fairing", "unknowns", "prepare[s]", "re-fair[ms]");
    msd::Positions lifted = scene.P;
    for (int v : scene.region.handle_vertices(0))
      lifted.row(v) = msd::transform_point(scene.transforms[0], scene.P.row(v).transpose()).transpose();
    for (int k : orders) {
      msd::FairingOptions fo;
      fo.order = static_cast<msd::FairingOrder>(k);
      msd::RegionFairing fairing;
      auto t0 = Clock::now();
      fairing.prepare(scene.P, scene.F, scene.region, fo);
      const double prepare = ms_since(t0) / 1000;
      msd::Positions out;
      std::vector<double> solves;
      for (int f = 0; f < 5; ++f) {
        t0 = Clock::now();
        fairing.fair(lifted, out);
        solves.push_back(ms_since(t0));
      }
      std::printf("  %-18s %10zu %12.2f %14.1f\n", msd::to_string(fo.order), fairing.free_vertices().size(),
                  prepare, median(solves));
      std::fflush(stdout);
    }

    // The default multi-scale base: low-pass at the automatic detail scale (one factorisation per
    // candidate of the bisection), and at a given scale (one factorisation).
    for (const double given : {0.0, 0.15}) {
      msd::LowPassOptions lo;
      lo.detail_scale = given;
      msd::LowPassReport report;
      const auto t_lp = Clock::now();
      msd::low_pass_base(scene.P, scene.F, lo, &report);
      std::printf("  low-pass %-9s scale %.3g, %zu candidates, %.2f s, fold ratio %.3g\n",
                  given > 0 ? "(given)" : "(auto)", report.detail_scale, report.candidates.size(),
                  seconds_since(t_lp), report.check.max_fold_ratio);
      std::fflush(stdout);
    }

    msd::SubdivisionHierarchy hierarchy;
    auto t0 = Clock::now();
    hierarchy.build(scene.P, scene.F, scene.coarse_P, scene.coarse_F, scene.refinement);
    const double build = ms_since(t0) / 1000;
    msd::Positions coarse = hierarchy.control_points(), fine(scene.P.rows(), 3);
    std::vector<double> frames;
    for (int f = 0; f < 100; ++f) {
      for (int v = 0; v < coarse.rows(); ++v)  // an animated lift of the coarse handle side
        coarse(v, 2) = hierarchy.control_points()(v, 2) + (coarse(v, 0) > 0.8 ? 0.3 * (f + 1) / 100.0 : 0.0);
      t0 = Clock::now();
      hierarchy.refine(coarse, fine);
      frames.push_back(ms_since(t0));
    }
    std::sort(frames.begin(), frames.end());
    std::printf(
        "  subdivision: %d coarse -> %d fine (%d levels), %ld stencil non-zeros in %ld patterns (%ld "
        "weights)\n",
        hierarchy.num_coarse_vertices(), hierarchy.num_fine_vertices(), scene.refinement.levels,
        long(scene.refinement.loop.nonZeros()), hierarchy.num_stencil_patterns(),
        hierarchy.num_stored_weights());
    std::printf("  %-18s %12s %14s %14s\n", "", "build[s]", "refine med[ms]", "refine min[ms]");
    std::printf("  %-18s %12.2f %14.2f %14.2f\n", "subdivision", build, frames[frames.size() / 2],
                frames.front());
    std::fflush(stdout);
  }
  return 0;
}
