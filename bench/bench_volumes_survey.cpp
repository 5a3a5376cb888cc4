// Displacement volumes against normal displacements on the edits of the Botsch–Sorkine survey (2008):
// per edit, the base B is an implicit smoothing of S (decomposition/smoothing.h), B' the shell deformation
// of B under the edit's handle transform (pure bending), and both encodings reconstruct S' over the same
// B'. Prints, per encoding: frame time (median of several frames, the edit animated from 0 to 1 and back,
// so the volumes solve is warm-started as in an interactive session), iterations, bounded heights, the
// rigidity error of S' against S (mean and max, analysis/metrics.h) and the number of self-intersecting
// face pairs of S' (CGAL, analysis/self_intersections.h).
// Usage: bench_volumes_survey [--data DIR] [--time-step T] [--smoothing-iterations K] [--fair] [edit ...]
//   DIR defaults to ../shared/data/survey (relative to the working directory), edits to cylinder bar;
//   T in mean edge lengths squared (default 6), K smoothing steps (default 2). An edit that names a
//   built-in scene (core/scenes.h, e.g. bar-bend120; 10k vertices) is generated instead of read.
//   --fair: the base is the thin-plate fairing of the free region (fair_region) instead of a smoothing.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/analysis/metrics.h"
#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/region.h"
#include "msdeform/core/scenes.h"
#include "msdeform/decomposition/fairing.h"
#include "msdeform/decomposition/smoothing.h"
#include "msdeform/deformation/shell.h"
#include "msdeform/detail/displacement_volumes.h"
#include "msdeform/detail/normal_displacements.h"

using namespace msd::bench;

namespace {

// The transforms of the edit scaled to a fraction s of the way from the identity (linear blend of the
// matrices: enough to animate frames that differ).
std::vector<msd::Mat4> partial(const std::vector<msd::Mat4>& transforms, double s) {
  std::vector<msd::Mat4> out;
  for (const auto& T : transforms) out.push_back((1 - s) * msd::Mat4::Identity() + s * T);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  std::string dir = "../shared/data/survey";
  double time_step = 6;
  int smoothing_iterations = 2;
  bool fair = false;
  std::vector<std::string> edits;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--data" && i + 1 < argc)
      dir = argv[++i];
    else if (arg == "--time-step" && i + 1 < argc)
      time_step = std::stod(argv[++i]);
    else if (arg == "--smoothing-iterations" && i + 1 < argc)
      smoothing_iterations = std::stoi(argv[++i]);
    else if (arg == "--fair")
      fair = true;
    else
      edits.push_back(arg);
  }
  if (edits.empty()) edits = {"cylinder", "bar"};
  if (fair)
    std::printf("base: thin-plate fairing of the free region; B' = shell (pure bending)\n");
  else
    std::printf("base: implicit smoothing, %d step(s) of %g mean edge lengths^2; B' = shell (pure bending)\n",
                smoothing_iterations, time_step);
  std::printf("%-9s %6s %-7s | %9s %9s %6s %7s %9s | %10s %10s %6s\n", "edit", "verts", "method", "frame med",
              "frame max", "iters", "bounded", "max err", "rigid mean", "rigid max", "pairs");
  for (const auto& edit : edits) {
    const std::vector<std::string> scenes = msd::scene_names();
    const bool built_in = std::find(scenes.begin(), scenes.end(), edit) != scenes.end();
    msd::Positions S;
    msd::Faces F;
    msd::Region region;
    std::vector<msd::Mat4> transforms;
    if (built_in) {
      const msd::Scene scene = msd::make_scene(edit);
      S = scene.P;
      F = scene.F;
      region = scene.region;
      transforms = scene.transforms;
    } else {
      const msd::Mesh mesh = msd::load_mesh(dir + "/" + edit + ".off");
      S = msd::positions(mesh);
      F = msd::faces(mesh);
      region = msd::read_sel(dir + "/" + edit + ".sel", static_cast<int>(S.rows()));
      transforms = msd::read_def(dir + "/" + edit + ".def");
    }
    msd::SmoothingOptions smoothing;
    smoothing.time_step = time_step;
    smoothing.iterations = smoothing_iterations;
    const msd::Positions B =
        fair ? msd::fair_region(S, F, region) : msd::implicit_smoothing(S, F, smoothing);
    msd::ShellDeformer shell;
    shell.prepare(B, F, region);
    // Frames: the edit at 1/4, 1/2, 3/4, 1, 3/4, ... (the last frame is the full edit).
    std::vector<std::vector<msd::Mat4>> frames;
    for (double s : {0.25, 0.5, 0.75, 1.0, 0.75, 0.5, 0.75, 1.0}) frames.push_back(partial(transforms, s));
    std::vector<msd::Positions> bases(frames.size());
    for (size_t f = 0; f < frames.size(); ++f) shell.deform(frames[f], bases[f]);

    const std::vector<int> anchors = region.constrained_vertices();
    msd::NormalDisplacements normal;
    normal.encode(S, F, B, F);
    msd::DisplacementVolumes volumes;
    volumes.set_anchor_vertices(anchors);
    volumes.encode(S, F, B, F);

    msd::Positions out(S.rows(), 3);
    for (msd::DetailEncoding* encoding : std::vector<msd::DetailEncoding*>{&normal, &volumes}) {
      int iterations = 0, bounded = 0;
      double max_error = 0;
      const std::vector<double> ms = time_frames(static_cast<int>(frames.size()), [&](int f) {
        encoding->reconstruct(bases[f], out);
        if (encoding == &volumes) {
          iterations = std::max(iterations, volumes.report().iterations);
          bounded = volumes.report().bounded_heights;
          max_error = volumes.report().max_relative_error;
        }
      });
      const msd::RigidityError rigidity = msd::rigidity_error(S, out, F);
      const int pairs = msd::count_self_intersections(out, F);
      std::printf("%-9s %6ld %-7s | %9.2f %9.2f %6d %7d %9.2g | %10.4f %10.3f %6d\n", edit.c_str(),
                  static_cast<long>(S.rows()), encoding->name().c_str(), ms[ms.size() / 2], ms.back(),
                  iterations, bounded, max_error, rigidity.stats.mean, rigidity.stats.max, pairs);
      std::fflush(stdout);
    }
  }
  return 0;
}
