// The multi-scale edit (seed 9.3) on the bumpy plane: prepare (low-pass base at a given detail scale of
// 0.3, about what the automatic search picks on this plane — bench_decomposition times the search —,
// shell factorisation and basis, detail encoding) and the full per-frame time (shell basis product,
// fold count, base normals, reconstruction), for the lift and bend120 scenes.
// Usage: bench_multiscale [resolution ...]   (default: 100k 1M)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/scenes.h"
#include "msdeform/reconstruction/multiscale.h"

using namespace msd::bench;


namespace {
// Prepares the deformer on the scene, times 30 frames and prints a row.
void run(msd::Deformer& deformer, const msd::Scene& scene, const char* label) {
  const auto t0 = Clock::now();
  deformer.prepare(scene.P, scene.F, scene.region);
  const double prepare = seconds_since(t0);
  msd::Positions out(scene.P.rows(), 3);
  const auto frames = time_frames(30, [&](int) { deformer.deform(scene.transforms, out); });
  std::printf("%10ld %9s %9s %11.2f %14.2f %14.2f\n", long(scene.P.rows()), scene.name.c_str(), label, prepare,
              frames[frames.size() / 2], frames.front());
  std::fflush(stdout);
}
}  // namespace

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"100k", "1M"});
  std::printf("%10s %9s %9s %11s %14s %14s\n", "vertices", "scene", "encoding", "prepare[s]", "frame med[ms]",
              "frame min[ms]");
  for (const auto& size : sizes)
    for (const char* name : {"lift", "bend120"}) {
      msd::SceneOptions options;
      options.resolution = msd::parse_resolution(size);
      const msd::Scene scene = msd::make_scene(name, options);
      for (const char* encoding : {"normal", "vectors"}) {
        msd::MultiscaleOptions o;
        o.encoding.kind = msd::encoding_kind(encoding);
        o.decomposition.low_pass.detail_scale = 0.3;
        msd::MultiscaleDeformer ms(o);
        run(ms, scene, encoding);
      }
      // The subdivision path: shell on the coarse mesh, stencil to full resolution, local-frame vectors.
      msd::MultiscaleOptions o;
      o.decomposition.kind = msd::DecompositionKind::Subdivision;
      o.decomposition.control = std::make_shared<msd::ControlMesh>(msd::ControlMesh{scene.coarse_P, scene.coarse_F, scene.refinement});
      o.encoding.kind = msd::EncodingKind::Vectors;
      msd::MultiscaleDeformer sub(o);
      run(sub, scene, "subdiv");
    }
  return 0;
}
