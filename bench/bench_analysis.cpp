// Analysis costs on the bumpy plane: an 800x600 ray-traced picture (2x2 supersampling, shadows), CGAL's
// self-intersection test, and the rigidity / detail-distortion metrics of the lift scene's rest pose.
// Usage: bench_analysis [resolution ...]   (default: 100k)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/analysis/metrics.h"
#include "msdeform/analysis/render.h"
#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/scenes.h"

using namespace msd::bench;

namespace {

// Best of `repeats` runs, in milliseconds.
template <class F>
double best_of(int repeats, F&& f) {
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    f();
    best = std::min(best, ms_since(t0));
  }
  return best;
}
}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"100k"});
  std::printf("%10s %12s %14s %14s %12s %12s %14s\n", "vertices", "render[ms]", "render 1spp[ms]",
              "self-int[ms]", "pairs", "rigidity[ms]", "detail dist[ms]");
  for (const auto& size : sizes) {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(size);
    const msd::Scene scene = msd::make_surface(msd::SceneShape::Plane, options);

    msd::RenderOptions render_options;  // 800 x 600, 2 x 2 samples
    const double render = best_of(3, [&] { msd::render(scene.P, scene.F, render_options); });
    render_options.samples_per_axis = 1;
    const double render1 = best_of(3, [&] { msd::render(scene.P, scene.F, render_options); });

    int pairs = 0;
    const double self = best_of(3, [&] { pairs = msd::count_self_intersections(scene.P, scene.F); });

    const double rigidity = best_of(3, [&] { msd::rigidity_error(scene.P, 1.1 * scene.P, scene.F); });
    const double detail =
        best_of(1, [&] { msd::detail_distortion(scene.P, scene.P, scene.F, scene.region); });

    std::printf("%10ld %12.1f %14.1f %14.1f %12d %12.1f %14.1f\n", long(scene.P.rows()), render, render1,
                self, pairs, rigidity, detail);
    std::fflush(stdout);
  }
  return 0;
}
