// The multi-scale edit (seed 9.3) on the bumpy plane: prepare (fairing, shell factorisation and basis,
// detail encoding) and the full per-frame time (shell basis product, base normals, reconstruction), for
// the lift and bend120 scenes. Usage: bench_multiscale [resolution ...]   (default: 100k 1M)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "core/memory.h"
#include "core/scenes.h"
#include "reconstruction/multiscale.h"
#include "reconstruction/subdivision_multiscale.h"

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
}  // namespace

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  std::vector<std::string> sizes;
  for (int i = 1; i < argc; ++i) sizes.emplace_back(argv[i]);
  if (sizes.empty()) sizes = {"100k", "1M"};
  std::printf("%10s %9s %9s %11s %14s %14s\n", "vertices", "scene", "encoding", "prepare[s]", "frame med[ms]",
              "frame min[ms]");
  for (const auto& size : sizes)
    for (const char* name : {"lift", "bend120"}) {
      msd::SceneOptions options;
      options.resolution = msd::parse_resolution(size);
      const msd::Scene scene = msd::make_scene(name, options);
      const msd::Mesh mesh = msd::make_mesh(scene.P, scene.F);
      for (const char* encoding : {"normal", "vectors"}) {
        msd::MultiscaleOptions o;
        o.encoding = encoding;
        msd::MultiscaleDeformer ms(o);
        auto t0 = Clock::now();
        ms.prepare(mesh, scene.region);
        const double prepare = ms_since(t0) / 1000;
        msd::Positions out(scene.P.rows(), 3);
        std::vector<double> frames;
        for (int f = 0; f < 30; ++f) {
          msd::Mat4 T = scene.transforms[0];
          t0 = Clock::now();
          ms.deform({T}, out);
          frames.push_back(ms_since(t0));
        }
        std::sort(frames.begin(), frames.end());
        std::printf("%10ld %9s %9s %11.2f %14.2f %14.2f\n", long(scene.P.rows()), name, encoding, prepare,
                    frames[frames.size() / 2], frames.front());
        std::fflush(stdout);
      }
      // The subdivision path: shell on the coarse mesh, stencil to full resolution, local-frame vectors.
      msd::SubdivisionMultiscaleDeformer sub(scene.coarse_P, scene.coarse_F, scene.refinement);
      auto t0 = Clock::now();
      sub.prepare(mesh, scene.region);
      const double prepare = ms_since(t0) / 1000;
      msd::Positions out(scene.P.rows(), 3);
      std::vector<double> frames;
      for (int f = 0; f < 30; ++f) {
        t0 = Clock::now();
        sub.deform(scene.transforms, out);
        frames.push_back(ms_since(t0));
      }
      std::sort(frames.begin(), frames.end());
      std::printf("%10ld %9s %9s %11.2f %14.2f %14.2f\n", long(scene.P.rows()), name, "subdiv", prepare,
                  frames[frames.size() / 2], frames.front());
    }
  return 0;
}
