// Gradient-based editing (seed 9.4.1) and Laplacian editing (9.4.2, implicit and explicit) on the bumpy
// plane bent by 120°: prepare (assembly, fields, factorisation) and time per frame (one back-substitution
// for three columns, or one column of 3#U values for the implicit Laplacian).
// Usage: bench_linear_editing [resolution ...]   (default: 100k 1M)
//        MSD_BENCH_METHODS=gradient,laplacian,laplacian-explicit selects the methods.
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/gradient_editing.h"
#include "msdeform/deformation/laplacian_editing.h"

using namespace msd::bench;

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"100k", "1M"});
  const char* env = std::getenv("MSD_BENCH_METHODS");
  const std::string methods = env ? env : "gradient,laplacian,laplacian-explicit";
  std::printf("%-20s %10s %12s %14s %14s\n", "method", "vertices", "prepare[s]", "frame med[ms]", "frame min[ms]");
  for (const auto& size : sizes) {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(size);
    const msd::Scene scene = msd::make_scene("bend120", options);
    for (const std::string name : {"gradient", "laplacian", "laplacian-explicit"}) {
      if (("," + methods + ",").find("," + name + ",") == std::string::npos) continue;
      std::unique_ptr<msd::Deformer> d;
      if (name == "gradient")
        d = std::make_unique<msd::GradientEditing>();
      else
        d = std::make_unique<msd::LaplacianEditing>(msd::LaplacianEditingOptions{name == "laplacian"});
      auto t0 = Clock::now();
      d->prepare(scene.P, scene.F, scene.region);
      const double prepare = seconds_since(t0);
      msd::Positions out(scene.P.rows(), 3);
      std::vector<msd::Mat4> T = scene.transforms;
      const msd::Mat4 full = T[0];
      const auto frames = time_frames(20, [&](int f) {
        // an animated bend: blend towards the full transform
        const double a = (f + 1) / 20.0;
        T[0] = (1 - a) * msd::Mat4::Identity() + a * full;
        d->deform(T, out);
      });
      std::printf("%-20s %10ld %12.2f %14.2f %14.2f\n", name.c_str(), long(scene.P.rows()), prepare,
                  frames[frames.size() / 2], frames.front());
      std::fflush(stdout);
    }
  }
  return 0;
}
