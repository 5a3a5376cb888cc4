// Shell deformation (seed 9.2) on the lift scene: prepare (assembly, factorisation, basis) and per-frame
// time of the precomputed-basis path, against one back-substitution per frame.
// Usage: bench_shell [resolution ...]   (default: 100k 1M)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "core/memory.h"
#include "core/scenes.h"
#include "deformation/shell.h"

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
}  // namespace

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  std::vector<std::string> sizes;
  for (int i = 1; i < argc; ++i) sizes.emplace_back(argv[i]);
  if (sizes.empty()) sizes = {"100k", "1M"};
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
    std::vector<double> frames;
    for (int f = 0; f < 60; ++f) {
      msd::Mat4 T = scene.transforms[0];
      T(2, 3) *= (f + 1) / 60.0;  // an animated lift
      t0 = Clock::now();
      shell.deform({T}, out);
      frames.push_back(ms_since(t0));
    }
    std::sort(frames.begin(), frames.end());
    t0 = Clock::now();
    shell.deform_by_solve(scene.transforms, out);
    const double solve = ms_since(t0);
    std::printf("%10ld %12.2f %14.2f %14.2f %14.1f\n", long(scene.P.rows()), prepare, frames[frames.size() / 2],
                frames.front(), solve);
    std::fflush(stdout);
  }
  return 0;
}
