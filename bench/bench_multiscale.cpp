// The multi-scale edit (seed 9.3) on the bumpy plane: prepare (low-pass base at a given detail scale of
// 0.3, about what the automatic search picks on this plane — bench_decomposition times the search —,
// shell factorisation and basis, detail encoding), prepare again with the base reused (again[s]: another
// region on the same mesh, as in the viewer) and the full per-frame time (shell basis product,
// fold count, base normals, reconstruction), for the lift and bend120 scenes. --breakdown times only the
// stages of the lift frame, one by one.
// Usage: bench_multiscale [--breakdown] [resolution ...]   (default: 100k 1M)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/region.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/shell.h"
#include "msdeform/detail/encodings.h"
#include "msdeform/detail/fold_check.h"
#include "msdeform/reconstruction/decompose.h"
#include "msdeform/reconstruction/multiscale.h"

using namespace msd::bench;


namespace {
// Prepares the deformer on the scene, times 30 frames, prepares it again (with a LowPassCache in its
// options, the base is reused: what the viewer does when a region is painted) and prints a row.
void run(msd::Deformer& deformer, const msd::Scene& scene, const char* label) {
  auto t0 = Clock::now();
  deformer.prepare(scene.P, scene.F, scene.region);
  const double prepare = seconds_since(t0);
  msd::Positions out(scene.P.rows(), 3);
  const auto frames = time_frames(30, [&](int) { deformer.deform(scene.transforms, out); });
  t0 = Clock::now();
  deformer.prepare(scene.P, scene.F, scene.region);
  const double again = seconds_since(t0);
  std::printf("%10ld %9s %9s %11.2f %13.2f %14.2f %14.2f\n", long(scene.P.rows()), scene.name.c_str(), label, prepare,
              again, frames[frames.size() / 2], frames.front());
  std::fflush(stdout);
}

// A multi-scale frame's stages one by one (what MultiscaleDeformer::deform runs, on the same
// decomposition): the shell's basis product B', the encoding's reconstruction S' = B' ⊕ D (base normals or
// frames, then interpolation) of the vertices the edit does not place, the placement of the fixed and
// handle vertices and the fold count (the frame checks S' finite inside those passes). Medians of 30
// frames, each stage in its own loop: its data stay in the caches, so the stages add up to less than a
// whole frame (bench_summary), where they evict each other's.
void breakdown(const msd::Scene& scene) {
  msd::DecompositionOptions options;
  options.low_pass.detail_scale = 0.3;
  const msd::Decomposition d = msd::decompose(scene.P, scene.F, scene.region, options);
  msd::ShellDeformer shell;
  shell.prepare(d.edit, d.edit_faces, d.edit_region);
  msd::FoldCheck folds;
  folds.prepare(scene.P, scene.F, d.base, d.base_faces);
  msd::FoldCheck every = folds;                       // counts every triangle (no set_placements)
  folds.set_placements(scene.region, d.edit_region);  // as MultiscaleDeformer does
  msd::Positions B(d.base.rows(), 3), S(scene.P.rows(), 3);
  auto median = [](std::vector<double> ms) { return ms[ms.size() / 2]; };
  const double t_shell = median(time_frames(30, [&](int) { shell.deform(scene.transforms, B); }));
  for (const char* name : {"normal", "vectors"}) {
    msd::EncodingOptions eo;
    eo.kind = msd::encoding_kind(name);
    const auto encoding = msd::make_encoding(eo);
    encoding->set_placed_vertices(scene.region.constrained_vertices());  // as MultiscaleDeformer does
    encoding->encode(scene.P, scene.F, d.base, d.base_faces);
    const double t_encoding = median(time_frames(30, [&](int) { encoding->reconstruct(B, S); }));
    // The fixed and handle vertices, placed where the edit puts them.
    const std::vector<int>& placed = scene.region.constrained_vertices();
    const double t_place = median(time_frames(30, [&](int) {
      msd::parallel_for_chunks(static_cast<long>(placed.size()), [&](long begin, long end) {
        for (long i = begin; i < end; ++i) {
          const int v = placed[i], k = scene.region.handle_of(v);
          const msd::Vec3 p = scene.P.row(v);
          S.row(v) = k < 0 ? p : msd::transform_point(scene.transforms[k], p);
        }
      });
    }));
    int folded = 0, folded_every = 0;
    const double t_folds =
        median(time_frames(30, [&](int) { folded = folds.count(S, B, scene.transforms); }));
    const double t_every = median(time_frames(30, [&](int) { folded_every = every.count(S, B); }));
    if (folded != folded_every)
      std::printf("fold counts differ: %d skipping, %d every triangle\n", folded, folded_every);
    std::printf(
        "%10ld %9s %9s breakdown [ms]: shell %.2f, reconstruction %.2f, placement %.2f, fold count %.2f "
        "(%d folded; fold count of every triangle %.2f, %ld of %ld skipped)\n",
        long(scene.P.rows()), scene.name.c_str(), name, t_shell, t_encoding, t_place, t_folds, folded,
        t_every, folds.skipped(scene.transforms), long(scene.F.rows()));
    std::fflush(stdout);
  }
}
}  // namespace

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  // --breakdown: only the stages of the lift frame.
  const bool only_breakdown = argc > 1 && std::string(argv[1]) == "--breakdown";
  if (only_breakdown) --argc, ++argv;
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"100k", "1M"});
  if (!only_breakdown)
    std::printf("%10s %9s %9s %11s %13s %14s %14s\n", "vertices", "scene", "encoding", "prepare[s]", "again[s]",
                "frame med[ms]", "frame min[ms]");
  for (const auto& size : sizes)
    for (const char* name : {"lift", "bend120"}) {
      if (only_breakdown && std::string(name) != "lift") continue;
      msd::SceneOptions options;
      options.resolution = msd::parse_resolution(size);
      const msd::Scene scene = msd::make_scene(name, options);
      if (only_breakdown) {
        breakdown(scene);
        continue;
      }
      for (const char* encoding : {"normal", "vectors"}) {
        msd::MultiscaleOptions o;
        o.encoding.kind = msd::encoding_kind(encoding);
        o.decomposition.low_pass.detail_scale = 0.3;
        o.decomposition.low_pass_cache = std::make_shared<msd::LowPassCache>();
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
      if (std::string(name) == "lift") breakdown(scene);
    }
  return 0;
}
