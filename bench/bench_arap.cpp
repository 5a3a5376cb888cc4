// ARAP (Sorkine & Alexa 2007) on the bumpy plane bent by 120°: prepare time (weights, factorisation,
// rest cells) and time per iteration (local step, global step), with a fixed number of iterations per
// frame (tolerance 0) so the figures compare with libigl's arap_solve and CGAL's
// Surface_mesh_deformation run for the same count.
// Usage: bench_arap [resolution ...]                   (default: 100k 1M)
//        bench_arap quality MESH SEL DEF [spokes|rims]  rigidity and self-intersections after 10..1000 iterations
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/analysis/metrics.h"
#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/edit_case.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/arap.h"

using namespace msd::bench;

namespace {

int quality(const std::string& mesh, const std::string& sel, const std::string& def, msd::ArapEnergy energy) {
  const msd::EditCase c = msd::file_case(mesh, sel, def);
  std::printf("%s: %ld vertices, %ld faces, energy %s\n", mesh.c_str(), long(c.P.rows()), long(c.F.rows()),
              msd::to_string(energy));
  std::printf("%10s %14s %14s %12s %14s %12s\n", "iterations", "rigidity mean", "rigidity p95", "self-isect",
              "handle error", "rel. dE");
  const msd::RigidityMetric rigidity(c.P, c.F);
  int done = 0;
  msd::Positions out = c.P;
  for (int total : {1, 10, 100, 1000}) {
    // Continue from the last result: the local step refits every rotation from the positions, so a
    // new deformer seeded with them runs the same iteration sequence as one long frame.
    msd::ArapOptions o;
    o.energy = energy;
    o.tolerance = 0;
    o.max_iterations = total - done;
    msd::ArapDeformer arap(o);
    const auto t0 = Clock::now();
    arap.prepare(c.P, c.F, c.region);
    if (done == 0) std::printf("prepare %.3f s, clamped weights %d\n", seconds_since(t0), arap.clamped_weights());
    arap.set_initial_guess(out);
    arap.deform(c.transforms, out);
    done = total;
    const msd::RigidityError r = rigidity.measure(out);
    std::printf("%10d %14.4f %14.4f %12d %14.2e %12.2e\n", total, r.stats.mean, r.stats.p95,
                msd::count_self_intersections(out, c.F), msd::handle_error(c.P, out, c.region, c.transforms),
                arap.frame_report().residual);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  if (argc >= 5 && std::string(argv[1]) == "quality")
    return quality(argv[2], argv[3], argv[4],
                   argc > 5 && std::string(argv[5]) == "rims" ? msd::ArapEnergy::SpokesAndRims : msd::ArapEnergy::Spokes);
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"100k", "1M"});
  const int iterations = 10;
  std::printf("Per iteration: plain local/global (anderson 0), (time of %d iterations - time of half as many) / %d.\n"
              "To tolerance: the default options (Anderson 5, tolerance 1e-6 diagonals) from a cold start.\n",
              2 * iterations, iterations);
  std::printf("%10s %16s %11s %13s %13s %13s %13s %11s %12s\n", "vertices", "energy", "prepare[s]", "iter med[ms]",
              "iter min[ms]", "local[ms/it]", "global[ms/it]", "tol. iters", "tol. time[s]");
  for (const auto& size : sizes) {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(size);
    const msd::Scene scene = msd::make_scene("bend120", options);
    for (msd::ArapEnergy energy : {msd::ArapEnergy::Spokes, msd::ArapEnergy::SpokesAndRims}) {
      msd::ArapOptions o;
      o.energy = energy;
      o.tolerance = 0;
      o.anderson = 0;
      auto t0 = Clock::now();
      msd::ArapDeformer arap(o);
      arap.prepare(scene.P, scene.F, scene.region);
      const double prepare = seconds_since(t0);
      msd::Positions out(scene.P.rows(), 3);
      arap.deform(scene.transforms, out);  // the cold start
      // The marginal cost of an iteration: frames of 2N and N iterations, continuing from the last (a
      // frame also compares the warm with the cold start once), the difference over N.
      std::vector<double> per_iteration;
      double local = 0, global = 0;
      for (int f = 0; f < 5; ++f) {
        double ms[2];
        for (int k : {0, 1}) {
          msd::ArapOptions ok = o;
          ok.max_iterations = (k + 1) * iterations;
          arap = msd::ArapDeformer(ok);
          arap.prepare(scene.P, scene.F, scene.region);
          arap.set_initial_guess(out);
          const auto t = Clock::now();
          arap.deform(scene.transforms, out);
          ms[k] = ms_since(t);
          if (k == 1) local += arap.local_seconds(), global += arap.global_seconds();
        }
        per_iteration.push_back((ms[1] - ms[0]) / iterations);
      }
      std::sort(per_iteration.begin(), per_iteration.end());
      msd::ArapOptions defaults;
      defaults.energy = energy;
      msd::ArapDeformer converging(defaults);
      converging.prepare(scene.P, scene.F, scene.region);
      t0 = Clock::now();
      converging.deform(scene.transforms, out);
      const double to_tolerance = seconds_since(t0);
      std::printf("%10ld %16s %11.2f %13.1f %13.1f %13.1f %13.1f %11d %12.2f\n", long(scene.P.rows()),
                  msd::to_string(energy), prepare, per_iteration[2], per_iteration.front(),
                  1000 * local / (5 * 2 * iterations), 1000 * global / (5 * 2 * iterations),
                  converging.frame_report().iterations, to_tolerance);
      std::fflush(stdout);
    }
  }
  return 0;
}
