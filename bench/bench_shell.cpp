// Shell deformation (seed 9.2) on the lift scene: prepare (assembly, factorisation, basis) and per-frame
// time of the precomputed-basis path, against one back-substitution per frame.
// Usage: bench_shell [resolution ...]   (default: 100k 1M)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/shell.h"

using namespace msd::bench;


int main(int argc, char** argv) {
  msd::retain_freed_memory();
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"100k", "1M"});
  std::printf("%10s %12s %14s %14s %14s\n", "vertices", "prepare[s]", "frame med[ms]", "frame min[ms]", "re-solve[ms]");
  for (const auto& size : sizes) {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(size);
    const msd::Scene scene = msd::make_scene("lift", options);
    const msd::Mesh mesh = msd::make_mesh(scene.P, scene.F);
    msd::ShellDeformer shell;
    auto t0 = Clock::now();
    shell.prepare(mesh, scene.region);
    const double prepare = ms_since(t0) / 1000;
    msd::Positions out(scene.P.rows(), 3);
    std::vector<msd::Mat4> T = scene.transforms;
    const double lift = T[0](2, 3);
    const auto frames = time_frames(60, [&](int f) {
      T[0](2, 3) = lift * (f + 1) / 60.0;  // an animated lift
      shell.deform(T, out);
    });
    t0 = Clock::now();
    shell.deform_by_solve(scene.transforms, out);
    const double solve = ms_since(t0);
    std::printf("%10ld %12.2f %14.2f %14.2f %14.1f\n", long(scene.P.rows()), prepare, frames[frames.size() / 2],
                frames.front(), solve);
    std::fflush(stdout);
  }
  return 0;
}
